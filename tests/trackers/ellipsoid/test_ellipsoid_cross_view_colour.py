"""The colour test of a cross-view move: the other camera must show *this* person there
(:mod:`worldtrack.trackers.ellipsoid.cross_view_colour`)."""

import numpy as np
from _ellipsoid_scenes import ellipsoid_frames, noise_backgrounds
from test_ellipsoid_cross_view import PERSON, narrow_two_cameras

from worldtrack.foreground import make_foregrounds
from worldtrack.geometry import quadric as q
from worldtrack.trackers.base import Person
from worldtrack.trackers.ellipsoid import EllipsoidConfig, EllipsoidTracker
from worldtrack.trackers.ellipsoid.cameras import ray_direction
from worldtrack.trackers.ellipsoid.colours import HIST_BINS, Colours
from worldtrack.trackers.ellipsoid.cross_view_colour import ColourCheck, _Figure, colours_at
from worldtrack.trackers.ellipsoid.real import ternary_real

FAR = np.array([-3.0, -1.0])


def _read_one_frame(cfg=None, seed=4):
    """A tracker that has read one frame of the (green) person, and the scene."""
    scene = narrow_two_cameras()
    rng = np.random.default_rng(seed)
    bgs = noise_backgrounds(scene, rng)
    cen, rad = q.person_ellipsoid([PERSON], 1.65, 0.4)
    tracker = EllipsoidTracker(scene, make_foregrounds(scene, bgs, "colour"), cfg or EllipsoidConfig())
    tracker._read(ellipsoid_frames(scene, bgs, cen, rad, rng, 0))
    return scene, tracker


def _true_colours(tracker, cid):
    """The person's colours in ``cid`` measured where they stand."""
    figure = [_Figure(0, *PERSON, 1.65, 0.4)]
    return colours_at(tracker.views[cid], tracker.last_images[cid], tracker.last_labels[cid], figure, 0, PERSON, 10)


def _check(tracker, models, people, veto_only=False):
    return ColourCheck(people, models, tracker.views, tracker.last_images, tracker.last_labels, 10, 0.6, veto_only)


def test_a_move_is_allowed_only_onto_the_person_s_own_colours():
    scene, tracker = _read_one_frame()
    green = _true_colours(tracker, "c2")
    assert green is not None
    red_hist = np.zeros(HIST_BINS, np.float32)
    red_hist[0, 3, 3] = 1
    red = Colours([red_hist, red_hist])
    off = PERSON + 1.2 * ray_direction(scene.camera("c1"), PERSON)
    people = [Person(1, *off, mode="tracking"), Person(2, *FAR, mode="tracking")]
    real = {cid: ternary_real(labels, tracker.views[cid].ring_px) for cid, labels in tracker.last_labels.items()}
    joint = tracker.joint_image(real, people)
    assert _check(tracker, {people[0]: {"c2": green}}, people)(joint, 0, ["c2"], PERSON)
    # Colours that are not theirs, no model at all, or somebody else's model as near: no move.
    assert not _check(tracker, {people[0]: {"c2": red}}, people)(joint, 0, ["c2"], PERSON)
    assert not _check(tracker, {}, people)(joint, 0, ["c2"], PERSON)
    assert not _check(tracker, {people[0]: {"c2": green}, people[1]: {"c2": green}}, people)(joint, 0, ["c2"], PERSON)
    # A model learnt in another camera stands in for the one the unseeing camera lacks.
    assert _check(tracker, {people[0]: {"c1": _true_colours(tracker, "c1")}}, people)(joint, 0, ["c2"], PERSON)
    # Where the unseeing camera shows nobody's pixels, no colours: no move.
    assert not _check(tracker, {people[0]: {"c2": green}}, people)(joint, 0, ["c2"], FAR)
    # veto_only: what cannot be measured does not refuse; colours that are somebody else's still do.
    assert _check(tracker, {}, people, veto_only=True)(joint, 0, ["c2"], PERSON)
    assert _check(tracker, {people[0]: {"c2": green}}, people, veto_only=True)(joint, 0, ["c2"], FAR)
    assert not _check(tracker, {people[0]: {"c2": red}}, people, veto_only=True)(joint, 0, ["c2"], PERSON)
    assert not _check(tracker, {people[0]: {"c2": green}, people[1]: {"c2": green}}, people,
                      veto_only=True)(joint, 0, ["c2"], PERSON)


def test_the_tracker_moves_a_track_only_with_a_colour_model_that_fits():
    # The hand-placed track 2.8 m too far along c1's ray (as in test_ellipsoid_cross_view): with
    # the colour test on, it moves only when its model is the person's colours.
    scene = narrow_two_cameras()
    off = PERSON + 2.8 * ray_direction(scene.camera("c1"), PERSON)
    cen, rad = q.person_ellipsoid([PERSON], 1.65, 0.4)
    errors = {}
    for with_model in (False, True):
        cfg = EllipsoidConfig(cross_view={"search_m": 3.0, "colour_distance": 0.6}, births={"where": "none"},
                              warm_start={"frames": 0})
        _, reader = _read_one_frame(cfg, seed=8)
        rng = np.random.default_rng(8)
        bgs = noise_backgrounds(scene, rng)
        tracker = EllipsoidTracker(scene, make_foregrounds(scene, bgs, "colour"), cfg)
        tracker.init_track(*off, track_id=1)
        if with_model:
            tracker.identity.models[tracker.position_map.get(1)] = {"c2": _true_colours(reader, "c2")}
        (track,) = tracker.step(ellipsoid_frames(scene, bgs, cen, rad, rng, 0), 0.0)
        errors[with_model] = np.hypot(track.x - PERSON[0], track.y - PERSON[1])
    assert errors[True] < 0.15, errors
    assert errors[False] > 1.0, errors
