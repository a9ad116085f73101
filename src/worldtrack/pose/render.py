"""Rendering a point model with a z-buffer (paper 003, §2.2, §4.3).

To estimate the pose at time t the model is drawn at the pose of t−1 with hidden surfaces removed
(a z-buffer over the model's surface points); :mod:`worldtrack.pose.template` picks the sparse
template from that drawing. :func:`learn_appearance` reads a model's albedo from a frame where its
pose is known.

:func:`splat` is the compiled z-buffer; :func:`splat_reference` is the same in plain NumPy (tests
check they agree).
"""

from __future__ import annotations

from typing import NamedTuple

import cv2
import numpy as np
from numba import njit


class Intrinsics(NamedTuple):
    """Pinhole intrinsics (pixels): ``u = fx·x/z + cx``, ``v = fy·y/z + cy``; image ``width × height``."""

    fx: float
    fy: float
    cx: float
    cy: float
    width: int
    height: int

    @classmethod
    def from_matrix(cls, K: np.ndarray, width: int, height: int) -> "Intrinsics":
        """From a 3×3 camera matrix ``K`` and the image size (pixels)."""
        K = np.asarray(K, float)
        return cls(float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2]), int(width), int(height))

    def matrix(self) -> np.ndarray:
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    def scaled(self, s: float) -> "Intrinsics":
        """The same camera at ``s`` times the resolution (pixel centres stay at integers)."""
        return Intrinsics(self.fx * s, self.fy * s, (self.cx + 0.5) * s - 0.5, (self.cy + 0.5) * s - 0.5,
                          int(round(self.width * s)), int(round(self.height * s)))


class Rendering(NamedTuple):
    """A z-buffered view of a model. ``depth`` (H, W) float32 metres (inf where empty);
    ``index`` (H, W) int32, the model point drawn at each pixel (−1 where empty)."""

    depth: np.ndarray
    index: np.ndarray


@njit(cache=True)
def _splat_kernel(xyz, fx, fy, cx, cy, footprint, centre_weight, depth, key, index):  # pragma: no cover - compiled
    # Each pixel keeps the point with the least key = z + centre_weight·(distance to the pixel centre)²:
    # the nearest surface wins, and on one surface the point nearest the pixel centre (no shift of
    # the drawn texture towards the camera-near side).
    h, w = depth.shape
    for i in range(xyz.shape[0]):
        z = xyz[i, 2]
        if z <= 1e-6:
            continue
        u = fx * xyz[i, 0] / z + cx
        v = fy * xyz[i, 1] / z + cy
        if footprint == 1:
            u0 = int(np.floor(u + 0.5))
            v0 = int(np.floor(v + 0.5))
        else:
            u0 = int(np.floor(u))
            v0 = int(np.floor(v))
        for dv in range(footprint):
            for du in range(footprint):
                uu = u0 + du
                vv = v0 + dv
                if uu < 0 or vv < 0 or uu >= w or vv >= h:
                    continue
                kz = z + centre_weight * ((uu - u) ** 2 + (vv - v) ** 2)
                if kz < key[vv, uu]:
                    key[vv, uu] = kz
                    depth[vv, uu] = z
                    index[vv, uu] = i


def splat(xyz: np.ndarray, intr: Intrinsics, footprint: int = 1, centre_weight: float = 0.002) -> Rendering:
    """Z-buffer camera-frame points into an image: each pixel keeps its nearest point.

    Parameters
    ----------
    xyz : (M, 3) float, metres, camera frame (z forward)
    intr : Intrinsics
    footprint : 1 — a point covers the pixel it falls in; 2 — the 2×2 pixels around it (no holes
        when neighbouring points are up to 2 px apart; for dense synthetic rendering)
    centre_weight : metres per pixel² — a pixel keeps the point of least ``z + w·(distance to the
        pixel centre)²``: the nearest surface, and on it the point nearest the centre

    Returns
    -------
    Rendering

    >>> r = splat(np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 2.0]]), Intrinsics(100, 100, 2, 2, 5, 5))
    >>> int(r.index[2, 2]), float(r.depth[2, 2])
    (0, 1.0)
    """
    depth = np.full((intr.height, intr.width), np.inf, np.float32)
    key = np.full((intr.height, intr.width), np.inf)
    index = np.full((intr.height, intr.width), -1, np.int32)
    _splat_kernel(np.ascontiguousarray(xyz, np.float64), intr.fx, intr.fy, intr.cx, intr.cy, int(footprint),
                  float(centre_weight), depth, key, index)
    return Rendering(depth, index)


def splat_reference(xyz: np.ndarray, intr: Intrinsics, footprint: int = 1, centre_weight: float = 0.002) -> Rendering:
    """:func:`splat` in NumPy: sort by key and keep each pixel's first point."""
    xyz = np.asarray(xyz, np.float64)
    z = xyz[:, 2]
    ok = z > 1e-6
    idx = np.flatnonzero(ok)
    u = intr.fx * xyz[ok, 0] / z[ok] + intr.cx
    v = intr.fy * xyz[ok, 1] / z[ok] + intr.cy
    if footprint == 1:
        us, vs, ids = [np.floor(u + 0.5)], [np.floor(v + 0.5)], [idx]
    else:
        us = [np.floor(u) + du for dv in range(footprint) for du in range(footprint)]
        vs = [np.floor(v) + dv for dv in range(footprint) for du in range(footprint)]
        ids = [idx] * (footprint * footprint)
    uu, vv, ii = (np.concatenate(a) for a in (us, vs, ids))
    inside = (uu >= 0) & (vv >= 0) & (uu < intr.width) & (vv < intr.height)
    uf, vf = (np.concatenate([u] * (1 if footprint == 1 else footprint * footprint)),
              np.concatenate([v] * (1 if footprint == 1 else footprint * footprint)))
    kz = z[ii] + centre_weight * ((uu - uf) ** 2 + (vv - vf) ** 2)
    uu, vv, ii, kz = uu[inside].astype(np.int64), vv[inside].astype(np.int64), ii[inside], kz[inside]
    flat = vv * intr.width + uu
    order = np.lexsort((ii, kz, flat))             # by pixel, then key, then point order
    first = np.unique(flat[order], return_index=True)[1]
    depth = np.full(intr.height * intr.width, np.inf, np.float32)
    index = np.full(intr.height * intr.width, -1, np.int32)
    depth[flat[order][first]] = z[ii[order][first]]
    index[flat[order][first]] = ii[order][first]
    return Rendering(depth.reshape(intr.height, intr.width), index.reshape(intr.height, intr.width))


@njit(cache=True)
def _cull_and_bound_kernel(xyz, normals, cull, fx, fy, cx, cy, out, box):  # pragma: no cover - compiled
    # cull_and_bound_reference in one pass: copy, move back faces behind the camera, and keep the
    # image box of the points in front.
    box[0], box[1], box[2], box[3] = np.inf, np.inf, -np.inf, -np.inf
    for i in range(xyz.shape[0]):
        x, y, z = xyz[i, 0], xyz[i, 1], xyz[i, 2]
        if cull and normals[i, 0] * x + normals[i, 1] * y + normals[i, 2] * z > 0:
            x, y, z = 0.0, 0.0, -1.0
        out[i, 0], out[i, 1], out[i, 2] = x, y, z
        if z > 1e-6:
            u = fx * x / z + cx
            v = fy * y / z + cy
            box[0], box[1] = min(box[0], u), min(box[1], v)
            box[2], box[3] = max(box[2], u), max(box[3], v)


def cull_and_bound(xyz: np.ndarray, normals: np.ndarray | None, intr: Intrinsics) -> tuple[np.ndarray, np.ndarray | None]:
    """Camera points (M, 3) with back faces (``normals`` (M, 3) facing away) moved behind the
    camera so they are not drawn, and the image box ``[[u_min, v_min], [u_max, v_max]]`` of the
    points in front (None if none). Compiled; :func:`cull_and_bound_reference` is the NumPy version."""
    xyz = np.ascontiguousarray(xyz, np.float64)
    out, box = np.empty_like(xyz), np.empty(4)
    nrm = np.ascontiguousarray(normals, np.float64) if normals is not None else np.zeros((1, 3))
    _cull_and_bound_kernel(xyz, nrm, normals is not None, intr.fx, intr.fy, intr.cx, intr.cy, out, box)
    return out, (box.reshape(2, 2) if np.isfinite(box[0]) else None)


@njit(cache=True)
def _posed_points_kernel(points, normals, R, t, out):  # pragma: no cover - compiled
    # out_i = R·p_i + t, or (0, 0, −1) (behind the camera, not drawn) where R·n_i faces away.
    for i in range(points.shape[0]):
        p0, p1, p2 = points[i, 0], points[i, 1], points[i, 2]
        x = R[0, 0] * p0 + R[0, 1] * p1 + R[0, 2] * p2 + t[0]
        y = R[1, 0] * p0 + R[1, 1] * p1 + R[1, 2] * p2 + t[1]
        z = R[2, 0] * p0 + R[2, 1] * p1 + R[2, 2] * p2 + t[2]
        n0, n1, n2 = normals[i, 0], normals[i, 1], normals[i, 2]
        facing = ((R[0, 0] * n0 + R[0, 1] * n1 + R[0, 2] * n2) * x + (R[1, 0] * n0 + R[1, 1] * n1 + R[1, 2] * n2) * y
                  + (R[2, 0] * n0 + R[2, 1] * n1 + R[2, 2] * n2) * z)
        if facing > 0:
            x, y, z = 0.0, 0.0, -1.0
        out[i, 0], out[i, 1], out[i, 2] = x, y, z


def posed_points(points: np.ndarray, normals: np.ndarray, R: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Object points (M, 3) in the camera at pose ``R, t``, the back faces (normals facing away)
    moved behind the camera: ready for :func:`~worldtrack.pose.template.sparse_template_pixels` without ``normals``.
    Compiled; the same as ``cull_and_bound_reference(points @ R.T + t, normals @ R.T, …)[0]``."""
    out = np.empty((len(points), 3))
    _posed_points_kernel(np.ascontiguousarray(points, np.float64), np.ascontiguousarray(normals, np.float64),
                         np.ascontiguousarray(R, np.float64), np.ascontiguousarray(t, np.float64), out)
    return out


def cull_and_bound_reference(xyz: np.ndarray, normals: np.ndarray | None, intr: Intrinsics):
    """:func:`cull_and_bound` in NumPy."""
    xyz = np.array(xyz, float)
    if normals is not None:
        xyz[(np.asarray(normals) * xyz).sum(1) > 0] = (0.0, 0.0, -1.0)
    z = xyz[:, 2]
    front = z > 1e-6
    if not front.any():
        return xyz, None
    uv = np.column_stack([intr.fx * xyz[front, 0] / z[front] + intr.cx, intr.fy * xyz[front, 1] / z[front] + intr.cy])
    return xyz, np.array([uv.min(0), uv.max(0)])


def sample_bilinear(image: np.ndarray, xyz: np.ndarray, intr: Intrinsics) -> np.ndarray:
    """``image`` read bilinearly where camera points (n, 3) project."""
    if len(xyz) == 0:
        return np.zeros(0)
    u = intr.fx * xyz[:, 0] / xyz[:, 2] + intr.cx
    v = intr.fy * xyz[:, 1] / xyz[:, 2] + intr.cy
    return cv2.remap(image.astype(np.float32), u.astype(np.float32)[None], v.astype(np.float32)[None],
                     cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)[0].astype(float)


def learn_appearance(points: np.ndarray, normals: np.ndarray, grey: np.ndarray, intr: Intrinsics,
                     R: np.ndarray, t: np.ndarray, min_facing: float = 0.2) -> np.ndarray:
    """Albedo (M,) of model points read from a frame where the model's pose is known.

    What the paper takes from its KinectFusion model, learnt here from one frame: each point the
    z-buffer shows (and that faces the camera by more than ``min_facing`` = cos of the view angle)
    gets the grey level under its projection; hidden points stay NaN (unknown).
    """
    xyz = np.asarray(points, float) @ np.asarray(R, float).T + np.asarray(t, float)
    r = splat(xyz, intr)
    seen = np.zeros(len(xyz), bool)
    seen[r.index[r.index >= 0]] = True
    view = -xyz / np.linalg.norm(xyz, axis=1, keepdims=True)
    seen &= np.abs(((np.asarray(normals) @ np.asarray(R, float).T) * view).sum(1)) > min_facing   # either winding
    albedo = np.full(len(xyz), np.nan, np.float32)
    albedo[seen] = sample_bilinear(np.asarray(grey, np.float32), xyz[seen], intr)
    return albedo
