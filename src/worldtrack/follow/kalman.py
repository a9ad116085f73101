"""Constant-velocity Kalman filter on the floor (seed 001 §2.4), with the real time step, for many people at once.

State ``x = (X, Y, Ẋ, Ẏ)`` in metres and m/s; the paper keeps it in robot coordinates, worldtrack
in world coordinates whenever the camera's pose per frame is known (the robot's own motion is then
no part of the target's), which for a fixed camera is the same thing. Time steps are the
difference of the frames' time stamps in seconds, never "one frame".

Process noise: white acceleration of σ_a (m/s²) held over each step,
``Q = σ_a²·G·Gᵀ`` with ``G = (dt²/2, dt)`` per axis. Measurement: the position, ``R = σ_z²·I``.

>>> import numpy as np
>>> x, P = initial_state(np.array([[1.0, 2.0]]), 0.1)
>>> x, P = predict(x, P, 0.5, accel_sigma=1.0)
>>> x, P = update(x, P, np.array([[1.5, 2.0]]), 0.1)
>>> bool(1.0 < x[0, 0] < 1.5 and x[0, 2] > 0)
True
"""

from __future__ import annotations

import numpy as np

H = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]])


def initial_state(xy: np.ndarray, position_sigma: float, speed_sigma: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """States (T, 4) at rest at ``xy`` (T, 2) and covariances (T, 4, 4): σ_xy² and ``speed_sigma``² (m/s)."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    x = np.zeros((len(xy), 4))
    x[:, :2] = xy
    P = np.zeros((len(xy), 4, 4))
    P[:, [0, 1], [0, 1]] = position_sigma ** 2
    P[:, [2, 3], [2, 3]] = speed_sigma ** 2
    return x, P


def transition(dt: float) -> np.ndarray:
    """F (4, 4): X += Ẋ·dt, Y += Ẏ·dt."""
    F = np.eye(4)
    F[0, 2] = F[1, 3] = dt
    return F


def process_noise(dt: float, accel_sigma: float) -> np.ndarray:
    """Q (4, 4) = σ_a²·G·Gᵀ, G = (dt²/2, dt) per axis."""
    q = accel_sigma ** 2
    a, b, c = dt ** 4 / 4, dt ** 3 / 2, dt ** 2
    Q = np.zeros((4, 4))
    Q[[0, 1], [0, 1]] = a * q
    Q[[0, 1], [2, 3]] = Q[[2, 3], [0, 1]] = b * q
    Q[[2, 3], [2, 3]] = c * q
    return Q


def predict(x: np.ndarray, P: np.ndarray, dt: float, accel_sigma: float) -> tuple[np.ndarray, np.ndarray]:
    """x = F·x, P = F·P·Fᵀ + Q for every state (T, 4), (T, 4, 4); ``dt`` in seconds."""
    F = transition(dt)
    x = x @ F.T                                            # x = F x
    P = F @ P @ F.T + process_noise(dt, accel_sigma)       # P = F P Fᵀ + Q
    return x, P


def update(x: np.ndarray, P: np.ndarray, z: np.ndarray, measurement_sigma: float) -> tuple[np.ndarray, np.ndarray]:
    """Correct every state (T, 4) with its position measurement ``z`` (T, 2), metres (Joseph form)."""
    R = np.eye(2) * measurement_sigma ** 2
    y = z - x[:, :2]                                       # y = z − H x
    S = P[:, :2, :2] + R                                   # S = H P Hᵀ + R
    K = P[:, :, :2] @ np.linalg.inv(S)                     # K = P Hᵀ S⁻¹
    x = x + np.einsum("tij,tj->ti", K, y)                  # x = x + K y
    I_KH = np.eye(4)[None] - K @ H[None]
    # Joseph form P = (I − KH) P (I − KH)ᵀ + K R Kᵀ keeps P symmetric and positive.
    P = I_KH @ P @ I_KH.transpose(0, 2, 1) + K @ R @ K.transpose(0, 2, 1)
    return x, P


def position_sigma(P: np.ndarray) -> np.ndarray:
    """(T,) RMS position standard deviation sqrt((σ_X² + σ_Y²) / 2), metres."""
    return np.sqrt((P[:, 0, 0] + P[:, 1, 1]) / 2)
