"""Columns whose lower part is hidden — behind a nearer object or below the image's edge.

Uses the small rendered scene of ``test_particle.py``. The column kernel reports how many of each
column's lowest samples are hidden, reads per filter the samples below ``k_lo`` as no evidence and
weights samples per filter (``px_scale``); the NumPy reference must agree.
"""

from __future__ import annotations

import cv2
import numpy as np

from worldtrack.trackers.particle.likelihood import (CameraLikelihood, column_counts_reference, occluder_layers,
                                                     owner_image)

from test_particle import CAM, H, W, make_scene

ON, OFF = 2.77, -1.56


def _inputs(seed: int = 7, n: int = 3000):
    cam = make_scene(cameras=(dict(CAM, distortion=[-0.2, 0.05, 0.001, -0.002, 0.0]),)).cameras["cam"]
    rng = np.random.default_rng(seed)
    hit = (cv2.GaussianBlur(rng.random((H, W)).astype(np.float32), (0, 0), 4) > 0.5).astype(np.uint8)
    hit[(hit == 1) & (rng.random((H, W)) < 0.2)] = 2
    # Round the image's bottom edge and behind the boxes, so that many columns are hidden below.
    xy = np.column_stack([rng.uniform(-3.0, 3.0, n), rng.uniform(-0.5, 6.0, n)])
    boxes = [(40, 160, 60, 240), (120, 220, 0, 150), None]
    occluders = occluder_layers((H, W), boxes, [1.5, 2.5, 3.0])
    args = dict(on=ON, off=OFF, k_min=10, radius=0.1, below=-ON, n_below=2, n_above=2,
                owner=owner_image((H, W), boxes), box=boxes, me=[0, 1, 2], which=rng.integers(0, 3, n),
                tops=rng.uniform(1.4, 2.0, n), top_sigma=0.1, occluders=occluders, margin=0.3,
                outside_unknown=True)
    heights = np.concatenate([[-0.2, -0.1], np.arange(20) * 0.1, [2.0, 2.1]])
    return cam, hit, xy, heights, args


def test_hidden_counts_cuts_and_pixel_scales_agree_with_reference():
    cam, hit, xy, heights, args = _inputs()
    cl = CameraLikelihood(cam)
    for k_lo, px in ((0, 0.0), ([0, 6, 12], 0.0), ([3, 0, 9], [0.0, 0.3, 0.12])):
        out = cl.column(hit, xy, heights, k_lo=k_lo, px_scale=px, return_hidden=True, **args)
        ref = column_counts_reference(cam, hit, xy, heights, k_lo=k_lo, px_scale=px, return_hidden=True, **args)
        for i in (0, 3, 4):                                   # counts, seen, hidden
            np.testing.assert_array_equal(out[i], ref[i])
        np.testing.assert_allclose(out[1], ref[1], rtol=0, atol=1e-9)
        assert (out[2] == ref[2]).mean() > 0.999              # ties between tops may resolve either way
        hidden = out[4]
        # The test exercises columns hidden behind boxes, below the image, and whole columns.
        assert (hidden > 2).sum() > 100 and (hidden == 0).sum() > 100
        assert (hidden == len(heights)).sum() > 10
    # Without a cut the counts are the same, and a cut only removes evidence below k_lo.
    plain = cl.column(hit, xy, heights, return_hidden=True, **args)
    cut = cl.column(hit, xy, heights, k_lo=[5, 5, 5], return_hidden=True, **args)
    np.testing.assert_array_equal(plain[0], cut[0])
    np.testing.assert_array_equal(plain[4], cut[4])
    assert (plain[1] != cut[1]).sum() > 100


def test_a_column_hidden_up_to_k_lo_is_unchanged_by_the_cut():
    """Columns whose lowest ``k_lo`` samples are hidden anyway score the same with the cut."""
    cam, hit, xy, heights, args = _inputs(seed=8)
    cl = CameraLikelihood(cam)
    plain = cl.column(hit, xy, heights, return_hidden=True, **args)
    k = 6
    cut = cl.column(hit, xy, heights, k_lo=k, return_hidden=True, **args)
    deep = plain[4] >= k
    assert deep.sum() > 100
    np.testing.assert_array_equal(plain[1][deep], cut[1][deep])
