"""When the feet anchor must not fire: another person on the line of sight at the feet
(``feet.ray_band_share``), a height read above the feet that is off by more than its scatter (``feet.height_sigmas``)."""

import numpy as np
import pytest
from _line_of_sight import line_of_sight_frame, misplaced

from worldtrack.trackers.ellipsoid.anchor_gates import height_gate_m, ray_shared
from worldtrack.trackers.ellipsoid.config import AnchorHeightConfig, FeetConfig, HeightConfig
from worldtrack.trackers.ellipsoid.feet import anchor_to_feet


@pytest.fixture(scope="module")
def seen():
    return line_of_sight_frame()


def _near_on_ray(tracker, truth, along_m: float, across_m: float) -> np.ndarray:
    """The floor point (2,) ``along_m`` m beyond the truth along the camera's line of sight (negative:
    nearer) and ``across_m`` m across it (on the side where this frame's lowest foot is)."""
    cam = tracker.scene.cameras["cam"]
    xy = np.array([truth["x"], truth["y"]])
    ray = (xy - cam.centre[:2]) / np.hypot(*(xy - cam.centre[:2]))
    return xy + along_m * ray + across_m * np.array([-ray[1], ray[0]])


def _anchor_beside(tracker, labels, truth, band_share: float, along_m: float, across_m: float) -> tuple[int, float]:
    """Anchor a person put 0.6 m beyond the truth (feet only, no head fallback) with another track near
    the truth's line of sight (:func:`_near_on_ray`; not moved: their ellipse is all the test reads);
    (1 when the person moved else 0, their distance from the truth, m)."""
    p, xy = misplaced(tracker, truth, 0.6)
    near = _near_on_ray(tracker, truth, along_m, across_m)
    q = tracker.position_map.add(float(near[0]), float(near[1]), truth["height"], 0.45, mode="lost", time=0.0)
    before = (p.x, p.y)
    config = FeetConfig(anchor=True, head_fallback=False, ray_band_share=band_share)
    anchor_to_feet([p, q], tracker.views, {"cam": labels}, tracker.walkable, config, HeightConfig())
    return int((p.x, p.y) != before), float(np.hypot(p.x - xy[0], p.y - xy[1]))


@pytest.mark.parametrize("along_m, across_m, band_share", [(-1.0, -0.3, 0.05), (1.0, -0.3, 0.3)])
def test_another_track_in_front_or_just_behind_on_the_feet_stops_the_anchor_only_with_the_band(
        seen, along_m, across_m, band_share):
    tracker, labels, _, truth = seen
    # Off (0) the anchor takes the feet: the window round them and the covered share miss the other track.
    moved, off = _anchor_beside(tracker, labels, truth, 0.0, along_m, across_m)
    assert moved == 1 and off < 0.25
    moved, off = _anchor_beside(tracker, labels, truth, band_share, along_m, across_m)
    assert moved == 0 and off == pytest.approx(0.6, abs=1e-9)


def test_a_track_farther_behind_than_the_band_leaves_the_anchor_alone(seen):
    tracker, labels, _, truth = seen
    assert _anchor_beside(tracker, labels, truth, 0.2, 1.0, -0.3)[0] == 1    # 1 m behind: above a 0.2 band
    assert _anchor_beside(tracker, labels, truth, 0.3, 2.0, -0.2)[0] == 1    # 2 m behind: above a 0.3 band


def test_the_band_tests_the_feet_columns_and_the_rows_above_them():
    boxes = np.array([[90, 110, 20, 100], [95, 105, 10, 80], [200, 220, 20, 100], [80, 120, 30, 140]])
    valid = np.array([True, True, True, False])
    feet = np.array([100.0, 99.0])
    assert not ray_shared(boxes, valid, 0, feet, 0.0)
    assert not ray_shared(boxes, valid, 0, feet, 0.2)            # box 1 ends 20 rows above the feet, the band is 16
    assert ray_shared(boxes, valid, 0, feet, 0.3)                # 24 rows: it reaches box 1
    assert not ray_shared(boxes[[0, 2]], valid[[0, 2]], 0, feet, 0.9)   # beside, not on the ray
    assert ray_shared(boxes[[0, 3]], np.ones(2, bool), 0, feet, 0.05)  # in front: covers the feet
    assert not ray_shared(boxes[[0, 3]], np.array([True, False]), 0, feet, 0.05)
    assert ray_shared(boxes, valid, 0, np.array([np.nan, 99.0]), 0.1)


def test_a_measured_height_gates_the_feet_by_its_scatter(seen):
    tracker, labels, _, truth = seen
    # The track's height 0.1 m over what the silhouette shows above the feet: within the fixed 0.3 m.
    for sigmas, moves in ((0.0, 1), (3.0, 0)):
        p, _ = misplaced(tracker, truth, 0.6)
        p.height = truth["height"] + 0.1
        p.height_samples.extend([p.height] * 5)
        config = FeetConfig(anchor=True, head_fallback=False, height_sigmas=sigmas)
        assert anchor_to_feet([p], tracker.views, {"cam": labels}, tracker.walkable, config, HeightConfig()) == moves
    # Not yet measured: the fixed match alone.
    p, _ = misplaced(tracker, truth, 0.6)
    p.height = truth["height"] + 0.1
    config = FeetConfig(anchor=True, head_fallback=False, height_sigmas=3.0)
    assert anchor_to_feet([p], tracker.views, {"cam": labels}, tracker.walkable, config, HeightConfig()) == 1
    assert height_gate_m([1.7, 1.8], 0.3, 3.0) == 0.3
    assert height_gate_m([1.70, 1.73, 1.67, 1.74, 1.70], 0.1, 3.0) == 0.1


@pytest.mark.parametrize("floor_m, moves", [(0.02, 0), (0.04, 1)])
def test_the_scatter_floor_loosens_the_height_gate(seen, floor_m, moves):
    tracker, labels, _, truth = seen
    # Five equal samples (no scatter): the gate is 3 x the floor, 0.06 m or 0.12 m; the height is 0.1 m off.
    p, _ = misplaced(tracker, truth, 0.6)
    p.height = truth["height"] + 0.1
    p.height_samples.extend([p.height] * 5)
    config = FeetConfig(anchor=True, head_fallback=False, height_sigmas=3.0)
    gate = AnchorHeightConfig(scatter_floor_m=floor_m)
    assert anchor_to_feet([p], tracker.views, {"cam": labels}, tracker.walkable, config, HeightConfig(), gate) == moves
    assert height_gate_m([1.7] * 5, 0.3, 3.0, floor_m) == pytest.approx(3 * floor_m)


def _with_obstacle_beside_the_feet(tracker, instance, truth, distance_m: float):
    """The tracker's views with an obstacle ``distance_m`` m from the camera (floor distance) covering a
    few pixels 3-5 columns beside the lowest pixel of the truth's silhouette (not the pixel below it)."""
    import dataclasses

    rows, cols = np.nonzero(instance == truth["id"])
    v = int(rows.max())
    u = int(round(cols[rows == v].mean()))
    view = tracker.views["cam"]
    occ = np.array(view.occ, copy=True)
    occ[v - 1:v + 2, u + 3:u + 6] = distance_m
    return {"cam": dataclasses.replace(view, args=view.args._replace(occ=occ))}


@pytest.mark.parametrize("distance_m, moves", [(1.0, 0), (30.0, 1)])
def test_an_obstacle_nearer_than_the_feet_beside_them_stops_the_anchor_with_obstacle_clear(seen, distance_m, moves):
    tracker, labels, instance, truth = seen
    views = _with_obstacle_beside_the_feet(tracker, instance, truth, distance_m)
    p, _ = misplaced(tracker, truth, 0.6)
    config = FeetConfig(anchor=True, head_fallback=False)
    assert anchor_to_feet([p], views, {"cam": labels}, tracker.walkable, config, HeightConfig()) == 1
    p, _ = misplaced(tracker, truth, 0.6)
    config = FeetConfig(anchor=True, head_fallback=False, obstacle_clear=True)
    # Nearer than the feet: its edge may be where the silhouette ends. Behind them (30 m): not.
    assert anchor_to_feet([p], views, {"cam": labels}, tracker.walkable, config, HeightConfig()) == moves


@pytest.mark.parametrize("samples, moves", [(5, 1), (10, 0)])
def test_with_min_samples_the_height_gate_waits_for_a_settled_height(seen, samples, moves):
    tracker, labels, _, truth = seen
    # The track's height 0.1 m over what the silhouette shows: the tight gate (0.06 m) only from 10 samples.
    p, _ = misplaced(tracker, truth, 0.6)
    p.height = truth["height"] + 0.1
    p.height_samples.extend([p.height] * samples)
    config = FeetConfig(anchor=True, head_fallback=False, height_sigmas=3.0)
    gate = AnchorHeightConfig(min_samples=10)
    assert anchor_to_feet([p], tracker.views, {"cam": labels}, tracker.walkable, config, HeightConfig(), gate) == moves
    assert height_gate_m([1.7] * 9, 0.3, 3.0, 0.02, 10) == 0.3
    assert height_gate_m([1.7] * 10, 0.3, 3.0, 0.02, 10) == pytest.approx(0.06)
