"""Each person's reported velocity: a constant-velocity Kalman filter over the tracked positions.

The tracker's own velocity (``Person.vx, vy``) drives its prediction. It moves by half of each
frame's matching move over the frame interval, and matching moves are multiples of the smallest
candidate step (25 mm) along the camera's axes: at 10 frames/s speeds came out in steps of
0.5 · 0.025 / 0.1 = 0.125 m/s. What a user reads (``vx, vy, speed`` in ``tracks.csv``) is instead
this filter's estimate. Its measurements are the tracked positions with their covariance
(:mod:`.uncertainty`: the along-the-ray error is the larger one, so velocity across the line of
sight is followed more closely than along it). It never moves a person; the positions reported
stay the tracker's. A person no camera shows gets no measurement, so the filter predicts only
and its position covariance grows.

State ``(x, y, vx, vy)`` (m, m/s), white-noise acceleration of spectral density
:data:`ACCELERATION_PSD` (m²/s³), real time stamps (s).

>>> m = start(np.array([0.0, 0.0]), np.eye(2) * 0.01, 0.0)
>>> for k in range(1, 21):                     # walking at 1 m/s along x, 10 frames/s
...     m = update(predict(m, k / 10), np.array([k / 10, 0.0]), np.eye(2) * 0.01)
>>> np.round(m.mean[2:], 2).tolist()
[1.0, 0.0]
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

#: Spectral density of the white-noise acceleration, m²/s³: people walk, stop and turn (about
#: 0.7 m/s of speed change in a second).
ACCELERATION_PSD = 0.5
#: Speed uncertainty of a person just confirmed (they may be walking or standing), m/s.
START_SPEED_SIGMA = 1.0


class Motion(NamedTuple):
    """One person's filter state.

    Attributes
    ----------
    mean : (4,) float — x, y (m), vx, vy (m/s)
    cov : (4, 4) float — its covariance
    t : float — the time of the state, s
    measured_t : float — the time of the last measurement, s
    measured_cov : (2, 2) float — the covariance of that measurement, m²
    measured_pos_cov : (2, 2) float — the filter's position covariance just after it, m²
    """

    mean: np.ndarray
    cov: np.ndarray
    t: float
    measured_t: float
    measured_cov: np.ndarray
    measured_pos_cov: np.ndarray


def start(xy: np.ndarray, cov: np.ndarray, t: float, v: tuple[float, float] = (0.0, 0.0),
          speed_sigma: float = START_SPEED_SIGMA) -> Motion:
    """A filter at position ``xy`` (2,) m with covariance ``cov`` (2, 2) m², velocity ``v`` (m/s)
    ± ``speed_sigma`` per axis."""
    P = np.zeros((4, 4))
    P[:2, :2] = cov
    P[2, 2] = P[3, 3] = speed_sigma ** 2
    return Motion(np.array([xy[0], xy[1], v[0], v[1]], float), P, float(t), float(t), np.array(cov, float),
                  np.array(cov, float))


def predict(m: Motion, t: float, psd: float = ACCELERATION_PSD) -> Motion:
    """The state moved on to time ``t`` (s) at constant velocity (nothing if ``t`` is not later).

    ``F P Fᵀ + Q`` in 2×2 blocks (position A, cross B, velocity C): a few small products instead
    of 4×4 ones, as this runs for every person every frame.
    """
    dt = t - m.t
    if not dt > 0:
        return m
    P = m.cov
    A, B, C = P[:2, :2], P[:2, 2:], P[2:, 2:]
    eye = np.eye(2)
    out = np.empty((4, 4))
    out[:2, :2] = A + dt * (B + B.T) + dt * dt * C + (psd * dt ** 3 / 3) * eye
    out[:2, 2:] = B + dt * C + (psd * dt * dt / 2) * eye
    out[2:, :2] = out[:2, 2:].T
    out[2:, 2:] = C + (psd * dt) * eye
    mean = m.mean.copy()
    mean[:2] += dt * mean[2:]
    return m._replace(mean=mean, cov=out, t=float(t))


def update(m: Motion, xy: np.ndarray, cov: np.ndarray) -> Motion:
    """The state after measuring position ``xy`` (2,) m with covariance ``cov`` (2, 2) m² at ``m.t``."""
    P = m.cov
    S = P[:2, :2] + cov
    det = S[0, 0] * S[1, 1] - S[0, 1] * S[1, 0]
    S_inv = np.array([[S[1, 1], -S[0, 1]], [-S[1, 0], S[0, 0]]]) / det
    K = P[:, :2] @ S_inv                             # (4, 2) = P Hᵀ S⁻¹
    mean = m.mean + K @ (np.asarray(xy, float) - m.mean[:2])
    new = P - K @ P[:2, :]
    new = 0.5 * (new + new.T)
    return Motion(mean, new, m.t, m.t, np.array(cov, float), new[:2, :2].copy())


def grown_variance(m: Motion) -> float:
    """How much the filter's per-axis position variance has grown since the last measurement, m²
    (0 when measured at ``m.t``): what a person unseen since then may have walked."""
    return max(0.0, float(np.trace(m.cov[:2, :2]) - np.trace(m.measured_pos_cov)) / 2)


__all__ = ["ACCELERATION_PSD", "Motion", "START_SPEED_SIGMA", "grown_variance", "predict", "start", "update"]
