"""Feet pixels (beyond the paper): the floor point below the head, seen with it, makes the head
height observable. Exact geometry of the term and the solver with it, and the height it recovers."""

import numpy as np
import pytest

from worldtrack.errors import InputError
from worldtrack.geometry.camera import Camera
from worldtrack.trajectory.estimate import TrajectoryOptions, estimate_trajectory
from worldtrack.trajectory.model import dense_from_blocks
from worldtrack.trajectory.objective import evaluate, linearise
from worldtrack.trajectory.observation import Observations
from worldtrack.trajectory.solver import (dense_objective, jacobian_dense, levenberg_marquardt, residual_vector,
                                          solve_dense)
from worldtrack.trajectory.starts import straight_start

from _trajectory_cases import observed_walk


def test_the_feet_term_projects_the_floor_point_below_the_head():
    case = observed_walk(T=81, noise_px=0.0, feet=True)
    feet = case.problem.feet
    assert feet is not None and feet.floor and len(feet.obs) == int(case.obs.has_feet.sum()) > 0
    X = np.zeros((case.problem.grid.n, 6))
    X[:, [0, 2, 4]] = case.truth
    X[:, 1] = np.gradient(case.truth[:, 0], 0.1)
    r, J, _ = feet.residuals(X)
    assert np.abs(r).max() < 0.02 * 2                   # noise-free feet: the truth (up to ẋ·τ) fits them
    assert np.all(J[:, :, [4, 5]] == 0)                 # the floor point does not depend on w, ẇ
    cam = case.obs.cameras[feet.obs.camera[0]]
    p = X[feet.step[0], [0, 2, 4]] * [1, 1, 0] + feet.tau[0] * X[feet.step[0], [1, 3, 5]] * [1, 1, 0]
    np.testing.assert_allclose(r[0] * 1.5 + feet.obs.uv[0], cam.project(p[None])[0], atol=1e-9)


def test_the_feet_jacobian_matches_finite_differences():
    case = observed_walk(T=41, noise_px=1.0, feet=True)
    problem = case.problem
    X = straight_start(problem.observations, problem.grid, 1.7)
    X[:, 4] += 0.2
    _, J, _ = problem.feet.residuals(X)
    h = 1e-6
    for k in range(0, len(problem.feet.step), 3):
        t = problem.feet.step[k]
        for c in range(6):
            Xp, Xm = X.copy(), X.copy()
            Xp[t, c] += h
            Xm[t, c] -= h
            num = (problem.feet.residuals(Xp, False)[0][k] - problem.feet.residuals(Xm, False)[0][k]) / (2 * h)
            np.testing.assert_allclose(J[k, :, c], num, rtol=1e-6, atol=1e-6)
    Jd = jacobian_dense(problem, X)                    # the dense reference stacks the same rows
    assert Jd.shape[0] == len(residual_vector(problem, X))


def test_with_feet_the_normal_equations_are_j_transpose_j_and_the_banded_lm_equals_least_squares():
    case = observed_walk(T=81, seed=5, feet=True)
    problem = case.problem
    X0 = straight_start(problem.observations, problem.grid, 1.7)
    lin = linearise(problem, X0)
    J, r = jacobian_dense(problem, X0), residual_vector(problem, X0)
    assert lin.costs.total == pytest.approx(r @ r, rel=1e-12) == pytest.approx(evaluate(problem, X0).total)
    np.testing.assert_allclose(lin.g.ravel(), J.T @ r, rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(dense_from_blocks(lin.D, lin.B), J.T @ J, rtol=1e-10, atol=1e-6)
    ours = levenberg_marquardt(problem, X0)
    ref = solve_dense(problem, X0)
    assert ours.converged
    assert abs(ours.costs.total - dense_objective(problem, ref)) <= 1e-9 * dense_objective(problem, ref)
    assert np.abs(ours.X[:, [0, 2, 4]] - ref[:, [0, 2, 4]]).max() < 1e-6


def test_feet_pixels_reveal_a_head_height_that_head_pixels_alone_cannot():
    """A 1.90 m person estimated with the default 1.70 m: head pixels alone keep the prior's height
    (a homothety about each camera's nadir fits them as well); with the feet it is fitted."""
    case = observed_walk(T=81, seed=2, noise_px=1.0, feet=True, height=1.90)
    head_only = Observations(case.obs.time, case.obs.camera, case.obs.uv, case.obs.sigma, case.obs.cameras)
    options = TrajectoryOptions(dt=0.1, height=1.70, fit_height=True)
    blind = estimate_trajectory(head_only, None, options)
    seeing = estimate_trajectory(case.obs, None, options)
    seen = seeing.observed > 0
    assert np.abs(blind.positions[seen, 2] - case.truth[seen, 2]).mean() > 0.1
    assert seeing.height == pytest.approx(1.90, abs=0.03)
    assert np.sqrt(np.mean((seeing.positions[seen, 2] - case.truth[seen, 2]) ** 2)) < 0.03
    assert np.sqrt(np.mean(np.sum((seeing.positions[seen, :2] - case.truth[seen, :2]) ** 2, axis=1))) < 0.03


def test_half_a_feet_pixel_is_refused():
    cam = Camera.look_at("c", 320, 240, position=(0, 0, 3), target=(0, 0.4, 0), hfov_deg=70)
    with pytest.raises(InputError, match="u_feet and v_feet"):
        Observations.from_rows([0.0, 0.1], ["c", "c"], [[160, 120], [161, 120]], {"c": cam},
                               feet_uv=[[160, 200], [np.nan, 200]])
