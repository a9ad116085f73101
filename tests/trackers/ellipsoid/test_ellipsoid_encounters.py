"""Heights measured afresh after an encounter, also without the depth fusion
(``depth.remeasure_after_encounter`` with ``depth.fuse`` off)."""

import numpy as np
import pytest
from _line_of_sight import line_of_sight_frame, misplaced

from worldtrack.trackers.ellipsoid.config import DepthConfig, FeetConfig, HeightConfig
from worldtrack.trackers.ellipsoid.depth import DepthFusion
from worldtrack.trackers.ellipsoid.encounters import covered_in_some_view


@pytest.fixture(scope="module")
def seen():
    return line_of_sight_frame()


def _pair(tracker, truth, behind_m, aside_m=0.0):
    """The person at the truth, and another ``behind_m`` farther along the line of sight and
    ``aside_m`` across it (same height)."""
    p, xy = misplaced(tracker, truth, 0.0)
    cam = tracker.scene.cameras["cam"]
    ray = (xy - cam.centre[:2]) / np.hypot(*(xy - cam.centre[:2]))
    at = xy + behind_m * ray + aside_m * np.array([-ray[1], ray[0]])
    q = tracker.position_map.add(float(at[0]), float(at[1]), truth["height"], 0.45, mode="tracking", time=0.0)
    return p, q


def test_covered_only_with_somebody_on_the_same_line_of_sight(seen):
    tracker, *_, truth = seen
    p, q = _pair(tracker, truth, 1.0)
    # One metre behind on the same line of sight: the one behind is covered (the one in front
    # covers much of its region), the one in front is not; half a metre behind, both are.
    assert covered_in_some_view([p, q], tracker.views, 2.1) == [False, True]
    p, q = _pair(tracker, truth, 0.5)
    assert covered_in_some_view([p, q], tracker.views, 2.1) == [True, True]
    p, q = _pair(tracker, truth, 0.0, aside_m=2.0)
    assert covered_in_some_view([p, q], tracker.views, 2.1) == [False, False]
    p, q = _pair(tracker, truth, 1.0)
    q.mode = "capture"     # a candidate is never "covered" (it has no height to lose)
    assert covered_in_some_view([p, q], tracker.views, 2.1) == [False, False]
    assert covered_in_some_view([], tracker.views, 2.1) == []


@pytest.mark.parametrize("remeasure", [True, False])
def test_samples_dropped_once_clear_again_without_the_fusion(seen, remeasure):
    tracker, labels, *_, truth = seen
    fusion = DepthFusion(DepthConfig(fuse=False, remeasure_after_encounter=remeasure), FeetConfig(), HeightConfig())
    p, q = _pair(tracker, truth, 1.0)
    assert covered_in_some_view([p, q], tracker.views, 2.1) == [False, True]
    for r in (p, q):
        r.height_samples.extend([1.7, 1.71, 1.69])
        r.height_tries = 12
    # Crossing: q covered; nothing is dropped yet, and nobody moves (no fusion).
    assert fusion.apply([p, q], tracker.views, {"cam": labels}, tracker.walkable, 0.1) == 0
    assert len(p.height_samples) == 3 and len(q.height_samples) == 3
    # Apart again: the one who was covered has their samples dropped (with the option), once; the
    # one in front was never covered and keeps theirs.
    away = np.array([q.x, q.y]) + 2.5 * np.array([-1.0, 0.0])
    q.x, q.y = float(away[0]), float(away[1])
    fusion.apply([p, q], tracker.views, {"cam": labels}, tracker.walkable, 0.1)
    assert len(p.height_samples) == 3
    assert len(q.height_samples) == (0 if remeasure else 3)
    assert (q.height_tries == 0) == remeasure
    q.height_samples.append(1.7)
    fusion.apply([p, q], tracker.views, {"cam": labels}, tracker.walkable, 0.1)
    assert len(q.height_samples) == (1 if remeasure else 4)
