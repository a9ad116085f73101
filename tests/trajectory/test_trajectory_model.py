"""The motion prior, the time grid and the projection Jacobians (seed 002, eqs. 1–5, 7)."""

import numpy as np
import pytest

from worldtrack.errors import InputError
from worldtrack.trajectory.model import (MotionPrior, TimeGrid, dense_from_blocks, frame_interval, motion_blocks,
                                         motion_residuals)
from worldtrack.trajectory.observation import Observations, ObservationTerm, project_with_jacobian

from _trajectory_cases import ceiling_cameras


def test_time_grid_covers_the_observations_and_locates_off_grid_times():
    grid = TimeGrid.covering([2.0, 2.33, 3.02], dt=0.1)
    assert grid.n == 12 and grid.times[0] == 2.0 and grid.times[-1] >= 3.02 - 1e-9
    step, tau = grid.locate([2.0, 2.33, 3.02])
    np.testing.assert_array_equal(step, [0, 3, 10])
    np.testing.assert_allclose(grid.times[step] + tau, [2.0, 2.33, 3.02])
    assert np.all(np.abs(tau) <= 0.05 + 1e-12)


def test_frame_interval_is_the_fastest_cameras_median_gap():
    t = [0.0, 0.04, 0.08, 0.12, 9.0, 9.1, 9.2]
    assert frame_interval(t, [0, 0, 0, 0, 1, 1, 1]) == 0.04
    with pytest.raises(InputError, match="single time stamp"):
        frame_interval([1.0, 1.0], [0, 1])


def test_lambda_x_is_the_sum_of_squared_whitened_motion_residuals():
    """Eq. 9's XᵀΛ_X X with Σ read as Σ_υ⁻¹ equals Σ_t ‖W(x_{t+1} − A x_t)‖², and the whitener whitens."""
    prior = MotionPrior(0.7, 0.03)
    dt, n = 0.25, 7
    A, W = prior.transition(dt), prior.whitener(dt)
    np.testing.assert_allclose(W @ prior.noise(dt) @ W.T, np.eye(6), atol=1e-9)
    X = np.random.default_rng(1).normal(size=(n, 6))
    r = motion_residuals(X, A, W)
    D, B = motion_blocks(A, W, n)
    Lam = dense_from_blocks(D, B)
    assert X.ravel() @ Lam @ X.ravel() == pytest.approx(np.sum(r * r), rel=1e-12)
    # a constant-velocity trajectory costs nothing
    cv = np.zeros((n, 6))
    cv[:, 1], cv[:, 0] = 1.3, 1.3 * dt * np.arange(n)
    assert np.abs(motion_residuals(cv, A, W)).max() < 1e-9


def test_motion_noise_is_the_white_noise_acceleration_covariance():
    Q = MotionPrior(2.0, 0.5).noise(0.1)
    np.testing.assert_allclose(Q[:2, :2], 2.0 * np.array([[1e-3 / 3, 5e-3], [5e-3, 0.1]]))
    np.testing.assert_allclose(Q[4:, 4:], 0.5 * np.array([[1e-3 / 3, 5e-3], [5e-3, 0.1]]))
    with pytest.raises(InputError, match="q_vertical"):
        MotionPrior(1.0, 0.0)


def test_projection_and_its_jacobian_match_the_camera_and_finite_differences():
    cam = ceiling_cameras()["a"]
    pts = np.array([[0.3, 0.2, 1.7], [-0.6, 0.9, 1.5], [0.8, -0.4, 1.9]])
    uv, J, depth = project_with_jacobian(cam, pts)
    np.testing.assert_allclose(uv, cam.project(pts), atol=1e-9)
    np.testing.assert_allclose(depth, cam.depth(pts), atol=1e-12)
    h = 1e-6
    numeric = np.stack([(cam.project(pts + h * e) - cam.project(pts - h * e)) / (2 * h) for e in np.eye(3)], axis=2)
    np.testing.assert_allclose(J, numeric, rtol=1e-6, atol=1e-4)
    assert cam.has_distortion


def test_an_off_grid_observation_is_predicted_from_position_and_velocity():
    cams = ceiling_cameras()
    p = np.array([[0.2, 0.1, 1.7]])
    obs = Observations.from_points([0.13], ["a"], p, cams)          # between steps 0.1 and 0.2
    term = ObservationTerm.on_grid(obs, TimeGrid(0.0, 0.1, 3))
    X = np.zeros((3, 6))
    X[1, [0, 2, 4]] = p[0] - 0.03 * np.array([1.0, -2.0, 0.0])      # at t = 0.1 s, moving (1, −2, 0) m/s
    X[1, [1, 3, 5]] = [1.0, -2.0, 0.0]
    r, J, _ = term.residuals(X)
    assert np.abs(r).max() < 1e-6                                     # p_k + τ·ṗ_k is the observed point
    assert term.step[0] == 1 and term.tau[0] == pytest.approx(0.03)
    np.testing.assert_allclose(J[0][:, [1, 3, 5]], 0.03 * J[0][:, [0, 2, 4]])


def test_observations_name_an_unknown_camera():
    with pytest.raises(InputError, match="unknown camera 'c'"):
        Observations.from_rows([0.0], ["c"], [[1.0, 2.0]], ceiling_cameras())
