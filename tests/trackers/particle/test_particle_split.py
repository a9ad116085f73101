"""Splitting a cloud in two: two lumps side by side are two objects, one long cloud is not; the
cheap first test never rules out a split; the compiled parts against their NumPy references."""

from __future__ import annotations

import math

import numpy as np

from worldtrack.trackers.particle.split import (_principal, _principal_reference, _sides, _sides_reference, _valley,
                                                _valley_reference, _wide_enough, bimodal_split, splittable)


def test_bimodal_split_finds_two_lumps_not_one_long_cloud():
    rng = np.random.default_rng(0)
    two = np.vstack([rng.normal([0, 0], 0.06, (250, 2)), rng.normal([0.6, 0], 0.06, (250, 2))])
    side = bimodal_split(two, 0.35, 0.5, 0.2)
    assert side is not None and side.sum() in range(230, 271)
    long = np.column_stack([rng.uniform(-0.4, 0.4, 500), rng.normal(0, 0.05, 500)])
    assert bimodal_split(long, 0.35, 0.5, 0.2) is None
    assert bimodal_split(rng.normal(0, 0.1, (500, 2)), 0.35, 0.5, 0.2) is None


def test_splittable_is_the_first_test_of_bimodal_split():
    rng = np.random.default_rng(0)
    clouds = []
    for k in range(60):
        gap = rng.uniform(0.0, 0.8)
        n1 = int(rng.integers(50, 450))
        lumps = np.vstack([rng.normal([0, 0], rng.uniform(0.03, 0.15), (n1, 2)),
                           rng.normal([gap, 0], rng.uniform(0.03, 0.15), (500 - n1, 2))])
        clouds.append(lumps @ [[0.6, 0.8], [-0.8, 0.6]])                # along a slanted axis
    wide = splittable(np.array(clouds), 0.35, 0.2)
    split = np.array([bimodal_split(c, 0.35, 0.5, 0.2) is not None for c in clouds])
    assert wide.any() and not wide.all() and split.any()
    assert not np.any(split & ~wide)                                    # never rules out a split
    # Wide: the std along the principal axis is at least d·sqrt(m(1 − m)).
    sd = np.sqrt([np.linalg.eigvalsh(np.cov(c.T, bias=True))[-1] for c in clouds])
    bound = 0.35 * np.sqrt(0.2 * 0.8)
    clear = np.abs(sd - bound) > 1e-9
    np.testing.assert_array_equal(wide[clear], (sd >= bound)[clear])
    assert not splittable(np.zeros((2, 7, 2)), 0.35, 0.2).any()          # too few particles


def test_bimodal_split_with_splittables_principal_is_the_same():
    """The split check reuses the principal axes that ``splittable`` computed for all clouds at once:
    the same sides (and the same None) as computing them for each cloud alone."""
    rng = np.random.default_rng(6)
    clouds = []
    for k in range(40):
        one = rng.normal(0, 0.1, (500, 3))
        if k % 2:                                         # two lumps side by side
            one[:250, 0] += rng.uniform(0.3, 0.9)
        clouds.append(one + [rng.uniform(-3, 3), rng.uniform(0, 6), 0])
    xyz = np.stack(clouds)
    wide, principal = splittable(xyz[:, :, :2], 0.35, 0.2, principal=True)
    np.testing.assert_array_equal(wide, splittable(xyz[:, :, :2], 0.35, 0.2))
    splits = 0
    for cloud, w, pc in zip(clouds, wide, principal):
        alone = bimodal_split(cloud[:, :2], 0.35, 0.5, 0.2)
        given = bimodal_split(cloud[:, :2], 0.35, 0.5, 0.2, principal=pc)
        assert (alone is None) == (given is None)
        if alone is not None:
            np.testing.assert_array_equal(alone, given)
            splits += 1
    assert 10 <= splits <= 20 and wide.sum() >= splits


def test_valley_kernel_agrees_with_reference():
    rng = np.random.default_rng(4)
    found = 0
    for k in range(300):
        gap = rng.uniform(0.0, 0.8)
        n1 = int(rng.integers(5, 400))
        s = np.concatenate([rng.normal(0.0, rng.uniform(0.03, 0.2), n1),
                            rng.normal(gap, rng.uniform(0.03, 0.2), 500 - n1)])
        lo = s.min()
        for args in ((0.04, 0.05, 0.35, 0.5), (0.02, 0.03, 0.2, 0.8)):
            a, b = _valley(s, lo, *args), _valley_reference(s, lo, *args)
            assert a == b
            found += a >= 0
    assert 50 < found < 550                  # both outcomes are exercised


def test_split_sides_kernel_agrees_with_reference():
    """The end of bimodal_split (valley, sides, each side's mass) in one kernel, against NumPy."""
    rng = np.random.default_rng(14)
    found = 0
    for trial in range(200):
        n = int(rng.integers(8, 600))
        s = rng.normal(0, 0.1, n)
        if trial % 2:
            s[: int(rng.integers(1, n))] += rng.uniform(0.2, 0.9)
        side = np.empty(n, dtype=bool)
        for min_mass in (0.2, 0.45):
            ok = _sides(s, s.min(), 0.04, 0.05, 0.35, 0.5, min_mass, side)
            ref = _sides_reference(s, s.min(), 0.04, 0.05, 0.35, 0.5, min_mass)
            assert ok == (ref is not None)
            if ok:
                np.testing.assert_array_equal(side, ref)
                found += 1
    assert found > 30


def test_principal_axes_agree_with_numpy():
    """The covariance tail of _principal equals its NumPy code; splittable's width test is _wide_enough."""
    rng = np.random.default_rng(16)
    xy = rng.normal(0, 0.3, (7, 500, 3))[:, :, :2]
    xy[3] *= 0.2                                          # a narrow cloud, not wide enough
    c, stats = _principal(xy)
    c_ref, stats_ref = _principal_reference(xy)
    np.testing.assert_array_equal(c, c_ref)
    for a, b in zip(stats, stats_ref):
        np.testing.assert_array_equal(a, b)
    wide = splittable(xy, 0.35, 0.2)
    np.testing.assert_array_equal(wide, _wide_enough(stats_ref[3], 0.35, 0.2))
    assert wide.sum() == 6 and not wide[3]


def test_bimodal_split_width_test_is_wide_enough():
    """bimodal_split's own 'wide enough' test on the principal variance it is given (one float, the
    IEEE operations of _wide_enough): a two-lump cloud is split with its own variance, and is one
    object with a variance below the limit or NaN."""
    rng = np.random.default_rng(25)
    xy = rng.normal(0, 0.05, (500, 2))
    xy[:250, 0] += 0.8                                    # two lumps 0.8 m apart
    c, (sxx, syy, sxy, lam) = _principal(xy[None])
    row = (c[0], float(sxx[0]), float(syy[0]), float(sxy[0]), float(lam[0]))
    assert _wide_enough(lam, 0.35, 0.2)[0] and bimodal_split(xy, 0.35, 0.5, 0.2, principal=row) is not None
    limit = (0.35 * math.sqrt(0.2 * 0.8)) ** 2
    for narrow in (limit * (1 - 1e-9), 0.0, -0.0, -1.0, float("nan")):
        assert not _wide_enough(np.array([narrow]), 0.35, 0.2)[0]
        assert bimodal_split(xy, 0.35, 0.5, 0.2, principal=row[:4] + (narrow,)) is None
