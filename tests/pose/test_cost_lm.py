"""Geman–McClure residuals, the eigen-template projection, colour/depth terms, and LM."""

import numpy as np
import pytest
from scipy.optimize import least_squares

from worldtrack.pose.cost import ColourDepthCost, EigenTemplateCost, SparseTemplate, geman_mcclure, robust_residual
from worldtrack.pose.lm import central_difference_jacobian, levenberg_marquardt, lm_reference
from worldtrack.pose.models import quat_from_q123, quat_matrix, retract, rigid_state, state_pose
from worldtrack.pose.render import Intrinsics
from worldtrack.pose.rigid import RigidSpace


def test_residual_squares_to_geman_mcclure():
    d = np.array([-30.0, -1.0, 0.0, 2.5, 100.0])
    np.testing.assert_allclose(robust_residual(d, 4.0) ** 2, geman_mcclure(d, 4.0))   # eqs. 3 and 5
    assert geman_mcclure(np.array([4.0]), 4.0)[0] == pytest.approx(0.5)
    assert robust_residual(np.array([np.nan]), 4.0)[0] == 1.0


def test_quaternion_matrix_is_fig4_rotation():
    q = quat_from_q123(np.array([0.1, -0.2, 0.3]))
    assert q[0] == pytest.approx(np.sqrt(1 - 0.14))                                       # eq. 9
    R = quat_matrix(q)
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(R) == pytest.approx(1.0)
    # a rotation by θ about z has q = (cos θ/2, 0, 0, sin θ/2)
    th = 0.4
    np.testing.assert_allclose(quat_matrix([np.cos(th / 2), 0, 0, np.sin(th / 2)])[:2, :2],
                               [[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]], atol=1e-12)


def test_eigen_residual_is_zero_inside_the_subspace():
    rng = np.random.default_rng(0)
    basis = rng.normal(size=(50, 3))
    cost = EigenTemplateCost(SparseTemplate(np.zeros((50, 3)), np.zeros(50, int), np.zeros(50)), basis,
                             np.zeros((4, 4), np.float32), Intrinsics(1, 1, 0, 0, 4, 4))
    inside = basis @ np.array([2.0, -1.0, 0.5])
    outside = rng.normal(size=50)
    assert np.abs(cost.differences(inside[None])).max() < 1e-9                            # (Φ̃Φ̃⁺ − I)·V
    d = cost.differences(outside[None])[0]
    assert np.abs(basis.T @ d).max() < 1e-9 and np.linalg.norm(d) > 1.0


def test_colour_term_ignores_brightness():
    I = np.array([50.0, 120.0, 200.0, 80.0])
    cost = ColourDepthCost(SparseTemplate(np.zeros((4, 3)), np.zeros(4, int), I), None,
                           np.zeros((4, 4), np.float32), None, Intrinsics(1, 1, 0, 0, 4, 4))
    assert cost.c == pytest.approx(0.5 / 4)                                                # c = 0.5/N
    np.testing.assert_allclose(cost.colour_differences((1.7 * I)[None]), 0.0, atol=1e-12)  # eq. 16: β absorbs gain
    assert np.abs(cost.colour_differences((I[::-1])[None])).max() > 0.05


class _PointCloud:
    """A toy problem: a rigid state observed through the projections of 30 known points."""

    def __init__(self, rng):
        self.space = RigidSpace(length=0.1)
        self.points = rng.normal(0, 0.05, (30, 3))
        self.truth = rigid_state(np.eye(3), np.array([0.01, -0.02, 0.6]))
        self.target = self.project(self.truth[None])[0]

    def project(self, X):
        R, t = state_pose(X)
        P = self.points @ np.swapaxes(R, 1, 2) + t[:, None]
        return (500 * P[..., :2] / P[..., 2:]).reshape(len(X), -1)

    def residuals(self, X):
        d = self.project(X) - self.target
        return robust_residual(d, 2.0)


def test_batched_lm_converges_like_scipy_least_squares():
    rng = np.random.default_rng(4)
    prob = _PointCloud(rng)
    X0 = prob.space.retract(np.repeat(prob.truth[None], 6, 0), rng.normal(0, 0.02, (6, 6)))
    res = levenberg_marquardt(prob.space, prob.residuals, X0, 30)
    for k in range(6):
        fun = lambda p: prob.residuals(retract(X0[k][None], p[None], prob.space.length))[0]
        sp = least_squares(fun, np.zeros(6), method="lm")
        x_sp = retract(X0[k], sp.x, prob.space.length)
        np.testing.assert_allclose(res.states[k, :3], x_sp[:3], atol=1e-6)
        np.testing.assert_allclose(np.abs(res.states[k, 3:] @ x_sp[3:]), 1.0, atol=1e-9)
        assert res.cost[k] == pytest.approx(2 * sp.cost, abs=1e-9)          # scipy's cost is ½ rᵀr
    np.testing.assert_allclose(res.states[:, :3], np.repeat(prob.truth[None, :3], 6, 0), atol=1e-6)
    assert (np.diff(res.history, axis=0) <= 1e-12).all()                    # ε never rises


def test_reference_lm_agrees_with_batched():
    rng = np.random.default_rng(5)
    prob = _PointCloud(rng)
    X0 = prob.space.retract(prob.truth[None], rng.normal(0, 0.02, (1, 6)))
    x_ref, cost_ref = lm_reference(prob.space, prob.residuals, X0[0], 8)
    res = levenberg_marquardt(prob.space, prob.residuals, X0, 8)
    np.testing.assert_allclose(res.states[0], x_ref, atol=1e-10)
    assert res.cost[0] == pytest.approx(cost_ref)


def test_central_differences_match_a_finer_estimate():
    rng = np.random.default_rng(6)
    prob = _PointCloud(rng)
    X = prob.space.retract(prob.truth[None], rng.normal(0, 0.01, (1, 6)))
    J = central_difference_jacobian(prob.space, prob.residuals, X)[0]
    h = 1e-6
    for n in range(6):
        e = np.zeros((1, 6))
        e[0, n] = h
        fd = (prob.residuals(prob.space.retract(X, e)) - prob.residuals(prob.space.retract(X, -e)))[0] / (2 * h)
        np.testing.assert_allclose(J[:, n], fd, rtol=1e-3, atol=1e-3 * np.abs(fd).max())


def test_lm_tolerance_stops_converged_candidates_only():
    """With ``tol`` a candidate stops once its steps gain less than tol; the result is the same
    minimum, reached with fewer cost evaluations (the normal-equation path the face uses)."""
    from worldtrack.pose.lm import central_difference_jacobian

    rng = np.random.default_rng(7)
    prob = _PointCloud(rng)
    X0 = prob.space.retract(np.repeat(prob.truth[None], 5, 0), rng.normal(0, 0.02, (5, 6)))
    X0[0] = prob.truth                                                   # already at the minimum

    def normal(X):
        J = central_difference_jacobian(prob.space, prob.residuals, X)
        r = prob.residuals(X)
        return np.swapaxes(J, 1, 2) @ J, (np.swapaxes(J, 1, 2) @ r[..., None])[..., 0], (r * r).sum(1)

    rows = []

    def eps(X):
        rows.append(len(X))
        r = prob.residuals(X)
        return (r * r).sum(1)

    full = levenberg_marquardt(prob.space, prob.residuals, X0, 30, normal_equations=normal, epsilon=eps)
    n_full, rows[:] = sum(rows), []
    fast = levenberg_marquardt(prob.space, prob.residuals, X0, 30, normal_equations=normal, epsilon=eps, tol=1e-10)
    assert sum(rows) < n_full / 2
    np.testing.assert_allclose(fast.states[:, :3], full.states[:, :3], atol=1e-7)
    np.testing.assert_allclose(fast.states[:, :3], np.repeat(prob.truth[None, :3], 5, 0), atol=1e-6)
    assert (fast.cost < 1e-8).all() and (np.diff(fast.history, axis=0) <= 1e-12).all()
