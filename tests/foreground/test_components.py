"""connected_components (Grana's algorithm) against OpenCV's default labelling."""

import cv2
import numpy as np
import pytest

from worldtrack.foreground.components import blob_extent, blob_extent_reference, blobs, connected_components


@pytest.mark.parametrize("seed", range(5))
def test_same_labels_and_stats_as_the_default_algorithm(seed):
    rng = np.random.default_rng(seed)
    # Blobs of many sizes and shapes, touching diagonally in places (8-connectivity matters).
    noise = cv2.GaussianBlur(rng.random((240, 320)).astype(np.float32), (0, 0), 1 + seed)
    mask = (noise > np.quantile(noise, 0.7)).astype(np.uint8)
    n, labels, stats, cent = connected_components(mask)
    n0, labels0, stats0, cent0 = cv2.connectedComponentsWithStats(mask, connectivity=8)
    assert n == n0 > 3
    np.testing.assert_array_equal(labels, labels0)
    np.testing.assert_array_equal(stats, stats0)
    np.testing.assert_allclose(cent, cent0)


def test_two_diagonal_pixels_are_one_component_and_stats_are_exact():
    mask = np.zeros((6, 8), np.uint8)
    mask[1, 1] = mask[2, 2] = 1          # diagonal neighbours: one component
    mask[4, 5:8] = 1                     # a 3-pixel bar at the right border
    n, labels, stats, cent = connected_components(mask)
    assert n == 3
    assert labels[1, 1] == labels[2, 2] != labels[4, 6]
    np.testing.assert_array_equal(stats[labels[1, 1]], [1, 1, 2, 2, 2])
    np.testing.assert_array_equal(stats[labels[4, 6]], [5, 4, 3, 1, 3])
    np.testing.assert_allclose(cent[labels[4, 6]], [6.0, 4.0])


@pytest.mark.parametrize("shape", [(480, 640), (121, 161)])     # even, and not a multiple of the factor
def test_blobs_found_at_half_resolution_are_the_full_resolution_blobs(shape):
    rng = np.random.default_rng(7)
    mask = np.zeros(shape, np.uint8)
    H, W = shape
    for k in range(10):                  # separate rectangles (≥ 4 px apart: a 4 px grid of cells)
        y, x = 4 + 40 * (k // 4) % (H - 40), 4 + 40 * (k % 4) % (W - 40)
        h, w = rng.integers(1, 33, size=2)
        mask[y:y + h, x:x + w] = 1
    mask[H - 1, W - 1] = 1               # a single pixel in the last, partial block
    full = sorted(blobs(mask, 1, 1), key=lambda b: b[1])
    half = sorted(blobs(mask, 1, 2), key=lambda b: b[1])
    assert len(full) == len(half) >= 8
    for (a0, box0, c0, m0), (a1, box1, c1, m1) in zip(full, half):
        assert a0 == a1 and box0 == box1
        np.testing.assert_allclose(c0, c1)
        np.testing.assert_array_equal(m0, m1)
    # min_area counts full-resolution pixels
    assert sorted(b[1] for b in blobs(mask, 50, 2)) == sorted(b[1] for b in full if b[0] >= 50)


def test_blobs_one_pixel_apart_are_joined_at_half_resolution():
    mask = np.zeros((8, 8), np.uint8)
    mask[2:6, 1] = 1
    mask[2:6, 3] = 1                     # one empty column between: two blobs, one 2x2 block apart
    assert len(blobs(mask, 1, 1)) == 2
    ((area, box, centroid, crop),) = blobs(mask, 1, 2)
    assert area == 8 and box == (1, 2, 3, 4)
    np.testing.assert_allclose(centroid, [2.0, 3.5])
    assert crop.sum() == 8 and not crop[:, 1].any()


def test_a_shrink_factor_that_would_lose_single_pixels_is_refused():
    mask = np.zeros((100, 100), np.uint8)
    mask[50, 50] = 1
    assert len(blobs(mask, 1, 22)) == 1          # 255 / 22² rounds to 1: the pixel survives
    with pytest.raises(ValueError, match="at most 22"):
        blobs(mask, 1, 23)


@pytest.mark.parametrize("direction", [(0.0, 1.0), (0.6, 0.8), (-0.96, 0.28)])
def test_blob_extent_equals_the_reference(direction):
    rng = np.random.default_rng(5)
    for trial in range(20):
        blob = rng.random((int(rng.integers(1, 80)), int(rng.integers(1, 50)))) < rng.uniform(0.2, 1.0)
        u0, v0 = int(rng.integers(0, 300)), int(rng.integers(0, 200))
        cu, cv = u0 + rng.uniform(0, blob.shape[1]), v0 + rng.uniform(0, blob.shape[0])
        got = blob_extent(blob, u0, v0, cu, cv, *direction, 50)
        want = blob_extent_reference(blob, u0, v0, cu, cv, *direction, 50)
        if not blob.any():
            assert np.isnan(got).all() and np.isnan(want).all()
            continue
        np.testing.assert_array_equal(got[:4], want[:4])
        np.testing.assert_allclose(got[4:], want[4:], rtol=0, atol=1e-9)   # sums in another order


def test_blob_extent_of_a_rectangle():
    blob = np.zeros((100, 40), bool)
    blob[10:90, 5:25] = True                       # 1600 pixels, 20 per row: each end is 32 = 1.6 rows
    along_min, along_max, across_min, across_max, first, last = blob_extent(blob, 100, 50, 115.0, 100.0, 0.0, 1.0, 50)
    assert (along_min, along_max) == (60 - 100.0, 139 - 100.0)   # rows v = 60 … 139 about v = 100
    assert (across_min, across_max) == (-(124 - 115.0), -(105 - 115.0))   # across = −du for down = (0, 1)
    # The top end: row 60 whole (u 105…124) and the first 12 pixels of row 61 (u 105…116).
    assert first == pytest.approx(-np.mean([*range(105, 125), *range(105, 117)]) + 115.0)


def test_extreme_indices_take_ties_in_index_order():
    from worldtrack.foreground.components import extreme_indices
    values = np.array([3.0, 1.0, 2.0, 1.0, 5.0, 1.0, 5.0, 0.0])
    assert extreme_indices(values, 3, True).tolist() == [7, 1, 3]       # 0, then the first two 1s
    assert extreme_indices(values, 1, False).tolist() == [4]            # the first of the two 5s
    assert extreme_indices(values, 3, False).tolist() == [4, 6, 0]      # both 5s, then the 3
    order = np.argsort(values, kind="stable")
    assert sorted(extreme_indices(values, 5, True).tolist()) == sorted(order[:5].tolist())
