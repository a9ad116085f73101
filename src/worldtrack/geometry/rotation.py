"""Rotation matrices from the angle conventions the papers and file formats use.

All angles are radians. Matrices are (3, 3) float arrays, or (..., 3, 3) when the angles are arrays.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike


def rot_x(angle: ArrayLike) -> np.ndarray:
    """Rotation about the X axis by ``angle`` radians (right-handed)."""
    a = np.asarray(angle, dtype=float)
    c, s = np.cos(a), np.sin(a)
    one, zero = np.ones_like(a), np.zeros_like(a)
    return np.stack([np.stack([one, zero, zero], -1),
                     np.stack([zero, c, -s], -1),
                     np.stack([zero, s, c], -1)], -2)


def rot_y(angle: ArrayLike) -> np.ndarray:
    """Rotation about the Y axis by ``angle`` radians (right-handed)."""
    a = np.asarray(angle, dtype=float)
    c, s = np.cos(a), np.sin(a)
    one, zero = np.ones_like(a), np.zeros_like(a)
    return np.stack([np.stack([c, zero, s], -1),
                     np.stack([zero, one, zero], -1),
                     np.stack([-s, zero, c], -1)], -2)


def rot_z(angle: ArrayLike) -> np.ndarray:
    """Rotation about the Z axis by ``angle`` radians (right-handed); yaw on the floor."""
    a = np.asarray(angle, dtype=float)
    c, s = np.cos(a), np.sin(a)
    one, zero = np.ones_like(a), np.zeros_like(a)
    return np.stack([np.stack([c, -s, zero], -1),
                     np.stack([s, c, zero], -1),
                     np.stack([zero, zero, one], -1)], -2)


def euler_zyx(rz: ArrayLike, ry: ArrayLike, rx: ArrayLike) -> np.ndarray:
    """``Rz(rz) · Ry(ry) · Rx(rx)``: the Tsai/PETS convention and seed 003's torso angles."""
    return rot_z(rz) @ rot_y(ry) @ rot_x(rx)


def rodrigues(rvec: ArrayLike) -> np.ndarray:
    """Rotation matrix of an axis-angle vector (OpenCV ``rvec``), shape (3,) → (3, 3)."""
    r = np.asarray(rvec, dtype=float).reshape(3)
    theta = float(np.linalg.norm(r))
    if theta < 1e-12:
        return np.eye(3)
    k = r / theta
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(theta) * kx + (1.0 - np.cos(theta)) * (kx @ kx)


def rotation_to_rodrigues(R: ArrayLike) -> np.ndarray:
    """Axis-angle vector (3,) of a rotation matrix; inverse of :func:`rodrigues`."""
    R = np.asarray(R, dtype=float)
    cos_theta = np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0)
    theta = float(np.arccos(cos_theta))
    if theta < 1e-12:
        return np.zeros(3)
    if np.pi - theta < 1e-6:
        # Near 180°: axis from the diagonal of (R + I) / 2 = k kᵀ.
        B = (R + np.eye(3)) / 2.0
        k = np.sqrt(np.clip(np.diag(B), 0.0, None))
        i = int(np.argmax(k))
        k = B[i] / k[i]
        return theta * k / np.linalg.norm(k)
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    return theta * w / (2.0 * np.sin(theta))


def rotation_angle_deg(R_true: ArrayLike, R_est: ArrayLike) -> np.ndarray:
    """Angle of ``R_true · R_estᵀ`` in degrees: seed 003's ``arccos((tr(R0 Rᵀ) − 1) / 2)``.

    Works on single matrices (3, 3) or stacks (..., 3, 3).
    """
    A = np.asarray(R_true, dtype=float) @ np.swapaxes(np.asarray(R_est, dtype=float), -1, -2)
    c = (np.trace(A, axis1=-2, axis2=-1) - 1.0) / 2.0
    return np.degrees(np.arccos(np.clip(c, -1.0, 1.0)))
