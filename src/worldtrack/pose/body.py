"""The articulated upper body: 14 DoF, eqs. 11–15 of seed 003, and its tracker.

Parts: torso (with head), left upper arm, left forearm, right upper arm, right forearm, each a
:class:`~worldtrack.pose.models.PointModel` in its own frame. Pose parameters ``p`` (14,):

* torso ``(tx, ty, tz)`` (m) and ``(θ, φ, ψ)`` (rad): ``D = [Rz(θ)·Ry(φ)·Rx(ψ) | t]`` (eq. 13);
* per arm (left, then right) shoulder ``(θs, φs)`` and elbow ``(θe, φe)``:
  ``D_OU = [B·Rz(θs)·Ry(φs) | t_S]`` (eq. 14), ``D_UL = [Rz(θe)·Ry(φe) | t_E]`` (eq. 15), the limb
  along each frame's x axis. ``t_S`` (shoulder in the torso frame) and ``t_E`` (elbow in the upper
  arm frame) are the person's known joint offsets; ``B`` is a fixed rotation of each arm's rest
  frame (identity for the left arm, a half turn about z for the right one, so both arms point
  outwards at rest — rotated copies, as the paper's figure 8 draws them).

Model points go to the camera by ``D``, ``D·D_OU`` and ``D·D_OU·D_UL`` (eqs. 11–12).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from worldtrack.geometry.rotation import euler_zyx, rot_x, rot_y, rot_z
from worldtrack.pose.models import PointModel

PARTS = ("torso", "l_upper_arm", "l_forearm", "r_upper_arm", "r_forearm")
LIMBS = {"r_upper_arm": 3, "l_upper_arm": 1, "r_forearm": 4, "l_forearm": 2}     # the paper's table order
N_PARAMS = 14
TORSO, LEFT_ARM, RIGHT_ARM = slice(0, 6), slice(6, 10), slice(10, 14)
ELBOWS = [8, 9, 12, 13]


class BodyModel(NamedTuple):
    """Parts (5 PointModels, :data:`PARTS` order), shoulder offsets ``t_S`` (2, 3) m in the torso
    frame and elbow offsets ``t_E`` (2, 3) m in the upper-arm frames (left, right), rest rotations
    ``B`` (2, 3, 3)."""

    parts: tuple
    shoulder: np.ndarray
    elbow: np.ndarray
    rest: np.ndarray


def arm_rest_rotations() -> np.ndarray:
    """``B`` for the left (identity) and right (half turn about z) arm."""
    return np.stack([np.eye(3), rot_z(np.pi)])


def rz_ry(theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """``Rz(θ)·Ry(φ)`` (K, 3, 3), written out (the joints of eqs. 14–15)."""
    ct, st, cp, sp = np.cos(theta), np.sin(theta), np.cos(phi), np.sin(phi)
    R = np.empty(np.shape(theta) + (3, 3))
    R[..., 0, 0], R[..., 0, 1], R[..., 0, 2] = ct * cp, -st, ct * sp
    R[..., 1, 0], R[..., 1, 1], R[..., 1, 2] = st * cp, ct, st * sp
    R[..., 2, 0], R[..., 2, 1], R[..., 2, 2] = -sp, 0.0, cp
    return R


def body_transforms(p: np.ndarray, model: BodyModel) -> np.ndarray:
    """Part → camera transforms (K, 5, 3, 4) of parameter vectors ``p`` (K, 14) (eqs. 11–15)."""
    p = np.atleast_2d(np.asarray(p, float))
    K = len(p)
    out = np.empty((K, 5, 3, 4))
    R0 = rz_ry(p[:, 3], p[:, 4]) @ rot_x(p[:, 5])                       # eq. 13: Rz·Ry·Rx
    out[:, 0, :, :3], out[:, 0, :, 3] = R0, p[:, :3]
    for side, base in ((0, 6), (1, 10)):
        Rs = model.rest[side] @ rz_ry(p[:, base], p[:, base + 1])       # eq. 14: B·Rz·Ry
        Re = rz_ry(p[:, base + 2], p[:, base + 3])                      # eq. 15: Rz·Ry
        Ru = R0 @ Rs                                                    # eq. 11: D·D_OU
        tu = (R0 @ model.shoulder[side]) + p[:, :3]
        out[:, 1 + 2 * side, :, :3], out[:, 1 + 2 * side, :, 3] = Ru, tu
        out[:, 2 + 2 * side, :, :3] = Ru @ Re                           # eq. 12: D·D_OU·D_UL
        out[:, 2 + 2 * side, :, 3] = (Ru @ model.elbow[side]) + tu
    return out


def body_transforms_reference(p: np.ndarray, model: BodyModel) -> np.ndarray:
    """:func:`body_transforms` as products of 4×4 matrices, one candidate at a time (for tests)."""
    out = []
    for q in np.atleast_2d(np.asarray(p, float)):
        def D(R, t):
            M = np.eye(4)
            M[:3, :3], M[:3, 3] = R, t
            return M
        torso = D(euler_zyx(q[3], q[4], q[5]), q[:3])
        parts = [torso]
        for side, base in ((0, 6), (1, 10)):
            DOU = D(model.rest[side] @ rot_z(q[base]) @ rot_y(q[base + 1]), model.shoulder[side])
            DUL = D(rot_z(q[base + 2]) @ rot_y(q[base + 3]), model.elbow[side])
            parts += [torso @ DOU, torso @ DOU @ DUL]
        out.append(np.stack(parts)[:, :3, :])
    return np.stack(out)


def limb_axes(p: np.ndarray, model: BodyModel) -> dict[str, np.ndarray]:
    """Unit x axes (K, 3) of the four limbs in the camera frame (the limbs' main axes, §5.2.1)."""
    T = body_transforms(p, model)
    return {name: T[:, k, :, 0] for name, k in LIMBS.items()}


@dataclass
class BodySpace:
    """The 14-DoF pose space: increments are added (translation in units of ``length`` metres,
    angles in radians). ``elbow_limit`` (rad): a joint limit on both elbow angles — an elbow cannot
    fold the forearm back onto the upper arm (worldtrack's addition; None: no limit)."""

    length: float = 0.3
    fd_step: np.ndarray = field(default_factory=lambda: np.array([2e-3] * 3 + [2e-3] * 11))
    model: BodyModel | None = None
    elbow_limit: float | None = None
    dim: int = N_PARAMS

    def retract(self, X: np.ndarray, delta: np.ndarray) -> np.ndarray:
        """``X + δ`` (translation in ``length`` units), elbows kept within ±``elbow_limit`` rad."""
        scale = np.r_[[self.length] * 3, [1.0] * 11]
        out = np.asarray(X, float) + np.asarray(delta, float) * scale
        if self.elbow_limit is not None:
            out[..., ELBOWS] = np.clip(out[..., ELBOWS], -self.elbow_limit, self.elbow_limit)
        return out

    def transforms(self, X: np.ndarray) -> np.ndarray:
        return body_transforms(X, self.model)

    def increment_sigma(self, sigma_mm: tuple, sigma_deg: tuple) -> np.ndarray:
        """σ of increments from translation σ (mm) and the 11 angles' σ (degrees)."""
        return np.r_[np.asarray(sigma_mm, float) / 1000 / self.length, np.radians(np.asarray(sigma_deg, float))]


class SubSpace:
    """A :class:`BodySpace` moving only the parameters in ``index`` (the cascade's stages)."""

    def __init__(self, space: BodySpace, index: np.ndarray):
        self.space, self.index = space, np.asarray(index)
        self.dim = len(self.index)
        self.fd_step = space.fd_step[self.index]

    def retract(self, X: np.ndarray, delta: np.ndarray) -> np.ndarray:
        full = np.zeros((len(np.atleast_2d(delta)), self.space.dim))
        full[:, self.index] = delta
        return self.space.retract(X, full)

    def transforms(self, X: np.ndarray) -> np.ndarray:
        return self.space.transforms(X)


def stacked_points(model: BodyModel) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """All parts' points (M, 3), normals, albedo and part index (M,), concatenated."""
    pts = np.concatenate([m.points for m in model.parts])
    nrm = np.concatenate([m.normals for m in model.parts])
    alb = np.concatenate([m.albedo for m in model.parts])
    part = np.concatenate([np.full(len(m.points), k) for k, m in enumerate(model.parts)])
    return pts, nrm, alb, part


def model_points_camera(p: np.ndarray, model: BodyModel) -> np.ndarray:
    """(M, 3) camera-frame points of the whole body at one parameter vector ``p`` (14,)."""
    T = body_transforms(p[None], model)[0]
    out = [m.points @ T[k, :, :3].T + T[k, :, 3] for k, m in enumerate(model.parts)]
    return np.concatenate(out)


def with_part_albedo(model: BodyModel, albedo: np.ndarray, from_image: bool = True) -> BodyModel:
    """The model with a new appearance (M,) split back over its parts."""
    parts, start = [], 0
    for m in model.parts:
        parts.append(m.with_albedo(albedo[start:start + len(m.points)], from_image))
        start += len(m.points)
    return model._replace(parts=tuple(parts))


def _cylinder(radius: float, length: float, spacing: float, axis_x: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Points and normals of a capped cylinder along +x from 0 to ``length``."""
    xs = np.arange(spacing / 2, length, spacing)
    ang = np.arange(0, 2 * np.pi, spacing / radius)
    X, A = np.meshgrid(xs, ang, indexing="ij")
    p = np.column_stack([X.ravel(), radius * np.cos(A).ravel(), radius * np.sin(A).ravel()])
    n = np.column_stack([np.zeros(p.shape[0]), np.cos(A).ravel(), np.sin(A).ravel()])
    rr = np.arange(spacing / 2, radius, spacing)
    R2, A2 = np.meshgrid(rr, np.arange(0, 2 * np.pi, spacing / radius), indexing="ij")
    cap = np.column_stack([np.full(R2.size, length), (R2 * np.cos(A2)).ravel(), (R2 * np.sin(A2)).ravel()])
    return np.vstack([p, cap]), np.vstack([n, np.tile([1.0, 0, 0], (len(cap), 1))])


def body_geometry(spacing: float, torso_width: float = 0.36, torso_depth: float = 0.22, torso_height: float = 0.55,
                  upper_len: float = 0.28, fore_len: float = 0.27, arm_r: float = 0.05,
                  fore_r: float = 0.042) -> BodyModel:
    """An upper body's shape (albedo unknown): torso frame x to the person's left… see below.

    Torso frame: origin at the waist centre, x towards the image's right when the person faces
    the camera (the person's left), y down, z away from the camera (into the back); the torso is an
    elliptic cylinder from y = 0 up to the shoulders (y = −``torso_height``) with a head above.
    Shoulders at ``(±(w/2 + r), −h + r, 0)``; each arm's frame has x along the limb.
    """
    a, b, h = torso_width / 2, torso_depth / 2, torso_height
    ys = np.arange(-h + spacing / 2, 0, spacing)
    ang = np.arange(0, 2 * np.pi, spacing / max(a, b))
    Y, A = np.meshgrid(ys, ang, indexing="ij")
    tp = np.column_stack([a * np.cos(A).ravel(), Y.ravel(), b * np.sin(A).ravel()])
    tn = np.column_stack([np.cos(A).ravel() / a, np.zeros(tp.shape[0]), np.sin(A).ravel() / b])
    tn /= np.linalg.norm(tn, axis=1, keepdims=True)
    # shoulders' top: a flattened half-ellipsoid cap; head: a sphere of radius 0.1 above a neck
    u, v = np.meshgrid(np.arange(0, 2 * np.pi, spacing / a), np.arange(0, np.pi / 2, spacing / 0.06))
    cap = np.column_stack([(a * np.cos(u) * np.cos(v)).ravel(), (-h - 0.06 * np.sin(v)).ravel(),
                           (b * np.sin(u) * np.cos(v)).ravel()])
    capn = np.column_stack([cap[:, 0] / a ** 2, (cap[:, 1] + h) / 0.06 ** 2, cap[:, 2] / b ** 2])
    capn /= np.linalg.norm(capn, axis=1, keepdims=True)
    hr = 0.1
    u, v = np.meshgrid(np.arange(0, 2 * np.pi, spacing / hr), np.arange(0.05, np.pi, spacing / hr))
    hn = np.column_stack([(np.sin(v) * np.cos(u)).ravel(), -np.cos(v).ravel(), (np.sin(v) * np.sin(u)).ravel()])
    head = hn * [hr * 0.85, hr * 1.15, hr] + [0, -h - 0.06 - 0.03 - hr * 1.15, 0]
    pts = np.vstack([tp, cap, head])
    nrm = np.vstack([tn, capn, hn])
    torso = PointModel(pts, nrm, np.full(len(pts), np.nan, np.float32), spacing)
    up_p, up_n = _cylinder(arm_r, upper_len, spacing)
    fo_p, fo_n = _cylinder(fore_r, fore_len, spacing)
    upper = PointModel(up_p, up_n, np.full(len(up_p), np.nan, np.float32), spacing)
    fore = PointModel(fo_p, fo_n, np.full(len(fo_p), np.nan, np.float32), spacing)
    sx, sy = a + arm_r * 0.6, -h + arm_r
    shoulder = np.array([[sx, sy, 0.0], [-sx, sy, 0.0]])
    elbow = np.array([[upper_len, 0.0, 0.0], [upper_len, 0.0, 0.0]])
    return BodyModel((torso, upper, fore, upper, fore), shoulder, elbow, arm_rest_rotations())
