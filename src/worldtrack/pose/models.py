"""Shape models for pose tracking: rigid point models and the rigid pose (seed 003, §2.1, §3.2).

A model is a dense set of surface points ``M_O`` (object frame, metres) with outward normals and a
grey-level appearance per point (albedo, 0–255; NaN where unknown). Its image is
``M_I = K̂·D·M_O`` with ``D = [R t; 0 1]`` (eqs. 1–2).

Rigid pose (eqs. 8–9): ``p = (tx, ty, tz, q1, q2, q3)``, ``q0 = sqrt(1 − q1² − q2² − q3²)`` and
``R`` the rotation of the unit quaternion ``(q0, q1, q2, q3)`` (the matrix of the paper's Fig. 4).
A tracker state is stored as ``(tx, ty, tz, qw, qx, qy, qz)`` and every step is taken as an
*increment*: ``R ← R(q)·R``, ``t ← t + δt`` with ``q`` small, so ``q0`` stays near 1 whatever the
object's orientation (the paper's parameters applied to the change of pose; see :func:`retract`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from numba import njit

from worldtrack.errors import InputError


@dataclass(frozen=True)
class PointModel:
    """A rigid surface model.

    Attributes
    ----------
    points : (M, 3) float, metres, object frame
    normals : (M, 3) float, unit outward normals
    albedo : (M,) float32, grey level 0–255 under unit light; NaN where unknown
    spacing : float, metres — distance between neighbouring points
    from_image : bool — the albedo was read from a camera image (so it already holds the camera's
        blur; see :func:`worldtrack.pose.render.learn_appearance`)
    """

    points: np.ndarray
    normals: np.ndarray
    albedo: np.ndarray
    spacing: float
    from_image: bool = False

    @property
    def radius(self) -> float:
        """Largest distance of a point from the object origin (m)."""
        return float(np.sqrt((self.points ** 2).sum(1).max()))

    def with_albedo(self, albedo: np.ndarray, from_image: bool = True) -> "PointModel":
        """The same model with another appearance (by default one read from a camera image)."""
        return replace(self, albedo=np.asarray(albedo, np.float32), from_image=from_image)


# ----------------------------------------------------------------------------------- rotations

def quat_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of unit quaternions ``q = (q0, q1, q2, q3)`` (..., 4) (Fig. 4)."""
    q = np.asarray(q, float)
    q0, q1, q2, q3 = np.moveaxis(q, -1, 0)
    return np.stack([
        np.stack([q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3, 2 * (q1 * q2 - q0 * q3), 2 * (q1 * q3 + q0 * q2)], -1),
        np.stack([2 * (q1 * q2 + q0 * q3), q0 * q0 - q1 * q1 + q2 * q2 - q3 * q3, 2 * (q2 * q3 - q0 * q1)], -1),
        np.stack([2 * (q1 * q3 - q0 * q2), 2 * (q2 * q3 + q0 * q1), q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3], -1),
    ], -2)


def quat_from_q123(q: np.ndarray) -> np.ndarray:
    """``(q1, q2, q3)`` (..., 3) → unit quaternion (..., 4) with ``q0 = sqrt(1 − |q|²)`` (eq. 9).

    A vector longer than 1 is scaled back to unit length (q0 = 0), so any input is a rotation.
    """
    q = np.asarray(q, float)
    n2 = (q * q).sum(-1, keepdims=True)
    q = np.where(n2 > 1.0, q / np.sqrt(np.maximum(n2, 1e-300)), q)
    q0 = np.sqrt(np.clip(1.0 - (q * q).sum(-1, keepdims=True), 0.0, 1.0))
    return np.concatenate([q0, q], -1)


def quat_multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product ``a·b`` of quaternions (..., 4): the rotation ``R(a)·R(b)``."""
    a0, a1, a2, a3 = np.moveaxis(np.asarray(a, float), -1, 0)
    b0, b1, b2, b3 = np.moveaxis(np.asarray(b, float), -1, 0)
    return np.stack([a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
                     a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
                     a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1,
                     a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0], -1)


def quat_from_matrix(R: np.ndarray) -> np.ndarray:
    """Unit quaternion (..., 4), ``q0 ≥ 0``, of rotation matrices (..., 3, 3)."""
    from scipy.spatial.transform import Rotation

    R = np.asarray(R, float)
    xyzw = Rotation.from_matrix(R.reshape(-1, 3, 3)).as_quat()
    q = np.concatenate([xyzw[:, 3:], xyzw[:, :3]], 1)
    q *= np.where(q[:, :1] < 0, -1.0, 1.0)
    return q.reshape(R.shape[:-2] + (4,))


def rigid_state(R: np.ndarray, t: np.ndarray) -> np.ndarray:
    """State vector(s) ``(tx, ty, tz, qw, qx, qy, qz)`` of object → camera poses ``R`` (..., 3, 3), ``t`` (..., 3)."""
    return np.concatenate([np.asarray(t, float), quat_from_matrix(R)], -1)


def state_pose(X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(R (..., 3, 3), t (..., 3))`` of rigid states (..., 7) (compiled; the NumPy reference is
    :func:`quat_matrix` of the normalised quaternions)."""
    X = np.asarray(X, float)
    flat = np.ascontiguousarray(X.reshape(-1, 7))
    R = np.empty((len(flat), 3, 3))
    _state_rotation_kernel(flat, R)
    return R.reshape(X.shape[:-1] + (3, 3)), X[..., :3].copy()


@njit(cache=True)
def _state_rotation_kernel(X, R):  # pragma: no cover - compiled
    # quat_matrix(q / |q|) of each state's quaternion, without NumPy's per-call overhead (the LM
    # and the particle filter convert ~100 small batches of states per frame).
    for k in range(X.shape[0]):
        n = np.sqrt(X[k, 3] ** 2 + X[k, 4] ** 2 + X[k, 5] ** 2 + X[k, 6] ** 2)
        q0, q1, q2, q3 = X[k, 3] / n, X[k, 4] / n, X[k, 5] / n, X[k, 6] / n
        R[k, 0, 0], R[k, 0, 1], R[k, 0, 2] = q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3, 2 * (q1 * q2 - q0 * q3), 2 * (q1 * q3 + q0 * q2)
        R[k, 1, 0], R[k, 1, 1], R[k, 1, 2] = 2 * (q1 * q2 + q0 * q3), q0 * q0 - q1 * q1 + q2 * q2 - q3 * q3, 2 * (q2 * q3 - q0 * q1)
        R[k, 2, 0], R[k, 2, 1], R[k, 2, 2] = 2 * (q1 * q3 - q0 * q2), 2 * (q2 * q3 + q0 * q1), q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3


def retract(X: np.ndarray, delta: np.ndarray, length: float = 1.0) -> np.ndarray:
    """Apply increments ``delta = (δtx, δty, δtz, q1, q2, q3)`` (..., 6) to rigid states (..., 7).

    ``t ← t + length·δt`` and ``R ← R(q)·R`` with ``R(q)`` from eq. 9, rotating about the object
    origin in camera axes. ``length`` (m) scales the translation so that both halves of ``delta``
    are of the same order (LM's damping ``C·I`` treats them alike).
    """
    X, delta = np.asarray(X, float), np.asarray(delta, float)
    lead = np.broadcast_shapes(X.shape[:-1], delta.shape[:-1])
    X, delta = np.broadcast_to(X, lead + (7,)), np.broadcast_to(delta, lead + (6,))
    out = np.empty(X.shape)
    _retract_kernel(np.ascontiguousarray(X.reshape(-1, 7)), np.ascontiguousarray(delta.reshape(-1, 6)), float(length),
                    out.reshape(-1, 7))
    return out


def retract_reference(X: np.ndarray, delta: np.ndarray, length: float = 1.0) -> np.ndarray:
    """:func:`retract` in NumPy, with the quaternion functions above (the compiled one is tested equal)."""
    X = np.asarray(X, float)
    delta = np.asarray(delta, float)
    t = X[..., :3] + length * delta[..., :3]
    q = quat_multiply(quat_from_q123(delta[..., 3:6]), X[..., 3:7])
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return np.concatenate([t, q * np.where(q[..., :1] < 0, -1.0, 1.0)], -1)


@njit(cache=True)
def _retract_kernel(X, delta, length, out):  # pragma: no cover - compiled
    # retract_reference per row: t + L·δt; q = q(δ)·q_X (eq. 9, a vector longer than 1 scaled to
    # unit length), normalised, sign chosen with q0 ≥ 0.
    for k in range(X.shape[0]):
        for j in range(3):
            out[k, j] = X[k, j] + length * delta[k, j]
        a1, a2, a3 = delta[k, 3], delta[k, 4], delta[k, 5]
        n2 = a1 * a1 + a2 * a2 + a3 * a3
        if n2 > 1.0:
            s = 1.0 / np.sqrt(n2)
            a1, a2, a3 = a1 * s, a2 * s, a3 * s
        a0 = np.sqrt(min(max(1.0 - (a1 * a1 + a2 * a2 + a3 * a3), 0.0), 1.0))
        b0, b1, b2, b3 = X[k, 3], X[k, 4], X[k, 5], X[k, 6]
        q0 = a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3
        q1 = a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2
        q2 = a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1
        q3 = a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0
        n = np.sqrt(q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
        if q0 < 0:
            n = -n
        out[k, 3], out[k, 4], out[k, 5], out[k, 6] = q0 / n, q1 / n, q2 / n, q3 / n


def increment_between(X0: np.ndarray, X1: np.ndarray, length: float = 1.0) -> np.ndarray:
    """The increment δ (6,) with ``retract(X0, δ, length) = X1`` (rigid states (7,))."""
    X0, X1 = np.asarray(X0, float), np.asarray(X1, float)
    q0 = X0[3:7] * np.array([1.0, -1.0, -1.0, -1.0])                 # inverse of a unit quaternion
    dq = quat_multiply(X1[3:7], q0)
    dq = dq * (1.0 if dq[0] >= 0 else -1.0)
    return np.concatenate([(X1[:3] - X0[:3]) / length, dq[1:]])


# -------------------------------------------------------------------------------- building models

def box_model(half_size: tuple[float, float, float], spacing: float) -> PointModel:
    """Points on the surface of a box centred on the origin, ``spacing`` metres apart; albedo unknown."""
    h = np.asarray(half_size, float)
    pts, nrm = [], []
    for axis in range(3):
        a, b = [i for i in range(3) if i != axis]
        ua = np.arange(-h[a] + spacing / 2, h[a], spacing)
        ub = np.arange(-h[b] + spacing / 2, h[b], spacing)
        A, B = np.meshgrid(ua, ub, indexing="ij")
        for sign in (-1.0, 1.0):
            p = np.zeros((A.size, 3))
            p[:, a], p[:, b], p[:, axis] = A.ravel(), B.ravel(), sign * h[axis]
            n = np.zeros_like(p)
            n[:, axis] = sign
            pts.append(p)
            nrm.append(n)
    P = np.concatenate(pts)
    return PointModel(P, np.concatenate(nrm), np.full(len(P), np.nan, np.float32), float(spacing))


def mesh_model(vertices: np.ndarray, faces: np.ndarray, spacing: float) -> PointModel:
    """Points sampled on a triangle mesh about ``spacing`` metres apart (barycentric grid per face)."""
    V = np.asarray(vertices, float)
    F = np.asarray(faces, np.int64)
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    n = np.cross(b - a, c - a)
    area = np.linalg.norm(n, axis=1)
    keep = area > 1e-12
    a, b, c, n, area = a[keep], b[keep], c[keep], n[keep] / area[keep, None], area[keep]
    pts, nrm = [], []
    edge = np.maximum(np.linalg.norm(b - a, axis=1), np.linalg.norm(c - a, axis=1))
    for k in np.unique(np.ceil(np.maximum(edge, 1e-9) / spacing).astype(int)):
        sel = np.ceil(np.maximum(edge, 1e-9) / spacing).astype(int) == k
        i, j = np.meshgrid(np.arange(k), np.arange(k), indexing="ij")
        ok = i + j <= k - 1
        s = (i[ok] + 1 / 3) / k
        r = (j[ok] + 1 / 3) / k
        p = a[sel, None] + s[None, :, None] * (b - a)[sel, None] + r[None, :, None] * (c - a)[sel, None]
        pts.append(p.reshape(-1, 3))
        nrm.append(np.repeat(n[sel], len(s), 0))
    P = np.concatenate(pts)
    return PointModel(P, np.concatenate(nrm), np.full(len(P), np.nan, np.float32), float(spacing))


def load_obj(path: str | Path, spacing: float = 0.001) -> PointModel:
    """Read a Wavefront OBJ mesh (``v`` and ``f`` lines; metres) and sample its surface.

    Raises :class:`~worldtrack.errors.InputError` naming the file when it cannot be read or has
    no triangles.
    """
    p = Path(path)
    try:
        text = p.read_text(errors="strict")
    except (OSError, UnicodeDecodeError) as e:
        raise InputError(f"{p}: cannot read the model ({getattr(e, 'strerror', None) or e})") from None
    verts, faces = [], []
    try:
        for line in text.splitlines():
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                verts.append([float(x) for x in parts[1:4]])
            elif parts[0] == "f":
                idx = [int(x.split("/")[0]) for x in parts[1:]]
                idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
                faces += [[idx[0], idx[k], idx[k + 1]] for k in range(1, len(idx) - 1)]
    except (ValueError, IndexError):
        raise InputError(f"{p}: not a Wavefront OBJ mesh (bad 'v' or 'f' line)") from None
    if not verts or not faces or max(max(f) for f in faces) >= len(verts) or min(min(f) for f in faces) < 0:
        raise InputError(f"{p}: expected an OBJ mesh with vertices ('v') and faces ('f') that index them")
    return mesh_model(np.array(verts), np.array(faces), spacing)
