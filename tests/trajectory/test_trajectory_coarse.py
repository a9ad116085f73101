"""Coarse to fine (``TrajectoryOptions(coarse_steps=m)``, an option): the coarse grid, the motion prior's own
interpolation between coarse states, and the estimate it leads to on the test office against the default's."""

from dataclasses import replace

import numpy as np
import pytest

from worldtrack.errors import InputError
from worldtrack.trajectory.coarse import coarse_grid, interpolation_gains, refine, subsample
from worldtrack.trajectory.environment import hermite_weights, sample_field
from worldtrack.trajectory.estimate import TrajectoryOptions, build_environment, estimate_trajectory
from worldtrack.trajectory.model import MotionPrior, TimeGrid, frame_interval
from worldtrack.trajectory.objective import Problem
from worldtrack.trajectory.solver import levenberg_marquardt


def test_the_coarse_grid_holds_every_mth_step_and_covers_the_end():
    fine = TimeGrid(2.0, 0.1, 23)
    g = coarse_grid(fine, 4)
    assert (g.t0, g.n) == (2.0, 7) and g.dt == pytest.approx(0.4)
    np.testing.assert_allclose(g.times[:6], fine.times[::4][:6])
    assert g.times[-1] >= fine.times[-1]
    assert coarse_grid(TimeGrid(0.0, 0.1, 9), 4).n == 3               # 8 = 2·4 steps: no extra one
    with pytest.raises(InputError, match="coarse_steps"):
        coarse_grid(fine, 1)
    with pytest.raises(InputError, match="coarse_steps"):
        TrajectoryOptions(coarse_steps=2.5)


def test_the_interpolation_is_the_priors_conditional_mean():
    """Against the Gaussian conditional of the joint prior of (x_k, x(τ), x_{k+1}) written out densely, and,
    for white-noise acceleration, the cubic Hermite curve through the two states (position and velocity)."""
    motion, h, m = MotionPrior(q_horizontal=0.8, q_vertical=0.03), 0.6, 3
    Lam, Psi = interpolation_gains(motion, h, m)
    rng = np.random.default_rng(4)
    x0, x1 = rng.normal(size=6), rng.normal(size=6)
    P0 = np.eye(6) * 5.0                                           # any prior on x_k: the gains do not depend on it
    for j in range(1, m):
        tau = j * h / m
        F1, Q1 = motion.transition(tau), motion.noise(tau)
        F2, Q2 = motion.transition(h - tau), motion.noise(h - tau)
        # joint covariance of (x_k, x_τ, x_{k+1}) with x_τ = F1 x_k + w1, x_{k+1} = F2 x_τ + w2
        C_tt = F1 @ P0 @ F1.T + Q1
        C = np.block([[P0, P0 @ F1.T, P0 @ F1.T @ F2.T],
                      [F1 @ P0, C_tt, C_tt @ F2.T],
                      [F2 @ F1 @ P0, F2 @ C_tt, F2 @ C_tt @ F2.T + Q2]])
        ends = np.r_[0:6, 12:18]
        mean = C[6:12][:, ends] @ np.linalg.solve(C[np.ix_(ends, ends)], np.r_[x0, x1])
        np.testing.assert_allclose(Lam[j] @ x0 + Psi[j] @ x1, mean, atol=1e-9)
        H = hermite_weights(np.array([j / m]), h)[0]
        dH = np.array([6 * (j / m) ** 2 - 6 * (j / m), 3 * (j / m) ** 2 - 4 * (j / m) + 1,
                       -6 * (j / m) ** 2 + 6 * (j / m), 3 * (j / m) ** 2 - 2 * (j / m)]) * np.array([1 / h, 1, 1 / h, 1])
        for p, v in ((0, 1), (2, 3), (4, 5)):
            ends_pv = np.array([x0[p], x0[v], x1[p], x1[v]])
            assert mean[p] == pytest.approx(H @ ends_pv, abs=1e-9)
            assert mean[v] == pytest.approx(dH @ ends_pv, abs=1e-9)


def test_refine_keeps_the_coarse_states_and_subsample_takes_them_back():
    rng = np.random.default_rng(7)
    Xc = rng.normal(size=(6, 6))
    for n in (21, 19):                                        # ends on a coarse step, or before the last one
        X = refine(Xc, MotionPrior(), 0.4, 4, n)
        assert X.shape == (n, 6)
        np.testing.assert_array_equal(X[::4], Xc[:len(X[::4])])
        np.testing.assert_array_equal(subsample(X, 4, len(X[::4])), X[::4])
    assert subsample(np.arange(12.0).reshape(2, 6), 4, 2)[1, 0] == 6.0      # the last fine state for a step past the end
    t = np.arange(21) * 0.1                                   # a walk at constant velocity stays on its line
    line = np.column_stack([1 + 0.8 * t, np.full(21, 0.8), 2 - 1.1 * t, np.full(21, -1.1), np.full(21, 1.7), 0 * t])
    np.testing.assert_allclose(refine(line[::4], MotionPrior(), 0.4, 4, 21), line, atol=1e-12)


@pytest.mark.parametrize("factor", [4, 8])
def test_coarse_to_fine_reaches_the_defaults_optimum_on_the_test_office(office_person, factor):
    """The same start wins (the race on every step picks it), the coarse solve runs, and the polished estimate
    is the default's optimum: both continued to the tolerance 1e-12 agree to 1e-9 in F and 1e-6 m, and the
    estimates themselves to 1e-6 in F (the default stop, 1e-5, is not tighter than that)."""
    obs, field, height = office_person
    options = TrajectoryOptions(height=height)
    default = estimate_trajectory(obs, field, options)
    coarse = estimate_trajectory(obs, field, replace(options, coarse_steps=factor))
    assert coarse.start == default.start == "shortest"
    assert f"on every {factor}th step" in coarse.results["shortest"].message
    assert coarse.results["shortest"].iterations < default.results["shortest"].iterations
    assert coarse.costs["total"] == pytest.approx(default.costs["total"], rel=1e-6)
    assert sample_field(field, coarse.positions[:, :2])[0].min() > 0
    dt = frame_interval(obs.time, obs.camera)
    grid = TimeGrid.covering(obs.time, dt)
    problem = Problem.build(obs, grid, options.motion, build_environment(options, field, dt))
    tight = replace(options.solver, barrier_relative_decrease=1e-12, max_iterations=300)
    a, b = levenberg_marquardt(problem, default.X, tight), levenberg_marquardt(problem, coarse.X, tight)
    assert b.costs.total == pytest.approx(a.costs.total, rel=1e-9)
    assert np.abs(a.X[:, [0, 2, 4]] - b.X[:, [0, 2, 4]]).max() < 1e-6


def test_the_default_does_not_go_coarse(office_person):
    obs, field, height = office_person
    est = estimate_trajectory(obs, field, TrajectoryOptions(height=height))
    assert "every" not in est.results["shortest"].message
