"""Searches along lines of sight: the birth search places newcomers, the rescue brings tracks back."""

import numpy as np
import pytest
from _ellipsoid_seen import one_person_seen

from worldtrack.trackers.base import Person
from worldtrack.trackers.ellipsoid.cameras import ray_direction
from worldtrack.trackers.ellipsoid.search import RescueArgs, RescueSchedule, birth_search, rescue, rescue_people


def test_rescue_brings_a_track_off_along_a_line_of_sight_back_and_leaves_a_right_one():
    # A track 0.9 m off along one camera's line of sight is searched back along the seeing
    # cameras' lines to the person; a track on the person stays (no candidate beats its own place
    # scored on the same pixels by ``rescue.gain``).
    scene, person, _, tracker, _, real = one_person_seen(seed=5)
    args = RescueArgs(1.5, 0.08, 0.4)

    def search(at):
        joint = tracker.joint_image(real, [Person(1, *at)])
        return rescue(joint, 0, args), joint.xy[0]

    found, xy = search(person)
    assert found is None and np.array_equal(xy, person)
    for cid in real:
        off = person + 0.9 * ray_direction(scene.camera(cid), person)
        found, xy = search(off)
        assert found is not None, cid
        assert np.hypot(*(xy - person)) < 0.03, (cid, xy)
        e, den = found
        assert 0.7 < e <= 1.0 and den > 0
    # Never onto somebody else: with a person standing at the right place, the off track is not
    # moved within ``min_separation_m`` of them (without the rule it is, as above).
    other = person + [0.05, 0.0]
    joint = tracker.joint_image(real, [Person(1, *off), Person(2, *other)])
    rescue(joint, 0, args)
    assert np.hypot(*(joint.xy[0] - other)) >= 0.4


def test_a_failing_track_waits_before_searching_again():
    scene, person, _, tracker, _, real = one_person_seen(seed=5)
    stuck = Person(1, -3.0, 4.5, mode="tracking")             # off in a corner: nothing better nearby
    stuck.tick("low", 0.0)
    when = RescueSchedule(frame=1, every=0, retry_s=0.3, half_frame=0.05)
    e, den = np.zeros(1), np.zeros(1)
    rescue_people(tracker.joint_image(real, [stuck]), [stuck], e, den, RescueArgs(1.5, 0.08, 0.4), when, 1.0)
    assert stuck.rescue_after == pytest.approx(1.3)            # nothing found: next search not before 1.3 s
    searched = []
    for t in (1.1, 1.2, 1.3):
        after = stuck.rescue_after
        rescue_people(tracker.joint_image(real, [stuck]), [stuck], e, den, RescueArgs(1.5, 0.08, 0.4), when, t)
        searched.append(stuck.rescue_after != after)
    assert searched == [False, False, True] and stuck.rescue_after == pytest.approx(1.6)


def test_new_person_is_placed_along_the_line_of_sight_of_the_camera_that_proposed_them():
    # A blob's foot point is uncertain along the ray of the camera whose blob it is: the birth
    # search runs along that ray (and the ray of the camera that sees the guess largest). Along the
    # largest camera's ray alone, a guess off along the other camera's ray stays 0.15 m off.
    scene, person, _, tracker, _, real = one_person_seen(seed=3)
    errors = {}
    for proposer in ("c1", "c2"):
        guess = person + 0.9 * ray_direction(scene.camera(proposer), person)
        for seen_by in (proposer, None):
            joint = tracker.joint_image(real, [Person(-1, *guess)])
            birth_search(joint, 0, tracker.config.births.search_m, tracker.views.get(seen_by))
            tracker.rounds(joint, np.array([False]), tracker.steps)     # then slide in, capture mode
            errors[proposer, seen_by] = np.hypot(*(joint.xy[0] - person))
    assert errors["c1", "c1"] < 0.03 and errors["c2", "c2"] < 0.03, errors
    assert max(errors["c1", None], errors["c2", None]) > 0.1, errors   # the proposer's ray is what finds it
