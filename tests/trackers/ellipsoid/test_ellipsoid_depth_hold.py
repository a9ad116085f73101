"""A person others cover is held along the line of sight by their clear head (``depth.head_when_covered``)
and a person's step along it is bounded by walking speed (``depth.max_along_speed_mps``)."""

import numpy as np
import pytest
from _line_of_sight import line_of_sight_frame

from worldtrack.trackers.ellipsoid import depth_hold
from worldtrack.trackers.ellipsoid.config import DepthConfig, FeetConfig, HeightConfig
from worldtrack.trackers.ellipsoid.depth import DepthFusion
from worldtrack.trackers.ellipsoid.depth_hold import hold_covered_by_head
from worldtrack.trackers.ellipsoid.depth_step import bound_steps


@pytest.fixture(scope="module")
def seen():
    return line_of_sight_frame()


def _covered(seen, along_m: float, cover: bool, samples: int = 3):
    """The seen person tracked ``along_m`` m beyond the truth along the ray with ``samples`` height
    samples, and (``cover``) a 1.5 m, 0.7 m wide person standing 0.85 of the way out on the same ray, whose
    ellipse covers the far one's legs but not their head; both on one map. Returns (far, people,
    the truth's floor point, the ray's floor direction)."""
    tracker, _, _, truth = seen
    cam = tracker.scene.cameras["cam"]
    xy = np.array([truth["x"], truth["y"]])
    ray = (xy - cam.centre[:2]) / np.hypot(*(xy - cam.centre[:2]))
    start = xy + along_m * ray
    pm = tracker.fresh().position_map
    far = pm.add(float(start[0]), float(start[1]), truth["height"], 0.45, mode="tracking", time=0.0)
    far.height_samples.extend([truth["height"]] * samples)
    people = [far]
    if cover:
        near = cam.centre[:2] + 0.85 * (xy - cam.centre[:2])
        people.append(pm.add(float(near[0]), float(near[1]), 1.5, 0.7, mode="tracking", time=0.0))
    return far, people, xy, ray


def _hold(tracker, labels, people):
    return hold_covered_by_head(people, tracker.views, {"cam": labels}, tracker.walkable, FeetConfig(),
                                HeightConfig())


def test_a_covered_person_moves_towards_the_point_under_their_clear_head(seen):
    tracker, labels, _, _ = seen
    far, people, xy, ray = _covered(seen, 0.35, cover=True)   # the head's σ here: 0.22 m
    assert _hold(tracker, labels, people) == 1
    after = float((np.array([far.x, far.y]) - xy) @ ray)
    assert 0.0 <= after < 0.2                   # from 0.35 m too far to within 0.2 m of the truth


def test_a_head_farther_than_its_own_sigma_allows_moves_nobody(seen):
    tracker, labels, _, _ = seen
    _, people, _, _ = _covered(seen, 0.8, cover=True)        # 0.8 m: beyond 2 σ (0.44 m)
    assert _hold(tracker, labels, people) == 0


def test_nothing_moves_uncovered_unmeasured_or_with_the_head_not_clear(seen, monkeypatch):
    tracker, labels, _, _ = seen
    _, alone, _, _ = _covered(seen, 0.35, cover=False)
    assert _hold(tracker, labels, alone) == 0          # not covered: the feet anchor's case
    _, unmeasured, _, _ = _covered(seen, 0.35, cover=True, samples=2)
    assert _hold(tracker, labels, unmeasured) == 0     # a height not measured places nobody
    monkeypatch.setattr(depth_hold, "head_is_clear", lambda *a: False)
    _, people, _, _ = _covered(seen, 0.35, cover=True)
    assert _hold(tracker, labels, people) == 0


def test_the_fusion_holds_covered_people_only_with_head_when_covered(seen):
    tracker, labels, _, _ = seen
    for on, expected in ((True, 1), (False, 0)):
        _, people, _, _ = _covered(seen, 0.35, cover=True)
        fusion = DepthFusion(DepthConfig(head_when_covered=on), FeetConfig(), HeightConfig())
        assert fusion.apply(people, tracker.views, {"cam": labels}, tracker.walkable, 0.1) == expected


def test_a_step_along_the_ray_is_bounded_from_the_last_place_not_across_it(seen):
    tracker, labels, _, _ = seen
    far, people, xy, ray = _covered(seen, 1.0, cover=False)
    last = xy.copy()                                            # where the person was a frame ago
    centre = tracker.scene.cameras["cam"].centre
    place = xy + 1.0 * ray + 0.3 * np.array([-ray[1], ray[0]])  # this frame's place: 1 m on, 0.3 m across
    r = (place - centre[:2]) / np.hypot(*(place - centre[:2]))  # the line of sight through it
    far.x, far.y = (float(v) for v in place)
    assert bound_steps(people, {far: last}, lambda k: centre, 2.0, 0.1, tracker.walkable) == 1
    off = np.array([far.x, far.y]) - last
    assert off @ r == pytest.approx(0.2, abs=1e-6)             # 2 m/s for 0.1 s along the ray
    assert off @ np.array([-r[1], r[0]]) == pytest.approx((place - last) @ np.array([-r[1], r[0]]), abs=1e-6)
    assert bound_steps(people, {far: last}, lambda k: None, 2.0, 0.1, tracker.walkable) == 0   # several views


def test_the_fusion_bounds_the_step_from_the_place_before_the_prediction(seen):
    tracker, labels, _, _ = seen
    far, people, xy, ray = _covered(seen, 0.0, cover=False)
    far.vx, far.vy = (float(v) for v in 1.0 * ray)              # walking away at 1 m/s: predicted 0.1 m on
    far.x, far.y = (float(v) for v in xy + 0.1 * ray)
    fusion = DepthFusion(DepthConfig(max_along_speed_mps=1.5), FeetConfig(), HeightConfig())
    fusion.remember_prediction([far])
    far.x, far.y = (float(v) for v in xy + 0.6 * ray)           # the match slid it 0.5 m on
    fusion.apply([far], tracker.views, {"cam": labels}, tracker.walkable, 0.1)
    assert float((np.array([far.x, far.y]) - xy) @ ray) == pytest.approx(0.15, abs=0.02)
