"""Levenberg–Marquardt over all kept candidates at once (seed 003, eqs. 6–7 and 20).

Each candidate ``k`` is refined by ``p ← p − (JᵀJ + C_k·I)⁻¹·Jᵀr`` (eq. 6). The damping ``C_k``
starts at 1e-5 and is adapted per candidate: a step that lowers ``ε = rᵀr`` is taken and ``C``
divided by 10; a step that does not is refused and ``C`` multiplied by 10 (large ``C`` far from the
optimum, small near it, as §2.5 says).

The parameters are increments on a *pose space* (:class:`PoseSpace`): ``retract(X, δ)`` applies
``δ`` to states ``X``; the Jacobian is taken at ``δ = 0`` — by central differences (eq. 20), all
``2M`` shifted copies of all K candidates evaluated in one call, or by an analytic function (the
face's eq. 10, :mod:`worldtrack.pose.jacobian`). :func:`lm_reference` is the same algorithm one
candidate at a time, written for reading.
"""

from __future__ import annotations

from typing import Callable, NamedTuple, Protocol

import numpy as np

Residuals = Callable[[np.ndarray], np.ndarray]                # states (K, S) → r (K, N)
Jacobian = Callable[[np.ndarray, np.ndarray], np.ndarray]     # states, r → J (K, N, M)
NormalEquations = Callable[[np.ndarray], tuple]               # states → (JᵀJ (K,M,M), Jᵀr (K,M), ε (K,))


class PoseSpace(Protocol):
    """States of a pose model and their increments."""

    dim: int                                                   # M, length of an increment
    fd_step: np.ndarray                                        # (M,) central-difference steps ε

    def retract(self, X: np.ndarray, delta: np.ndarray) -> np.ndarray: ...

    def transforms(self, X: np.ndarray) -> np.ndarray: ...     # (K, P, 3, 4) part → camera


class LMResult(NamedTuple):
    """``states`` (K, S) refined; ``cost`` (K,) ε = rᵀr; ``damping`` (K,) final C; ``accepted`` (K,)
    number of steps taken; ``history`` (iterations + 1, K) ε after each iteration."""

    states: np.ndarray
    cost: np.ndarray
    damping: np.ndarray
    accepted: np.ndarray
    history: np.ndarray


def central_difference_jacobian(space: PoseSpace, residuals: Residuals, X: np.ndarray) -> np.ndarray:
    """(K, N, M) ``∂r/∂δ_n ≈ (r(X ⊕ ε e_n) − r(X ⊖ ε e_n)) / 2ε`` (eq. 20), in one batched call."""
    K, M = len(X), space.dim
    E = np.eye(M) * space.fd_step                              # (M, M) rows ε_n e_n
    D = np.concatenate([E, -E])                                # (2M, M)
    Xs = space.retract(np.repeat(X, 2 * M, axis=0), np.tile(D, (K, 1)))
    R = residuals(Xs).reshape(K, 2 * M, -1)
    return np.moveaxis((R[:, :M] - R[:, M:]) / (2 * space.fd_step[None, :, None]), 1, 2)


def levenberg_marquardt(space: PoseSpace, residuals: Residuals, X0: np.ndarray, iterations: int,
                        jacobian: Jacobian | None = None, damping: float = 1e-5,
                        normal_equations: NormalEquations | None = None,
                        epsilon: Callable[[np.ndarray], np.ndarray] | None = None, tol: float = 0.0) -> LMResult:
    """Refine K candidate states together.

    Parameters
    ----------
    space : PoseSpace
    residuals : states (K, S) → (K, N) residuals r
    X0 : (K, S) starting states
    iterations : number of LM iterations (0 returns X0 with its cost)
    jacobian : optional analytic Jacobian ``(X, r) → (K, N, M)``; default central differences
    damping : initial C (1e-5)
    normal_equations, epsilon : optional compiled ``X → (JᵀJ, Jᵀr, ε)`` and ``X → ε``; with them
        no residual matrix is formed (the face's fused kernel)
    tol : with ``normal_equations``: a candidate whose accepted step lowered ε by less than ``tol``,
        or whose step is refused at a damping above 10× JᵀJ's largest diagonal element, has
        converged and is left as it is (0: always
        ``iterations`` steps, as the paper)

    Returns
    -------
    LMResult
    """
    X = np.array(X0, float)
    if normal_equations is not None:
        return _lm_normal(space, normal_equations, epsilon, X, iterations, damping, tol)
    r = residuals(X)
    cost = (r * r).sum(1)
    C = np.full(len(X), float(damping))
    taken = np.zeros(len(X), int)
    history = [cost.copy()]
    M = space.dim
    jac = jacobian if jacobian is not None else lambda X_, r_: central_difference_jacobian(space, residuals, X_)
    J, moved = None, np.ones(len(X), bool)
    for _ in range(int(iterations)):
        if J is None:
            J = jac(X, r)
        elif moved.any():                   # a rejected step leaves X, hence J, as it was: recompute the rest
            J[moved] = jac(X[moved], r[moved])
        Jt = np.swapaxes(J, 1, 2)
        A = Jt @ J + C[:, None, None] * np.eye(M)                          # JᵀJ + C·I
        g = (Jt @ r[..., None])[..., 0]                                    # Jᵀr
        delta = -np.linalg.solve(A, g[..., None])[..., 0]
        X_try = space.retract(X, delta)
        r_try = residuals(X_try)
        cost_try = (r_try * r_try).sum(1)
        better = cost_try < cost
        X[better], r[better], cost[better] = X_try[better], r_try[better], cost_try[better]
        C = np.where(better, C / 10.0, C * 10.0)
        taken += better
        moved = better
        history.append(cost.copy())
    return LMResult(X, cost, C, taken, np.array(history))


def _lm_normal(space: PoseSpace, normal_equations: NormalEquations, epsilon, X: np.ndarray, iterations: int,
               damping: float, tol: float = 0.0) -> LMResult:
    """:func:`levenberg_marquardt` driven by compiled normal equations. With ``tol > 0`` a candidate
    stops (its state and ε kept) once an accepted step lowers ε by less than ``tol``, or a step is
    refused although the damping ``C`` already exceeds 10× JᵀJ's largest diagonal element (a short
    gradient step that does not descend) — it has converged; the others go on."""
    C = np.full(len(X), float(damping))
    taken = np.zeros(len(X), int)
    active = np.ones(len(X), bool)
    A0, g, cost = normal_equations(X)
    history = [cost.copy()]
    eye = np.eye(space.dim)
    for it in range(int(iterations)):
        a = np.flatnonzero(active)
        if len(a) == 0:
            history.append(cost.copy())
            continue
        delta = -np.linalg.solve(A0[a] + C[a, None, None] * eye, g[a, :, None])[..., 0]   # eq. 6
        X_try = space.retract(X[a], delta)
        cost_try = epsilon(X_try)
        ok = cost_try < cost[a]
        better = a[ok]
        gain = cost[better] - cost_try[ok]
        X[better], cost[better] = X_try[ok], cost_try[ok]
        C[a] = np.where(ok, C[a] / 10.0, C[a] * 10.0)
        taken[better] += 1
        if tol > 0:
            active[better[gain < tol]] = False
            stuck = a[~ok]
            active[stuck[C[stuck] > 10.0 * np.diagonal(A0[stuck], axis1=1, axis2=2).max(1)]] = False
        history.append(cost.copy())
        renew = better[active[better]]
        if len(renew) and it + 1 < iterations:
            A0n, gn, _ = normal_equations(X[renew])
            A0[renew], g[renew] = A0n, gn
    return LMResult(X, cost, C, taken, np.array(history))


def lm_reference(space: PoseSpace, residuals: Residuals, x0: np.ndarray, iterations: int,
                 damping: float = 1e-5) -> tuple[np.ndarray, float]:
    """One candidate, plain loops, central differences: the algorithm as the paper states it."""
    x = np.array(x0, float)[None]
    C = damping
    r = residuals(x)[0]
    for _ in range(int(iterations)):
        J = np.empty((len(r), space.dim))
        for n in range(space.dim):                              # eq. 20
            e = np.zeros((1, space.dim))
            e[0, n] = space.fd_step[n]
            J[:, n] = (residuals(space.retract(x, e))[0] - residuals(space.retract(x, -e))[0]) / (2 * space.fd_step[n])
        step = -np.linalg.solve(J.T @ J + C * np.eye(space.dim), J.T @ r)   # eq. 6
        x_try = space.retract(x, step[None])
        r_try = residuals(x_try)[0]
        if r_try @ r_try < r @ r:
            x, r, C = x_try, r_try, C / 10.0
        else:
            C *= 10.0
    return x[0], float(r @ r)
