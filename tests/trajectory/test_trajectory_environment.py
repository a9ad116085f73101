"""The environment model: distance-field sampling, the barrier at Hermite substeps, crossings."""

import numpy as np
import pytest

from worldtrack.scene.floor import FloorGrid
from worldtrack.synth import make_scenario
from worldtrack.trajectory.environment import (Barrier, barrier_residuals, field_from_walkable, hermite_weights,
                                               inside_obstacles, rasterise_segments, sample_field, segment_crossings)


def _linear_field():
    xs, ys = np.arange(0, 3.01, 0.1), np.arange(0, 2.01, 0.1)
    gx, gy = np.meshgrid(xs, ys)
    return FloorGrid(np.array([0.0, 0.0]), 0.1, 0.3 * gx - 0.5 * gy + 1.0)


def test_bilinear_sampling_is_exact_on_a_linear_field_and_extrapolates_away_from_it():
    f = _linear_field()
    pts = np.array([[0.03, 0.07], [1.234, 1.987], [2.999, 0.5]])
    d, g = sample_field(f, pts)
    np.testing.assert_allclose(d, 0.3 * pts[:, 0] - 0.5 * pts[:, 1] + 1.0, atol=1e-12)
    np.testing.assert_allclose(g, np.tile([0.3, -0.5], (3, 1)), atol=1e-12)
    far, gfar = sample_field(f, np.array([[4.0, 1.0]]))               # 1 m beyond the right edge
    assert far[0] == pytest.approx(0.3 * 3.0 - 0.5 + 1.0 - 1.0)
    np.testing.assert_allclose(gfar[0], [-1.0, -0.5])     # across the edge −1, along it the field


def test_hermite_weights_reproduce_a_cubic_between_two_states():
    dt = 0.4
    p = lambda s: 1.0 + 2.0 * s - 3.0 * s ** 2 + 0.5 * s ** 3            # noqa: E731
    v = lambda s: 2.0 - 6.0 * s + 1.5 * s ** 2                           # noqa: E731
    alpha = np.linspace(0, 1, 7)
    H = hermite_weights(alpha, dt)
    np.testing.assert_allclose(H @ np.array([p(0), v(0), p(dt), v(dt)]), p(alpha * dt), atol=1e-12)


@pytest.fixture(scope="module")
def office_field():
    sc = make_scenario("non-overlapping", frames=2, seed=0, people=1, layout="detours")
    return sc.scene.distance_field(0.05)


def _random_states(n=400, seed=0):
    rng = np.random.default_rng(seed)
    X = np.zeros((n, 6))
    X[:, 0], X[:, 2] = rng.uniform(-1, 17, n), rng.uniform(-1, 9, n)
    X[:, 1], X[:, 3], X[:, 4] = rng.normal(0, 1, n), rng.normal(0, 1, n), 1.7
    return X


def test_the_compiled_barrier_equals_its_numpy_reference(office_field):
    X = _random_states()
    b = Barrier(office_field, clearance=0.2, substeps=3)
    fast = barrier_residuals(X, b, 1.5, 0.1, only_active=False)
    ref = barrier_residuals(X, b, 1.5, 0.1, only_active=False, reference=True)
    for name in ("r", "J", "curvature"):
        np.testing.assert_allclose(getattr(fast, name), getattr(ref, name), rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(fast.inside, ref.inside)
    assert fast.inside.any() and not fast.inside.all()


def test_the_barrier_jacobian_matches_finite_differences(office_field):
    X = _random_states(60, seed=3)
    b = Barrier(office_field, clearance=0.3, substeps=2, softness=0.05)
    res = barrier_residuals(X, b, 1.0, 0.2, only_active=False)
    h = 1e-6
    for k in (0, 1, 2, 3):          # u, u̇, v, v̇ of every state
        Xp, Xm = X.copy(), X.copy()
        Xp[:, k] += h
        Xm[:, k] -= h
        num = (barrier_residuals(Xp, b, 1.0, 0.2, only_active=False).r
               - barrier_residuals(Xm, b, 1.0, 0.2, only_active=False).r) / (2 * h)
        # each sample depends on x_t (column k) and x_{t+1} (column 6 + k)
        ana = res.J[:, k] + res.J[:, 6 + k]
        # a sample whose two states are both moved sees the sum of both derivatives
        assert np.nanmax(np.abs(num - ana)) < 1e-4 * max(1.0, np.abs(ana).max())


def test_the_barrier_grows_into_obstacles_and_vanishes_far_from_them():
    walk = np.ones((40, 40), dtype=bool)
    walk[:, 20:] = False                         # a wall filling x ≥ 2 m
    f = field_from_walkable(walk, (0.0, 0.0), 0.1)
    b = Barrier(f, clearance=0.2, scale=0.02, softness=0.03)
    X = np.zeros((4, 6))
    X[:, 0] = [0.5, 1.6, 1.8, 2.3]              # far, at the clearance, inside it, inside the wall
    X[:, 2] = 2.0
    r = barrier_residuals(X, b, 1.0, 0.1, only_active=False).r
    assert r[0] < 1e-6 and r[1] < r[2] < r[3]
    assert r[3] == pytest.approx((0.2 - (1.95 - 2.3)) / 0.02, rel=1e-6)    # deep inside: the plain hinge (c − d)/s


def test_walls_as_segments_block_and_crossings_are_counted():
    blocked = np.zeros((30, 30), dtype=bool)
    rasterise_segments(blocked, np.array([[[1.5, 0.0], [1.5, 2.0]]]), (0.0, 0.0), 0.1)
    assert blocked[:, 15].sum() >= 20 and blocked[:, :14].sum() == 0
    walls = np.array([[[1.5, 0.0], [1.5, 2.0]]])
    path = np.array([[1.0, 1.0], [1.4, 1.0], [1.6, 1.0], [1.6, 2.5], [1.4, 2.5]])
    np.testing.assert_array_equal(segment_crossings(path, walls), [False, True, False, False])
    f = field_from_walkable(~blocked, (0.0, 0.0), 0.1)
    assert inside_obstacles(f, [[1.5, 1.0]])[0] and not inside_obstacles(f, [[1.0, 1.0]])[0]
