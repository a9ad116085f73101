"""The crowd gate on height measurement (:mod:`worldtrack.trackers.ellipsoid.height_gate`)."""

import numpy as np
from _ellipsoid_seen import one_person_seen

from worldtrack.foreground import make_foregrounds
from worldtrack.trackers.ellipsoid import EllipsoidConfig, EllipsoidTracker
from worldtrack.trackers.ellipsoid.height_gate import crowd_shares, heights_due_clear


def _crowded(tracker, person):
    """The tracker's labels with foreground painted over everything within 60 px of the person's
    feet in each camera, except the person's own silhouette: people all round them."""
    labels = {}
    for cid, view in tracker.views.items():
        lab = tracker.last_labels[cid].copy()
        foot = view.camera.project(np.array([[*person, 0.0]]))[0]
        u, v = int(round(foot[0])), int(round(foot[1]))
        lab[max(v - 120, 0):v + 10, max(u - 60, 0):u + 60] = 1
        labels[cid] = lab
    return labels


def test_a_person_alone_has_floor_beside_them_and_one_in_a_crowd_has_people():
    scene, person, bgs, tracker, images, real = one_person_seen(seed=3)
    p = tracker.position_map.add(person[0], person[1], 1.65, 0.4, mode="tracking")
    crowded = _crowded(tracker, person)
    for cid, view in tracker.views.items():
        alone = crowd_shares([p], view, tracker.last_labels[cid])[0]
        among = crowd_shares([p], view, crowded[cid])[0]
        assert alone < 0.1 and among > 0.6


def test_heights_are_not_measured_where_every_view_shows_a_crowd_only_when_asked():
    scene, person, bgs, tracker, images, real = one_person_seen(seed=3)
    p = tracker.position_map.add(person[0], person[1], 1.65, 0.4, mode="tracking")
    gated = EllipsoidConfig(crowd={"height_max_beside": 0.3})
    crowded = _crowded(tracker, person)
    assert heights_due_clear([p], [p], gated, 0, tracker.views, tracker.last_labels) == [0]   # alone: measured
    assert heights_due_clear([p], [p], gated, 0, tracker.views, crowded) == []
    assert heights_due_clear([p], [p], EllipsoidConfig(), 0, tracker.views, crowded) == [0]   # off by default
    one = dict(crowded, **{c: tracker.last_labels[c] for c in list(crowded)[:1]})              # one view clear
    assert heights_due_clear([p], [p], gated, 0, tracker.views, one) == [0]


def test_births_read_heights_unless_the_crowd_setting_says_not_to():
    scene, person, bgs, tracker, images, real = one_person_seen(seed=3)
    assert tracker.births.height_range == tuple(EllipsoidConfig().height.range_m)
    crowd = EllipsoidTracker(scene, make_foregrounds(scene, bgs, "colour"),
                             EllipsoidConfig(crowd={"births_heights": False}))
    assert crowd.births.height_range is None
    assert crowd.config.height.measure                                    # the tracker still measures them
