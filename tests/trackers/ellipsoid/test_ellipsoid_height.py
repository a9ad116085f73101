"""The compiled search for a person's ends in the foreground against its NumPy reference."""

import numpy as np
import pytest

from worldtrack.trackers.ellipsoid.height import extreme_ends, extreme_ends_reference


@pytest.mark.parametrize("down", [(0.0, 1.0), (0.6, 0.8), (-0.28, 0.96), (1.0, 0.0)])
def test_extreme_ends_equals_the_reference(down):
    # Axis-aligned directions put whole rows (or columns) of pixels on the same value along
    # ``down``: the ties at the cut must be taken in the same (row-major) order.
    rng = np.random.default_rng(3)
    for trial in range(20):
        H, W = 120, 90
        labels = np.zeros((H, W), np.uint8)
        y, x = rng.integers(0, 60), rng.integers(0, 50)
        labels[y:y + rng.integers(5, 60), x:x + rng.integers(3, 40)] = 1
        labels[rng.random((H, W)) < 0.1] = rng.choice([0, 1, 2])
        u0, v0 = int(rng.integers(0, 20)), int(rng.integers(0, 30))
        h, w = int(rng.integers(10, H - v0)), int(rng.integers(10, W - u0))
        region = rng.random((h, w)) < 0.9
        n, first, last = extreme_ends(labels, region, u0, v0, *down)
        rn, rfirst, rlast = extreme_ends_reference(labels, region, u0, v0, *down)
        assert n == rn == np.count_nonzero((labels[v0:v0 + h, u0:u0 + w] == 1) & region)
        np.testing.assert_array_equal(first, rfirst)
        np.testing.assert_array_equal(last, rlast)


def test_extreme_ends_of_a_rectangle_are_its_top_and_bottom_rows():
    labels = np.zeros((300, 200), np.uint8)
    labels[50:250, 80:120] = 1              # 8000 pixels: the 80 extreme are exactly two rows
    region = np.ones((300, 200), bool)
    n, top, bottom = extreme_ends(labels, region, 0, 0, 0.0, 1.0)
    assert n == 8000
    np.testing.assert_allclose(top, [99.5, 50.5])      # rows 50 and 51, columns 80…119
    np.testing.assert_allclose(bottom, [99.5, 248.5])  # rows 248 and 249
    n, _, _ = extreme_ends(labels, np.zeros((300, 200), bool), 0, 0, 0.0, 1.0)
    assert n == 0


def test_pixel_clear_equals_the_reference():
    from worldtrack.geometry.camera import Camera
    from worldtrack.trackers.ellipsoid.height import pixel_clear, pixel_clear_reference
    cam = Camera.look_at("c", 64, 48, [0.0, -5.0, 3.0], [0.0, 0.0, 0.0], hfov_deg=60.0)
    occ = np.full((48, 64), np.inf, np.float32)
    occ[30:, 10:40] = 4.0                                     # an obstacle in the lower left
    rng = np.random.default_rng(2)
    p = rng.uniform([-3, -3], [67, 51], (500, 2))
    p[:50] = np.round(p[:50]) + 0.5                            # exact halves round to even
    for grid in (None, occ):
        got = pixel_clear(cam, grid, p)
        np.testing.assert_array_equal(got, pixel_clear_reference(cam, grid, p))
        assert got.shape == (500,) and 0 < got.sum() < 500
        np.testing.assert_array_equal(pixel_clear(cam, grid, p.reshape(50, 10, 2)), got.reshape(50, 10))
        assert pixel_clear(cam, grid, p[7]) == got[7]            # one point: a scalar
    assert not pixel_clear(cam, occ, np.array([20.0, 40.0])) and pixel_clear(cam, None, np.array([20.0, 40.0]))
