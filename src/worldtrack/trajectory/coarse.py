"""Coarse to fine: the MAP with the barrier first on every m-th step of the grid, then on every step.

With the barrier, Levenberg–Marquardt from the shortest-path start spends most of its iterations
moving paths by metres, 0.25 m at a time (the step limit the hinge needs, 34g's trace). Those
iterations cost less on a coarser grid: here the same problem is posed on the grid
``t0 + k·m·dt`` (:func:`coarse_grid`), solved there from the starts subsampled, brought back to
every step by the motion model's own interpolation (:func:`refine`), and polished by
Levenberg–Marquardt on the full grid.

The coarse problem is the same model, not an approximation of it chosen by hand:

- the motion prior of :class:`~.model.MotionPrior` re-derived for the step m·dt from the same
  spectral densities (white-noise acceleration: the prior of every m-th state of the fine chain is
  exactly the coarse chain's);
- every observation on its nearest coarse step, with its time offset τ (|τ| ≤ m·dt/2), as on the fine
  grid (the head at x_k + τ·ẋ_k);
- the barrier with as many samples per coarse step as :meth:`~.environment.Barrier.substeps_for`
  asks for the longer step, on the same cubic Hermite curves.

Between two coarse states the fine states are the conditional mean of the Gauss–Markov process
given both (:func:`interpolation_gains`: the Gaussian-process interpolation of a linear SDE prior,
Barfoot, Tong & Särkkä 2014, "Batch continuous-time trajectory estimation as exactly sparse
Gaussian process regression", eq. 21); for white-noise acceleration it is the cubic Hermite curve
through the two states and its derivative.

It is an option (``TrajectoryOptions(coarse_steps=m)``), not the default: see the option's notes.
"""

from __future__ import annotations

import numpy as np

from worldtrack.errors import InputError
from worldtrack.trajectory.model import STATE, MotionPrior, TimeGrid


def coarse_grid(grid: TimeGrid, factor: int) -> TimeGrid:
    """Every ``factor``-th step of ``grid`` (s), extended by at most one coarse step to cover its end.

    >>> g = coarse_grid(TimeGrid(0.0, 0.1, 11), 4)
    >>> g.n, g.dt, float(g.times[-1])
    (4, 0.4, 1.2000000000000002)
    """
    if int(factor) != factor or factor < 2:
        raise InputError(f"coarse_steps: expected an integer ≥ 2 fine steps per coarse step, got {factor}")
    factor = int(factor)
    return TimeGrid(grid.t0, grid.dt * factor, int(np.ceil((grid.n - 1) / factor)) + 1)


def interpolation_gains(motion: MotionPrior, dt: float, factor: int) -> tuple[np.ndarray, np.ndarray]:
    """Λ_j, Ψ_j (factor, 6, 6): E[x(t_k + j·dt/factor) | x_k, x_{k+1}] = Λ_j·x_k + Ψ_j·x_{k+1}.

    For the linear prior x(t + s) = Φ(s)·x(t) + υ(s), υ(s) ~ N(0, Q(s)) (``transition``, ``noise``):
    Ψ = Q(τ)·Φ(h − τ)ᵀ·Q(h)⁻¹ and Λ = Φ(τ) − Ψ·Φ(h), h = ``dt`` (the coarse step, s), τ = j·h/factor.

    >>> L, P = interpolation_gains(MotionPrior(), 0.4, 4)
    >>> x0 = np.array([0.0, 1.0, 0.0, 0.0, 1.7, 0.0]); x1 = x0 + 0.4 * np.r_[1.0, 0, 0, 0, 0, 0]
    >>> np.round(L[2] @ x0 + P[2] @ x1, 12)       # constant velocity: halfway is halfway
    array([0.2, 1. , 0. , 0. , 1.7, 0. ])
    """
    Phi_h, Q_h_inv = motion.transition(dt), np.linalg.inv(motion.noise(dt))
    Lam = np.zeros((factor, STATE, STATE))
    Psi = np.zeros((factor, STATE, STATE))
    Lam[0] = np.eye(STATE)
    for j in range(1, factor):
        tau = j * dt / factor
        Psi[j] = motion.noise(tau) @ motion.transition(dt - tau).T @ Q_h_inv
        Lam[j] = motion.transition(tau) - Psi[j] @ Phi_h
    return Lam, Psi


def subsample(X: np.ndarray, factor: int, n_coarse: int) -> np.ndarray:
    """(n_coarse, 6): the states of X (n, 6) at every ``factor``-th step (the last one where the coarse
    grid runs past the fine grid's end)."""
    return X[np.minimum(np.arange(n_coarse) * factor, len(X) - 1)].copy()


def refine(Xc: np.ndarray, motion: MotionPrior, dt: float, factor: int, n: int) -> np.ndarray:
    """(n, 6) the states on the fine grid (step ``dt``/``factor``) between coarse states Xc (n_c, 6) on
    the grid of step ``dt`` (s): the prior's conditional mean given the two coarse neighbours."""
    Lam, Psi = interpolation_gains(motion, dt, factor)
    k = np.arange(n)
    left = np.minimum(k // factor, len(Xc) - 2)
    j = k - left * factor                       # 0 … factor − 1 (factor on the last step if n − 1 = factor·(n_c − 1))
    out = np.empty((n, STATE))
    for jj in range(factor + 1):
        sel = j == jj
        if jj == factor:                        # the last coarse state itself
            out[sel] = Xc[left[sel] + 1]
        elif sel.any():
            out[sel] = np.einsum("ij,nj->ni", Lam[jj], Xc[left[sel]]) + np.einsum("ij,nj->ni", Psi[jj], Xc[left[sel] + 1])
    return out
