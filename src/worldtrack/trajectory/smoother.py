"""The baseline seed 002 is measured against: a Kalman filter + RTS smoother on the floor.

Every head pixel is back-projected to the person's head height (the plane Z = H), giving a floor
point with the covariance the pixel noise maps to there (J·σ²·Jᵀ, J = ∂(x, y)/∂(u, v) of the
back-projection). A constant-velocity model with the same white-noise acceleration as the MAP's
horizontal prior runs forward over the grid and the observation times, and the Rauch–Tung–Striebel
pass runs back. No environment: between views it follows straight constant-velocity lines.

The few lines are ours, not Stone Soup's ``KalmanSmoother``: that one leaves states that are
predictions only (no update) as the filter had them (dstl/Stone-Soup issue #178), and a gap
between camera views is nothing but such states.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from worldtrack.errors import InputError
from worldtrack.trajectory.model import TimeGrid
from worldtrack.trajectory.observation import Observations


@dataclass
class BaselineEstimate:
    """times (n,) s; xy (n, 2) m; covariance (n, 2, 2) m² — smoothed floor positions on the grid."""

    times: np.ndarray
    xy: np.ndarray
    covariance: np.ndarray


def backproject_with_covariance(obs: Observations, height: float, step_px: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """Floor points (N, 2) where the head pixels' rays meet Z = ``height`` (m), and their (N, 2, 2)
    covariances J·diag(σ²)·Jᵀ (J by central differences of ``step_px`` pixels). NaN where a ray misses."""
    xy = np.full((len(obs), 2), np.nan)
    cov = np.full((len(obs), 2, 2), np.nan)
    for k, cam in enumerate(obs.cameras):
        sel = np.flatnonzero(obs.camera == k)
        uv = obs.uv[sel]
        xy[sel] = cam.backproject(uv, height)[:, :2]
        J = np.stack([(cam.backproject(uv + d, height)[:, :2] - cam.backproject(uv - d, height)[:, :2]) / (2 * step_px)
                      for d in (np.array([step_px, 0.0]), np.array([0.0, step_px]))], axis=2)
        s2 = obs.sigma[sel] ** 2
        cov[sel] = np.einsum("nij,nkj->nik", J, J) * s2[:, None, None]
    return xy, cov


def constant_velocity(dt: float, q: float) -> tuple[np.ndarray, np.ndarray]:
    """F and Q (4, 4) of the state (x, ẋ, y, ẏ) over ``dt`` seconds, white-noise acceleration ``q`` m²/s³."""
    F1 = np.array([[1.0, dt], [0.0, 1.0]])
    Q1 = q * np.array([[dt ** 3 / 3, dt ** 2 / 2], [dt ** 2 / 2, dt]])
    Z = np.zeros((2, 2))
    return np.block([[F1, Z], [Z, F1]]), np.block([[Q1, Z], [Z, Q1]])


def kalman_rts(obs: Observations, grid: TimeGrid, q_horizontal: float, height: float,
               initial_speed_sigma: float = 2.0) -> BaselineEstimate:
    """Kalman filter and RTS smoother on the back-projected head points, sampled on ``grid``.

    Parameters
    ----------
    obs : Observations
    grid : TimeGrid — the MAP's grid; the filter also steps to every observation's own time
    q_horizontal : float, m²/s³ — white-noise acceleration (as :class:`~.model.MotionPrior`)
    height : float, metres — the head height the pixels are back-projected to
    initial_speed_sigma : float, m/s — prior spread of the velocity at the first time
    """
    xy, cov = backproject_with_covariance(obs, height)
    ok = np.all(np.isfinite(xy), axis=1)
    if not ok.any():
        raise InputError(f"no observation's viewing ray reaches the head height {height:.2f} m")
    rows = np.flatnonzero(ok)
    times = np.unique(np.concatenate([grid.times, obs.time[rows]]))
    H = np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]])
    first = rows[0]
    x = np.array([xy[first, 0], 0.0, xy[first, 1], 0.0])
    P = np.diag([cov[first, 0, 0], initial_speed_sigma ** 2, cov[first, 1, 1], initial_speed_sigma ** 2])
    n = len(times)
    xf, Pf, xp, Pp, Fs = (np.empty((n, 4)), np.empty((n, 4, 4)), np.empty((n, 4)), np.empty((n, 4, 4)),
                          np.empty((n, 4, 4)))
    j, t_prev = 0, times[0]
    for k, t in enumerate(times):
        F, Q = constant_velocity(t - t_prev, q_horizontal)
        x, P = F @ x, F @ P @ F.T + Q                           # predict
        xp[k], Pp[k], Fs[k] = x, P, F
        while j < len(rows) and obs.time[rows[j]] <= t + 1e-9:  # update with every observation at t
            i = rows[j]
            S = H @ P @ H.T + cov[i]
            K = P @ H.T @ np.linalg.inv(S)
            x = x + K @ (xy[i] - H @ x)
            IKH = np.eye(4) - K @ H
            P = IKH @ P @ IKH.T + K @ cov[i] @ K.T              # Joseph form
            j += 1
        xf[k], Pf[k], t_prev = x, P, t
    xs, Ps = xf.copy(), Pf.copy()
    for k in range(n - 2, -1, -1):                             # Rauch–Tung–Striebel
        G = Pf[k] @ Fs[k + 1].T @ np.linalg.inv(Pp[k + 1])
        xs[k] = xf[k] + G @ (xs[k + 1] - xp[k + 1])
        Ps[k] = Pf[k] + G @ (Ps[k + 1] - Pp[k + 1]) @ G.T
    idx = np.clip(np.searchsorted(times, grid.times - 1e-9), 0, n - 1)
    return BaselineEstimate(grid.times, xs[idx][:, [0, 2]], Ps[idx][:, [0, 2]][:, :, [0, 2]])
