"""Objects' image boxes: the plain projection against the kernel, what a box covers, and the
overlap tests (a box alone; two filters on one object)."""

from __future__ import annotations

import numpy as np
import pytest

from worldtrack.trackers.particle.likelihood import CameraLikelihood
from worldtrack.trackers.particle.likelihood.boxes import (boxes_apart, boxes_on_one_object,
                                                           boxes_on_one_object_reference, image_box, image_boxes,
                                                           overlaps)

from particle_scenes import CAM, DISTORTION, HEIGHT, H, W, WIDTH, make_scene, render

OVERHEAD = {"id": "cam", "image_size": [W, H], "position": [0, 2.999, 4], "look_at": [0, 3, 0], "hfov_deg": 70}


def test_image_box_covers_the_person():
    scene = make_scene()
    cam = scene.cameras["cam"]
    img = render(cam, np.zeros((H, W, 3), np.uint8), [(0.5, 3.0)], np.random.default_rng(0))
    ys, xs = np.nonzero(img.max(axis=2) > 100)
    u0, u1, v0, v1 = image_box(cam, 0.5, 3.0, WIDTH, HEIGHT, 0.0)
    assert u0 <= xs.min() + 1 and u1 >= xs.max() and v0 <= ys.min() + 1 and v1 >= ys.max()
    assert (u1 - u0) < 1.3 * (xs.max() - xs.min() + 1)


@pytest.mark.parametrize("spec", [CAM, dict(CAM, distortion=DISTORTION), OVERHEAD])
def test_box_kernel_agrees_with_image_boxes(spec):
    cam = make_scene(cameras=(spec,)).cameras["cam"]
    rng = np.random.default_rng(6)
    xy = np.column_stack([rng.uniform(-8, 8, 3000), rng.uniform(-4, 12, 3000)])   # in view, out, behind
    xy[:2] = cam.centre[:2]                                                      # at the camera's foot
    widths, heights = rng.uniform(0.3, 0.6, len(xy)), rng.uniform(1.0, 2.0, len(xy))
    cl = CameraLikelihood(cam)
    for margin, depth in ((0.0, 0.0), (0.05, 0.0), (0.05, 0.5)):
        plain = image_boxes(cam, xy, widths, heights, margin, depth)
        assert cl.boxes(xy, widths, heights, margin, depth) == plain
        assert 100 < sum(b is None for b in plain) < len(xy) - 100
        assert sum(b is not None and (b[0] == 0 or b[1] == W) for b in plain) > 50     # clipped at the edges
        assert plain[0] is not None or spec is not OVERHEAD                            # seen at the foot


def test_image_box_with_depth_covers_the_object_nearer_and_farther():
    cam = make_scene().cameras["cam"]
    for x, y in [(0.5, 3.0), (-2.0, 5.0), (2.5, 1.5)]:       # the last one cut by the image's edges
        along = (np.array([x, y]) - cam.centre[:2]) / np.hypot(x - cam.centre[0], y - cam.centre[1])
        near, mid, far = (image_box(cam, *(np.array([x, y]) + s * along), WIDTH, HEIGHT, 0.05) for s in (-0.5, 0, 0.5))
        deep = image_box(cam, x, y, WIDTH, HEIGHT, 0.05, depth=0.5)
        together = (min(near[0], mid[0], far[0]), max(near[1], mid[1], far[1]),
                    min(near[2], mid[2], far[2]), max(near[3], mid[3], far[3]))
        np.testing.assert_allclose(deep, together, atol=1)     # the three boxes together, to a pixel
        assert deep[3] - deep[2] > mid[3] - mid[2] + 10          # stretched along the line of sight


def test_boxes_apart_agrees_with_overlaps():
    """Which boxes overlap no other: integers in a kernel against the NumPy ratios of overlaps."""
    rng = np.random.default_rng(9)
    for trial in range(50):
        k = int(rng.integers(1, 15))
        u0, v0 = rng.integers(0, W - 1, k), rng.integers(0, H - 1, k)
        boxes = [None if rng.random() < 0.2 else (int(a), int(min(a + rng.integers(1, 60), W)), int(b),
                                                 int(min(b + rng.integers(1, 60), H))) for a, b in zip(u0, v0)]
        arr = np.array([(-1,) * 4 if b is None else b for b in boxes], dtype=np.int64).reshape(-1, 4)
        ov = overlaps(boxes)
        np.fill_diagonal(ov, 0.0)
        want = np.array([b is not None for b in boxes]) & ~(ov > 0).any(axis=1)
        np.testing.assert_array_equal(boxes_apart(arr), want)
    assert boxes_apart(np.array([[0, 10, 0, 10], [10, 20, 0, 10], [5, 15, 9, 12]])).tolist() == [False, False, False]
    assert boxes_apart(np.array([[0, 10, 0, 10], [10, 20, 0, 10]])).tolist() == [True, True]   # edges touch


def test_boxes_on_one_object_agrees_with_reference():
    """The merge's test of two filters on one object (boxes overlapping by ``merge.overlap`` in
    every camera that sees both), integers against the NumPy ratios of overlaps."""
    rng = np.random.default_rng(12)
    found = 0
    for trial in range(60):
        c, k = int(rng.integers(1, 4)), int(rng.integers(2, 12))
        cams = []
        for _ in range(c):
            u0, v0 = rng.integers(0, 60, k), rng.integers(0, 60, k)
            cams.append([None if rng.random() < 0.2 else (int(a), int(a + rng.integers(5, 40)), int(b),
                                                         int(b + rng.integers(5, 40))) for a, b in zip(u0, v0)])
        arr = np.array([[(-1,) * 4 if b is None else b for b in cam] for cam in cams], dtype=np.int64)
        for min_overlap in (0.6, 0.3):
            got = boxes_on_one_object(arr, min_overlap)
            np.testing.assert_array_equal(got, boxes_on_one_object_reference(cams, min_overlap))
            found += got.sum()
        assert np.array_equal(boxes_on_one_object_reference([cams[0]], 0.6),
                              np.triu(~np.isnan(overlaps(cams[0])) & (overlaps(cams[0]) >= 0.6), 1))
    assert found > 20
