"""The dense reference of the banded solver: every residual stacked into one vector with a dense Jacobian,
handed to ``scipy.optimize.least_squares``. Small problems only (T of a few hundred); the tests check that
:mod:`.solver` reaches the same optimum. (Moved out of :mod:`.solver`, which re-exports these names.)
"""

from __future__ import annotations

import numpy as np
import scipy.optimize

from worldtrack.trajectory.environment import barrier_residuals, height_residuals
from worldtrack.trajectory.model import STATE, VEL, first_velocity_residuals, motion_residuals
from worldtrack.trajectory.objective import Problem, huber


def residual_vector(problem: Problem, X: np.ndarray) -> np.ndarray:
    """All whitened residuals stacked: motion, observations, every barrier sample, heights.

    Huber residuals enter as r·√ρ(e)/e, whose squared norm is ρ(e): the same objective, so the same
    optimum (not the same Jacobian as the IRLS weights the fast solver uses).
    """
    parts = [motion_residuals(X, problem.A, problem.W).ravel(),
             first_velocity_residuals(X, problem.motion.first_velocity_gain)]
    for term in problem.pixel_terms:
        r, _, _ = term.residuals(X, with_jacobian=False)
        e = np.hypot(r[:, 0], r[:, 1])
        rho, _ = huber(e, problem.robust)
        parts.append((r * (np.sqrt(rho) / np.where(e > 0, e, 1.0))[:, None]).ravel() if problem.robust else r.ravel())
    env = problem.environment
    if env.barrier is not None:
        parts.append(barrier_residuals(X, env.barrier, env.weight, problem.grid.dt, only_active=False).r)
    if env.height is not None:
        parts.append(height_residuals(X, env.height, env.weight)[0])
    return np.concatenate(parts)


def jacobian_dense(problem: Problem, X: np.ndarray) -> np.ndarray:
    """The dense Jacobian of :func:`residual_vector` (plain squares only), row by row as the terms say."""
    n = len(X)
    rows = []
    minus_WA = -problem.W @ problem.A
    for t in range(n - 1):                                    # motion: W·(x_{t+1} − A·x_t)
        block = np.zeros((STATE, STATE * n))
        block[:, STATE * t:STATE * t + STATE] = minus_WA
        block[:, STATE * (t + 1):STATE * (t + 2)] = problem.W
        rows.append(block)
    first = np.zeros((len(VEL), STATE * n))                  # prior on the first velocity
    first[np.arange(len(VEL)), VEL] = problem.motion.first_velocity_gain
    rows.append(first)
    for term in problem.pixel_terms:                          # observations: one state each
        _, J, _ = term.residuals(X)
        for i, k in enumerate(term.step):
            block = np.zeros((2, STATE * n))
            block[:, STATE * k:STATE * k + STATE] = J[i]
            rows.append(block)
    env = problem.environment
    if env.barrier is not None:                               # barrier samples: two states each
        br = barrier_residuals(X, env.barrier, env.weight, problem.grid.dt, only_active=False)
        block = np.zeros((len(br.r), STATE * n))
        for i, t in enumerate(br.step):
            block[i, STATE * t:STATE * t + 2 * STATE] = br.J[i]
        rows.append(block)
    if env.height is not None:                                # height: ∂/∂w_t
        _, gain = height_residuals(X, env.height, env.weight)
        block = np.zeros((n, STATE * n))
        block[np.arange(n), STATE * np.arange(n) + 4] = gain
        rows.append(block)
    return np.vstack(rows)


def solve_dense(problem: Problem, X0: np.ndarray, xtol: float = 1e-8) -> np.ndarray:
    """Reference optimum: ``scipy.optimize.least_squares`` (MINPACK's Levenberg–Marquardt, dense
    Jacobian) on :func:`residual_vector` from X0. Small problems only (T of a few hundred)."""
    shape = np.shape(X0)
    fun = lambda x: residual_vector(problem, x.reshape(shape))  # noqa: E731
    jac = "2-point" if problem.robust else (lambda x: jacobian_dense(problem, x.reshape(shape)))
    sol = scipy.optimize.least_squares(fun, np.asarray(X0, float).ravel(), jac=jac, method="lm",
                                       xtol=xtol, ftol=1e-12, gtol=1e-12)
    return sol.x.reshape(shape)


def dense_objective(problem: Problem, X: np.ndarray) -> float:
    """F(X) from the stacked residuals (equals ``evaluate(problem, X).total``)."""
    r = residual_vector(problem, X)
    return float(r @ r)


__all__ = ["dense_objective", "jacobian_dense", "residual_vector", "solve_dense"]
