"""Columns whose lower part is hidden — behind a nearer object or below the image's edge — and the
order statistics and pixel scales the tracker derives from them.

The column kernel reports how many of each column's lowest samples are hidden, reads per filter the
samples below ``k_lo`` as no evidence and weights samples per filter (``px_scale``); a sample out of
the image reads no evidence with ``outside_unknown``. The NumPy reference must agree.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from worldtrack.trackers.particle.likelihood import CameraLikelihood, occluder_layers, owner_image
from worldtrack.trackers.particle.likelihood.hidden import order_statistic, quantile_rank
from worldtrack.trackers.particle.likelihood.pixel_weights import inverse_lengths, inverse_lengths_reference

from particle_scenes import CAM, DISTORTION, RING_HEIGHTS, H, W, column, column_reference, make_scene

ON, OFF = 2.77, -1.56


def _inputs(seed: int = 7, n: int = 3000):
    cam = make_scene(cameras=(dict(CAM, distortion=DISTORTION),)).cameras["cam"]
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
    return cam, hit, xy, RING_HEIGHTS, args


def test_hidden_counts_cuts_and_pixel_scales_agree_with_reference():
    cam, hit, xy, heights, args = _inputs()
    cl = CameraLikelihood(cam)
    for k_lo, px in ((0, 0.0), ([0, 6, 12], 0.0), ([3, 0, 9], [0.0, 0.3, 0.12])):
        out = column(cl, hit, xy, heights, k_lo=k_lo, px_scale=px, **args)
        ref = column_reference(cam, hit, xy, heights, k_lo=k_lo, px_scale=px, **args)
        for i in (0, 3, 4):                                   # counts, seen, hidden
            np.testing.assert_array_equal(out[i], ref[i])
        np.testing.assert_allclose(out[1], ref[1], rtol=0, atol=1e-9)
        assert (out[2] == ref[2]).mean() > 0.999              # ties between tops may resolve either way
        hidden = out[4]
        # The test exercises columns hidden behind boxes, below the image, and whole columns.
        assert (hidden > 2).sum() > 100 and (hidden == 0).sum() > 100
        assert (hidden == len(heights)).sum() > 10
    # Without a cut the counts are the same, and a cut only removes evidence below k_lo.
    plain = column(cl, hit, xy, heights, **args)
    cut = column(cl, hit, xy, heights, k_lo=[5, 5, 5], **args)
    np.testing.assert_array_equal(plain[0], cut[0])
    np.testing.assert_array_equal(plain[4], cut[4])
    assert (plain[1] != cut[1]).sum() > 100


def test_a_column_hidden_up_to_k_lo_is_unchanged_by_the_cut():
    """Columns whose lowest ``k_lo`` samples are hidden anyway score the same with the cut."""
    cam, hit, xy, heights, args = _inputs(seed=8)
    cl = CameraLikelihood(cam)
    plain = column(cl, hit, xy, heights, **args)
    k = 6
    cut = column(cl, hit, xy, heights, k_lo=k, **args)
    deep = plain[4] >= k
    assert deep.sum() > 100
    np.testing.assert_array_equal(plain[1][deep], cut[1][deep])


def test_samples_below_the_image_read_nothing_instead_of_background():
    """A column at y = 0.7 m (feet at v ≈ 260, below the 240-row image) over an image that is
    object everywhere: with ``outside_unknown`` its ratio is ``on`` times the samples in view and
    the samples out of view add nothing; without, each adds ``off``."""
    cam = make_scene().cameras["cam"]
    cl = CameraLikelihood(cam)
    hit = np.ones((H, W), dtype=np.uint8)
    xy = np.array([[0.0, 0.7]])
    z = np.arange(20) * 0.1
    inside = cam.in_image(cam.project(np.column_stack([np.zeros(20), np.full(20, 0.7), z])))
    n_in = int(inside.sum())
    assert 3 <= 20 - n_in <= 10                       # the test needs a column partly out of view
    counts, ratio, top, seen, _ = column(cl, hit, xy, z, on=ON, off=OFF, k_min=8, outside_unknown=True)
    assert counts[0] == n_in and seen[0] and top[0] == 19
    assert ratio[0] == pytest.approx(ON * n_in)
    counts, ratio, top, seen, _ = column(cl, hit, xy, z, on=ON, off=OFF, k_min=8, outside_unknown=False)
    assert counts[0] == n_in
    assert ratio[0] == pytest.approx(ON * n_in + OFF * (20 - n_in))


@pytest.mark.parametrize("radius", [0.0, 0.1])
def test_kernel_agrees_with_reference_for_columns_leaving_the_image(radius):
    cam = make_scene(cameras=(dict(CAM, distortion=DISTORTION),)).cameras["cam"]
    rng = np.random.default_rng(3)
    hit = rng.integers(0, 3, (H, W)).astype(np.uint8)
    # Floor positions round the image's bottom and side edges, so many columns leave the image.
    xy = np.column_stack([rng.uniform(-4.0, 4.0, 2000), rng.uniform(-0.5, 2.5, 2000)])
    args = dict(on=ON, off=OFF, k_min=10, radius=radius, below=-ON, n_below=2, n_above=2, outside_unknown=True)
    out = column(CameraLikelihood(cam), hit, xy, RING_HEIGHTS, **args)
    ref = column_reference(cam, hit, xy, RING_HEIGHTS, **args)
    for i in (0, 3, 4):
        np.testing.assert_array_equal(out[i], ref[i])
    np.testing.assert_allclose(out[1], ref[1], rtol=0, atol=1e-9)
    assert (out[2] == ref[2]).mean() > 0.999
    partly = out.seen & (out.counts < 20)
    assert partly.sum() > 200                          # the test exercises columns partly in view


def test_order_statistic_agrees_with_partition():
    rng = np.random.default_rng(11)
    for f, n, top in ((1, 1, 3), (4, 500, 27), (3, 37, 5), (2, 9, 5000)):      # 5000: the partition fallback
        x = rng.integers(0, top + 1, (f, n)).astype(np.int32)
        for rank in {0, n // 2, n - 1}:
            got = order_statistic(x, rank)
            assert got.dtype == x.dtype
            np.testing.assert_array_equal(got, np.partition(x, rank, axis=1)[:, rank])
    x = np.array([[5, 1, 3, 3, 0]], dtype=np.int32)
    assert order_statistic(x, 0)[0] == 0 and order_statistic(x, 2)[0] == 3 and order_statistic(x, 4)[0] == 5


@pytest.mark.parametrize("q", [0.5, 0.3, 0.1, 0.9, 1.0, 0.0])
def test_quantile_rank_picks_what_np_quantile_higher_picks(q):
    """``k_lo`` is the per-filter order statistic at :func:`quantile_rank` (np.partition), which is
    the value ``np.quantile(..., method="higher")`` returns."""
    rng = np.random.default_rng(5)
    for f, n in ((1, 1), (4, 500), (3, 37)):
        hid = rng.integers(0, 27, (f, n)).astype(np.int32)
        r = quantile_rank(n, q)
        np.testing.assert_array_equal(np.partition(hid, r, axis=1)[:, r],
                                      np.quantile(hid, q, axis=1, method="higher"))


def test_inverse_lengths_agree_with_numpy():
    rng = np.random.default_rng(26)
    uv = rng.normal(300, 80, (2, 200, 2))
    uv[1, :5] = uv[0, :5]                                 # zero length
    uv[0, 5:8] = np.nan                                   # not in front of the camera
    out = np.empty(200)
    inverse_lengths(uv, 19, out)
    np.testing.assert_array_equal(out, inverse_lengths_reference(uv, 19))
    assert np.all(out[:8] == 0) and np.all(out[8:] > 0)
