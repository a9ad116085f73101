"""Weights (eq. 8) and resampling: what systematic and stratified resampling draw, row by row, and
the compiled kernels against their NumPy references."""

from __future__ import annotations

import numpy as np
import pytest

from worldtrack.errors import InputError
from worldtrack.trackers.particle.resample import (RESAMPLERS, Particles, _draw_rows, _lookup, gather_particles,
                                                   particle_weights, resample_reference, resampler,
                                                   stratified_resample, systematic_resample, take_rows,
                                                   weights_reference)


def test_systematic_resampling_copies_floor_or_ceil_of_n_w():
    rng = np.random.default_rng(0)
    w = rng.random(50) ** 3
    idx = systematic_resample(w, 1000, rng)
    counts = np.bincount(idx, minlength=50)
    expected = 1000 * w / w.sum()
    assert np.all(counts >= np.floor(expected)) and np.all(counts <= np.ceil(expected))
    s = np.bincount(stratified_resample(w, 100000, rng), minlength=50)
    np.testing.assert_allclose(s / 100000, w / w.sum(), atol=0.003)


def test_resamplers_are_chosen_by_name():
    assert resampler("systematic") is systematic_resample and RESAMPLERS["stratified"] is stratified_resample
    with pytest.raises(InputError, match="particle.weights.resampler: expected one of systematic, stratified, "
                                         "got 'multinomial'"):
        resampler("multinomial")


def test_resampling_rows_is_resampling_each_row():
    """F filters' weights as rows: each row resampled on its own, with the same random numbers as
    one call per row; the lookup is ``searchsorted(side="right")`` (zero weights never drawn)."""
    rng = np.random.default_rng(1)
    W = rng.random((6, 40)) ** 4
    W[:, ::3] = 0.0                                                     # ties in the cumulative weights
    W[2] = 0.0
    W[2, 7] = 1.0                                                       # one particle takes all
    for resample in (systematic_resample, stratified_resample):
        rows = resample(W, 40, np.random.default_rng(9))
        r = np.random.default_rng(9)
        np.testing.assert_array_equal(rows, [resample(w, 40, r) for w in W])
        assert rows.shape == (6, 40) and np.all(rows[2] == 7) and not np.any(rows % 3 == 0)
    u = (np.random.default_rng(2).random((6, 1)) + np.arange(40)) / 40
    c = np.cumsum(W, axis=1) / W.sum(axis=1, keepdims=True)
    expected = [np.minimum(np.searchsorted(cr, ur, side="right"), 39) for cr, ur in zip(c, u)]
    np.testing.assert_array_equal(systematic_resample(W, 40, np.random.default_rng(2)), expected)
    # A point on a cumulative weight falls after it (side="right"), past the last one stays in range.
    np.testing.assert_array_equal(_lookup(np.ones((1, 4)), np.array([[0.0, 0.25, 0.5, 0.75, 1.0]])),
                                  [[0, 1, 2, 3, 3]])


def test_resampling_kernel_agrees_with_reference():
    """Systematic and stratified resampling (cumulative weights, normalised, points merged in one
    kernel) draw the NumPy lookup's indices: ties, zero weights and a row with one weight included."""
    rng = np.random.default_rng(7)
    for trial in range(30):
        f, m = int(rng.integers(1, 12)), int(rng.integers(1, 600))
        w = rng.random((f, m)) ** rng.uniform(1, 30)
        w[:, ::3] = 0.0
        w[0] = 0.0
        w[0, m // 2] = 2.5
        for resample, shape in ((systematic_resample, (f, 1)), (stratified_resample, (f, m))):
            got = resample(w, m, np.random.default_rng(trial))
            ref = resample_reference(w, np.random.default_rng(trial).random(shape), m)
            np.testing.assert_array_equal(got, ref)
            assert np.all(got[0] == m // 2) and not np.any(got[1:] % 3 == 0)
    # Points exactly on a cumulative weight (0, 1/4, 2/4, 3/4 over four equal weights) fall after it
    # (side="right"), in the kernel as in the reference; random points never test that.
    for r in (np.zeros((1, 1)), np.zeros((1, 4))):
        np.testing.assert_array_equal(_draw_rows(np.ones((1, 4)), r, 4), [[0, 1, 2, 3]])
        np.testing.assert_array_equal(resample_reference(np.ones((1, 4)), r, 4), [[0, 1, 2, 3]])


def test_take_rows_agrees_with_take_along_axis():
    rng = np.random.default_rng(8)
    idx = rng.integers(0, 50, (4, 70))
    for a in (rng.normal(size=(4, 50, 3)), rng.normal(size=(4, 50)), rng.random((4, 50)) < 0.5):
        want = np.take_along_axis(a, idx.reshape(idx.shape + (1,) * (a.ndim - 2)), axis=1)
        got = take_rows(a, idx)
        assert got.dtype == a.dtype and got.shape == want.shape
        np.testing.assert_array_equal(got, want)
    assert take_rows(np.zeros((2, 0, 3)), np.zeros((2, 0), dtype=np.int64)).shape == (2, 0, 3)


def test_gather_particles_agrees_with_take_rows():
    """The resampled particles gathered in one kernel (heights drawn below the column tops) equal
    take_rows and the NumPy product."""
    rng = np.random.default_rng(16)
    f, m, n = 5, 300, 280
    parts = Particles(rng.normal(size=(f, m, 3)), rng.normal(size=(f, m, 3)), rng.normal(size=(f, m)),
                      rng.normal(size=(f, m)), rng.random((f, m)) < 0.5, rng.uniform(0, 2, (f, m)))
    idx = np.sort(rng.integers(0, m, (f, n)), axis=1)
    z = rng.random((f, n))
    for draws in (None, z):
        got = gather_particles(idx, parts, z=draws)
        want = [take_rows(a, idx) for a in parts]
        if draws is not None:
            want[0][..., 2] = draws * want[5]
        for a, b in zip(got, want):
            assert a.dtype == b.dtype
            np.testing.assert_array_equal(a, b)


def test_particle_weights_agree_with_numpy_bit_for_bit():
    """Eq. 8's weights from the kernel's max and exponents against weights_reference: equal bit for bit
    for rows of filters and for one filter's row, a row of zero likelihood (-inf everywhere) weighs 1
    throughout and is resampled uniformly, and so does a row with a NaN (np.max's NaN is not finite)."""
    rng = np.random.default_rng(17)
    logpi = rng.normal(0, 20, (4, 300))
    logpi[logpi < -25] = -np.inf
    logpi[2] = -np.inf                                   # nothing likely: uniform weights
    for power in (0.2, 1.0):
        w = particle_weights(logpi, power)
        np.testing.assert_array_equal(w, weights_reference(logpi, power))
        np.testing.assert_array_equal(particle_weights(logpi[1], power), weights_reference(logpi[1], power))
    assert (w[2] == 1).all() and w[[0, 1, 3]].max(axis=1).tolist() == [1.0, 1.0, 1.0]
    idx = systematic_resample(w, 300, np.random.default_rng(3))
    assert len(np.unique(idx[2])) == 300 and len(np.unique(idx[0])) < 100   # uniform row vs peaked rows
    nan = logpi.copy()
    nan[0, 5] = np.nan
    np.testing.assert_array_equal(particle_weights(nan, 0.2), weights_reference(nan, 0.2))
    assert (particle_weights(nan, 0.2)[0] == 1).all()
    assert particle_weights(np.zeros((3, 0)), 0.2).shape == (3, 0)
