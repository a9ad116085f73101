"""The object region (eqs. 9–10): the clouds' means and the region sizes, kernels against NumPy."""

from __future__ import annotations

import numpy as np

from worldtrack.trackers.particle.region import cloud_mean, region_sizes, region_sizes_reference


def test_region_sizes_agree_with_numpy():
    rng = np.random.default_rng(18)
    sd = rng.uniform(0, 0.5, (9, 3))
    widths = rng.uniform(0.3, 0.6, 9)
    for w in (widths, np.zeros(0)):
        a, b = sd.copy(), sd.copy()
        sa, sb = np.empty(9), np.empty(9)
        region_sizes(a, w, sa)
        region_sizes_reference(b, w, sb)
        np.testing.assert_array_equal(a, b)
        np.testing.assert_array_equal(sa, sb)
        assert (a[:, :2] > sd[:, :2]).all() if len(w) else np.array_equal(a, sd)


def test_cloud_mean_is_the_mean_over_particles():
    rng = np.random.default_rng(19)
    x = rng.normal(size=(5, 400, 3))
    np.testing.assert_allclose(cloud_mean(x), x.mean(axis=1), rtol=0, atol=1e-12)


def test_row_means_and_sds_are_numpys():
    from worldtrack.trackers.particle.region import mean_rows, mean_sd

    rng = np.random.default_rng(20)
    h = rng.normal(1.7, 0.1, (6, 500))
    np.testing.assert_array_equal(mean_rows(h), h.mean(axis=1))
    x = rng.normal(0, 0.3, (4, 500, 3))
    mean, sd = mean_sd(x)
    np.testing.assert_allclose(mean, x.mean(axis=1), rtol=0, atol=1e-12)
    np.testing.assert_allclose(sd, x.std(axis=1), rtol=0, atol=1e-12)
