"""The banded Levenberg–Marquardt against dense references (seed 002's objective, eq. 9)."""

import numpy as np
import pytest

from worldtrack.trajectory import kernels
from worldtrack.trajectory.model import dense_from_blocks
from worldtrack.trajectory.objective import evaluate, linearise
from worldtrack.trajectory.solver import (LevenbergMarquardt, SolverOptions, dense_objective, jacobian_dense,
                                          levenberg_marquardt, residual_vector, solve_blocks, solve_dense, to_banded)
from worldtrack.trajectory.starts import straight_start
from worldtrack.trajectory.uncertainty import marginal_covariances, marginal_covariances_dense

from _trajectory_cases import observed_walk


def _random_blocks(n, seed=0):
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(n, 6, 6))
    D = np.einsum("nij,nkj->nik", A, A) + 6 * np.eye(6)
    B = 0.3 * rng.normal(size=(n - 1, 6, 6))
    return D, B


def test_band_storage_products_and_solves_equal_the_dense_matrix():
    D, B = _random_blocks(9)
    H = dense_from_blocks(D, B)
    np.testing.assert_array_equal(to_banded(D, B), kernels.fill_banded_reference(D, B))
    x = np.random.default_rng(2).normal(size=(9, 6))
    np.testing.assert_allclose(kernels.block_matvec(D, B, x), (H @ x.ravel()).reshape(9, 6), atol=1e-10)
    np.testing.assert_allclose(kernels.block_matvec_reference(D, B, x), (H @ x.ravel()).reshape(9, 6), atol=1e-10)
    np.testing.assert_allclose(solve_blocks(D, B, x), np.linalg.solve(H, x.ravel()).reshape(9, 6), atol=1e-10)


def test_the_block_cholesky_kernel_equals_lapacks_band_cholesky():
    D, B = _random_blocks(40, seed=8)
    rng = np.random.default_rng(9)
    rhs, damping = rng.normal(size=(40, 6)), rng.uniform(0, 2, (40, 6))
    work = np.empty((40, 6, 6)), np.empty((40, 6, 6)), np.empty((40, 6)), np.empty((40, 6))
    assert kernels.block_cholesky_solve(D, B, damping, rhs, *work)
    Dd = D.copy()
    Dd[:, np.arange(6), np.arange(6)] += damping
    np.testing.assert_allclose(work[3], solve_blocks(Dd, B, rhs), rtol=1e-10, atol=1e-12)
    D[17] = -np.eye(6)                                              # not positive definite
    assert not kernels.block_cholesky_solve(D, B, damping * 0, rhs, *work)


def test_lm_with_either_linear_solver_reaches_the_same_optimum():
    case = observed_walk(T=81, seed=5)
    X0 = straight_start(case.problem.observations, case.problem.grid, 1.7)
    a = levenberg_marquardt(case.problem, X0, SolverOptions(linear_solver="block"))
    b = levenberg_marquardt(case.problem, X0, SolverOptions(linear_solver="lapack"))
    assert a.costs.total == pytest.approx(b.costs.total, rel=1e-12)
    assert np.abs(a.X - b.X).max() < 1e-8


def test_the_motion_kernel_equals_its_numpy_reference():
    from worldtrack.trajectory.model import MotionPrior
    X = np.random.default_rng(3).normal(size=(30, 6))
    prior = MotionPrior(0.8, 0.05)
    A, W = prior.transition(0.2), prior.whitener(0.2)
    g1, g2 = np.zeros((30, 6)), np.zeros((30, 6))
    c1 = kernels.add_motion_terms(X, A, W, g1)
    c2 = kernels.add_motion_terms_reference(X, A, W, g2)
    assert c1 == pytest.approx(c2, rel=1e-12)
    np.testing.assert_allclose(g1, g2, atol=1e-9)


def test_the_compiled_scatter_equals_np_add_at():
    rng = np.random.default_rng(4)
    n, m = 12, 40
    step = np.sort(rng.integers(0, n - 1, m))
    J, r, w = rng.normal(size=(m, 12)), rng.normal(size=m), rng.uniform(1, 2, m)
    a = [np.zeros((n, 6, 6)), np.zeros((n - 1, 6, 6)), np.zeros((n, 6))]
    b = [np.zeros((n, 6, 6)), np.zeros((n - 1, 6, 6)), np.zeros((n, 6))]
    kernels.add_pair_terms(*a, step, J, r, w)
    kernels.add_pair_terms_reference(*b, step, J, r, w)
    for x, y in zip(a, b):
        np.testing.assert_allclose(x, y, atol=1e-12)


@pytest.fixture(scope="module")
def walk_with_wall():
    from worldtrack.trajectory.environment import field_from_walkable
    walk = np.ones((80, 120), dtype=bool)       # x −1…4.95 m, y −2…1.95 m
    walk[20:40, 50:70] = False                  # a block at x 1.5–2.5 m, y −1…1 m: the walk bends round it
    field = field_from_walkable(walk, (-1.0, -2.0), 0.05)
    return observed_walk(T=81, barrier_field=field, curve=1.6)


def test_normal_equations_are_j_transpose_j_of_the_stacked_residuals(walk_with_wall):
    case = walk_with_wall
    X = straight_start(case.problem.observations, case.problem.grid, 1.7)
    X[:, 2] += 0.3 * np.sin(np.arange(len(X)) / 9.0)               # somewhere near the block
    lin = linearise(case.problem, X)
    J = jacobian_dense(case.problem, X)
    r = residual_vector(case.problem, X)
    assert lin.costs.total == pytest.approx(r @ r, rel=1e-12) == pytest.approx(evaluate(case.problem, X).total)
    np.testing.assert_allclose(lin.g.ravel(), J.T @ r, rtol=1e-9, atol=1e-6)
    GN = J.T @ J
    H = dense_from_blocks(lin.D, lin.B)
    # identical but for the barrier's curvature factor, which only adds on the samples' own directions
    assert np.all(np.linalg.eigvalsh(H - GN) > -1e-6)
    free = case.problem.with_environment(case.problem.environment.without_barrier())
    lin0 = linearise(free, X)
    J0 = jacobian_dense(free, X)
    np.testing.assert_allclose(dense_from_blocks(lin0.D, lin0.B), J0.T @ J0, rtol=1e-10, atol=1e-6)


def test_the_dense_jacobian_matches_finite_differences(walk_with_wall):
    case = walk_with_wall
    X = straight_start(case.problem.observations, case.problem.grid, 1.7)[:30]
    from worldtrack.trajectory.model import TimeGrid
    from worldtrack.trajectory.objective import Problem
    sub = case.obs.subset(case.obs.time <= case.problem.grid.times[29] + 1e-9)
    problem = Problem.build(sub, TimeGrid(case.problem.grid.t0, 0.1, 30), case.problem.motion,
                            case.problem.environment)
    X[:, 2] += 0.5
    J = jacobian_dense(problem, X)
    h = 1e-6
    cols = np.arange(0, X.size, 7)
    for c in cols:
        e = np.zeros(X.size)
        e[c] = h
        num = (residual_vector(problem, (X.ravel() + e).reshape(X.shape))
               - residual_vector(problem, (X.ravel() - e).reshape(X.shape))) / (2 * h)
        np.testing.assert_allclose(J[:, c], num, rtol=1e-5, atol=1e-4 * max(1, np.abs(num).max()))


@pytest.mark.slow
def test_banded_lm_equals_dense_least_squares_on_200_steps():
    """The issue's check: T = 200, no barrier — same optimum as scipy.optimize.least_squares."""
    case = observed_walk(T=200, seed=7)
    problem = case.problem
    assert problem.grid.n >= 190
    X0 = straight_start(problem.observations, problem.grid, 1.7)
    ours = levenberg_marquardt(problem, X0)
    ref = solve_dense(problem, X0)
    assert ours.converged
    f_ours, f_ref = ours.costs.total, dense_objective(problem, ref)
    assert abs(f_ours - f_ref) <= 1e-9 * f_ref
    assert np.abs(ours.X[:, [0, 2, 4]] - ref[:, [0, 2, 4]]).max() < 1e-6


def test_with_the_barrier_both_reach_the_same_optimum_from_the_same_start(walk_with_wall):
    case = walk_with_wall
    problem = case.problem
    from worldtrack.trajectory.starts import shortest_path_start
    X0 = shortest_path_start(problem.observations, problem.grid, 1.7, problem.environment.barrier.field, 0.2)
    ours = levenberg_marquardt(problem, X0, SolverOptions(barrier_relative_decrease=1e-12))
    ref = solve_dense(problem, ours.X, xtol=1e-10)    # polished from ours: is it a stationary point?
    assert dense_objective(problem, ref) >= ours.costs.total * (1 - 1e-7)
    assert np.abs(ours.X[:, [0, 2]] - ref[:, [0, 2]]).max() < 2e-3


def test_huber_loss_discounts_an_outlier():
    case = observed_walk(T=81, seed=3)
    bad = case.obs.uv.copy()
    bad[5] += [60.0, -45.0]                                     # one wrong detection, 75 px off
    from worldtrack.trajectory.observation import Observations
    from worldtrack.trajectory.objective import Problem
    obs = Observations(case.obs.time, case.obs.camera, bad, case.obs.sigma, case.obs.cameras)
    k = case.problem.observations.step[5]
    errs = {}
    for robust in (None, 2.0):
        problem = Problem.build(obs, case.problem.grid, case.problem.motion, case.problem.environment, robust)
        X = levenberg_marquardt(problem, straight_start(problem.observations, problem.grid, 1.7)).X
        errs[robust] = np.hypot(*(X[k, [0, 2]] - case.truth[k, :2]))
    assert errs[2.0] < 0.02 < errs[None]


def test_a_race_then_convergence_equals_one_uninterrupted_run():
    case = observed_walk(T=81, seed=1)
    X0 = straight_start(case.problem.observations, case.problem.grid, 1.7)
    one = levenberg_marquardt(case.problem, X0)
    solver = LevenbergMarquardt(case.problem, X0)
    solver.run(1)
    assert solver.iterations == 1 and not solver.converged
    two = solver.run()
    np.testing.assert_array_equal(one.X, two.X)


def test_marginal_covariances_equal_the_inverse_of_the_whole_matrix():
    D, B = _random_blocks(15, seed=5)
    np.testing.assert_allclose(marginal_covariances(D, B), marginal_covariances_dense(D, B), rtol=1e-9, atol=1e-12)


def test_uncertainty_is_small_in_view_and_large_between_views():
    case = observed_walk(T=81, seed=2)
    res = levenberg_marquardt(case.problem, straight_start(case.problem.observations, case.problem.grid, 1.7))
    C = marginal_covariances(res.linearisation.D, res.linearisation.B)
    sigma_x = np.sqrt(C[:, 0, 0])
    seen = np.bincount(case.problem.observations.step, minlength=case.problem.grid.n) > 0
    assert sigma_x[seen].max() < 0.02 and sigma_x[~seen].max() > 10 * sigma_x[seen].max()
    mid = np.argmax(sigma_x)
    assert not seen[mid] and abs(mid - len(sigma_x) / 2) < 0.15 * len(sigma_x)


def test_the_one_pass_barrier_kernel_equals_the_samples_and_the_scatter(walk_with_wall):
    """``barrier_terms.add_barrier_terms`` (the solver's) against ``barrier_samples`` + ``add_pair_terms``
    (its reference, each tested against NumPy): the same numbers bit for bit, near the block and beyond the grid."""
    from worldtrack.trajectory.barrier_terms import Hinge, Normal, add_barrier_terms
    problem = walk_with_wall.problem
    env = problem.environment
    b, f = env.barrier, env.barrier.field
    X = straight_start(problem.observations, problem.grid, 1.7)
    X[:, 2] += 0.3 * np.sin(np.arange(len(X)) / 9.0)
    X[-8:, 0] += 4.0                                          # the last steps beyond the grid's edge at x = 4.95 m
    step, alpha = b.samples(len(X))
    gain = np.sqrt(env.weight / b.substeps) / b.scale
    field = (f.values, np.asarray(f.origin, dtype=float), float(f.resolution))
    r, J, d, curvature = kernels.barrier_samples(X, step, alpha, problem.grid.dt, *field, b.clearance, b.softness, gain)
    assert np.sum(r > 0) > 20 and np.sum(r == 0) > 20 and np.sum(d < b.clearance) > 5 and d.min() < 0
    rng = np.random.default_rng(5)
    start = [rng.normal(size=(len(X), 6, 6)), rng.normal(size=(len(X) - 1, 6, 6)), rng.normal(size=(len(X), 6))]
    two = [a.copy() for a in start]
    kernels.add_pair_terms(*two, step, J, r, curvature)
    one = Normal(*(a.copy() for a in start))
    r1, d1, inside = np.empty(len(step)), np.empty(len(step)), np.zeros(len(X), dtype=bool)
    add_barrier_terms(X, step, alpha, problem.grid.dt, *field, Hinge(b.clearance, b.softness, gain), one, r1, d1,
                      inside, np.empty(0))
    for x, y in zip(one, two):
        np.testing.assert_array_equal(x, y)
    np.testing.assert_array_equal(r1, r)
    np.testing.assert_array_equal(d1, d)
    np.testing.assert_array_equal(inside, np.isin(np.arange(len(X)), step[d < b.clearance]))
    lin = linearise(problem, X)                               # and the linearisation keeps them
    np.testing.assert_array_equal(lin.barrier_d, d)
    assert lin.costs.barrier == float(r @ r)


def test_samples_that_moved_away_take_the_outward_curvature_factor(walk_with_wall):
    """``Hinge.outward`` (``SolverOptions.outward_curvature``): the samples whose distance grew by more than
    ``OUTWARD_MOVE`` since ``d_before`` enter D with that factor instead of Newton's; the rest, r and g unchanged."""
    from worldtrack.trajectory.barrier_terms import OUTWARD_MOVE, Hinge, Normal, add_barrier_terms
    problem = walk_with_wall.problem
    env = problem.environment
    b, f = env.barrier, env.barrier.field
    X = straight_start(problem.observations, problem.grid, 1.7)
    X[:, 2] += 0.3 * np.sin(np.arange(len(X)) / 9.0)
    step, alpha = b.samples(len(X))
    gain = np.sqrt(env.weight / b.substeps) / b.scale
    field = (f.values, np.asarray(f.origin, dtype=float), float(f.resolution))
    r, J, d, curvature = kernels.barrier_samples(X, step, alpha, problem.grid.dt, *field, b.clearance, b.softness, gain)
    away = np.arange(len(d)) % 3 == 0                         # every third sample "moved away"
    before = np.where(away, d - 2 * OUTWARD_MOVE, d - 0.5 * OUTWARD_MOVE)
    zeros = lambda: [np.zeros((len(X), 6, 6)), np.zeros((len(X) - 1, 6, 6)), np.zeros((len(X), 6))]  # noqa: E731
    expected = zeros()
    kernels.add_pair_terms(*expected, step, J, r, np.where(away, 1.3, curvature))
    got = Normal(*zeros())
    r1, d1, inside = np.empty(len(step)), np.empty(len(step)), np.zeros(len(X), dtype=bool)
    add_barrier_terms(X, step, alpha, problem.grid.dt, *field, Hinge(b.clearance, b.softness, gain, 1.3), got, r1, d1,
                      inside, before)
    assert np.sum(away & (r > 0)) > 10 and np.sum(~away & (r > 0)) > 10
    for x, y in zip(got, expected):
        np.testing.assert_allclose(x, y, rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(r1, r)
    newton = zeros()
    kernels.add_pair_terms(*newton, step, J, r, curvature)
    lin, plain = linearise(problem, X, outward=(before, 1.3)), linearise(problem, X)   # passed on by linearise
    np.testing.assert_allclose(lin.D - plain.D, got.D - newton[0], rtol=0, atol=1e-9 * np.abs(plain.D).max())
    np.testing.assert_array_equal(lin.g, plain.g)
    assert lin.costs.total == plain.costs.total
