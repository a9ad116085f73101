"""Depth from the feet (and the head's top where the feet are not to be trusted) along the line of sight."""

import numpy as np
import pytest

from worldtrack.experiment import synthetic_tracker
from worldtrack.synth import make_scenario
from worldtrack.trackers.ellipsoid.config import FeetConfig, HeightConfig
from worldtrack.trackers.ellipsoid.feet import anchor_to_feet, feet_weight


@pytest.fixture(scope="module")
def seen():
    """One rendered frame of the line-of-sight room (320x240, one camera 2.5-3 m high, people
    5-10 m away): the tracker, its foreground labels, and the truth of the person seen best."""
    sc = make_scenario("line-of-sight", size=(320, 240), frames=1, seed=7, floor_clothes=0)
    bundle = next(iter(sc.frames()))
    tracker = synthetic_tracker(sc, "ellipsoid")
    view = bundle.views["cam"]
    labels = tracker.views["cam"].foreground.labels(view.image)
    whole = [g for g in bundle.gt if g["head_cam"] and g["feet_cam"]]
    best = max(whole, key=lambda g: np.count_nonzero(view.instance == g["id"]))
    return tracker, labels, view.instance, best


def _misplaced(tracker, truth, along_m):
    """A tracked person ``along_m`` metres beyond the truth along the camera's line of sight, with
    the true height."""
    cam = tracker.scene.cameras["cam"]
    xy = np.array([truth["x"], truth["y"]])
    ray = (xy - cam.centre[:2]) / np.hypot(*(xy - cam.centre[:2]))
    start = xy + along_m * ray
    return tracker.fresh().position_map.add(float(start[0]), float(start[1]), truth["height"], 0.45,
                                            mode="tracking", time=0.0), xy


def test_the_feet_pull_a_track_that_sits_too_far_along_the_line_of_sight_back_to_the_person(seen):
    tracker, labels, instance, truth = seen
    p, xy = _misplaced(tracker, truth, 0.6)
    moved = anchor_to_feet([p], tracker.views, {"cam": labels}, tracker.walkable, FeetConfig(anchor=True), HeightConfig())
    assert moved == 1
    # 0.6 m off before; the feet are 0.1 m uncertain, the ellipse 0.3 m: 90 % of the way back.
    assert np.hypot(p.x - xy[0], p.y - xy[1]) < 0.2
    q, _ = _misplaced(tracker, truth, 0.6)
    assert anchor_to_feet([q], tracker.views, {"cam": labels}, tracker.walkable, FeetConfig(anchor=False),
                          HeightConfig()) == 0
    r, _ = _misplaced(tracker, truth, 0.0)   # in the right place: stays there
    anchor_to_feet([r], tracker.views, {"cam": labels}, tracker.walkable, FeetConfig(anchor=True), HeightConfig())
    assert np.hypot(r.x - xy[0], r.y - xy[1]) < 0.15


def test_without_legs_in_the_foreground_the_head_places_the_person_not_the_waist(seen):
    tracker, labels, instance, truth = seen
    # Legs the floor's colour: the body's pixels below its middle read as shadow-like ("unsure", 2).
    body = instance == truth["id"]
    rows = np.nonzero(body.any(axis=1))[0]
    legs = body & (np.arange(labels.shape[0])[:, None] > (rows.min() + rows.max()) / 2)
    cut = labels.copy()
    cut[legs & (cut == 1)] = 2
    p, xy = _misplaced(tracker, truth, 0.6)
    moved = anchor_to_feet([p], tracker.views, {"cam": cut}, tracker.walkable, FeetConfig(anchor=True), HeightConfig())
    assert moved == 1
    # The head at an unmeasured height (σ 0.1 m, ~0.6 m along the ray at this distance) is weak
    # evidence: a small step back (the waist, taken for the feet, would have pulled it farther).
    assert 0.3 < np.hypot(p.x - xy[0], p.y - xy[1]) < 0.57
    # Once the height is measured (σ 0.03 m) the head pins the depth nearly as well as the feet.
    q, _ = _misplaced(tracker, truth, 0.6)
    q.height_samples.extend([truth["height"]] * 3)
    anchor_to_feet([q], tracker.views, {"cam": cut}, tracker.walkable, FeetConfig(anchor=True), HeightConfig())
    assert np.hypot(q.x - xy[0], q.y - xy[1]) < 0.3
    assert feet_weight(0.3, 0.1) > 0.85
