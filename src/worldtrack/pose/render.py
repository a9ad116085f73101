"""Rendering a point model with a z-buffer and picking its sparse template (seed 003, §2.2, §4.3).

To estimate the pose at time t the model is drawn at the pose of t−1 with hidden surfaces removed
(a z-buffer over the model's surface points), and only the points where the rendered intensity is
a local maximum or minimum are kept (the *sparse template*, N ≤ 1024 for a face, N = 128 for a
body). For RGB-D the z-buffer's own local extrema give the depth template (N′ points).

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


def local_extrema(image: np.ndarray, valid: np.ndarray, radius: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Pixels of ``image`` strictly above or below all others of their (2r+1)² neighbourhood.

    Only pixels whose whole neighbourhood is ``valid`` count (no extrema on the silhouette).
    Returns ``(rows, cols)`` of the extrema and their strength ``|I − local mean|`` as (n,) arrays
    packed as ``(np.stack([rows, cols], 1), strength)``.
    """
    img = np.where(valid, image, 0).astype(np.float32)
    k = np.ones((2 * radius + 1, 2 * radius + 1), np.uint8)
    inner = cv2.erode(valid.astype(np.uint8), k, borderValue=0).astype(bool)
    ring = k.copy()
    ring[radius, radius] = 0                                         # the neighbours, not the pixel itself
    hi = cv2.dilate(np.where(valid, img, -np.inf).astype(np.float32), ring)
    lo = cv2.erode(np.where(valid, img, np.inf).astype(np.float32), ring)
    mean = cv2.blur(img, (2 * radius + 3, 2 * radius + 3))
    ext = inner & ((img > hi) | (img < lo))                          # strictly above / below every neighbour
    rc = np.argwhere(ext)
    strength = np.abs(img - mean)[ext]
    return rc, strength


def gradient_maxima(image: np.ndarray, valid: np.ndarray, min_gradient: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """Pixels where the gradient magnitude ``|∇I|`` (Sobel / 8, grey levels per pixel) is strictly
    above its eight neighbours and above ``min_gradient``: the crests of texture edges.

    Only pixels whose 5×5 neighbourhood is ``valid`` count. Returns ``(rows, cols)`` stacked (n, 2)
    and their ``|∇I|`` (n,), like :func:`local_extrema`.

    >>> yy, xx = np.mgrid[0:21, 0:21]
    >>> blob = (100 * np.exp(-((xx - 10.3) ** 2 + (yy - 9.8) ** 2) / 8)).astype(np.float32)   # σ = 2 px
    >>> rc, g = gradient_maxima(blob, np.ones((21, 21), bool))
    >>> len(rc) > 0, bool(np.all(np.abs(np.hypot(rc[:, 0] - 9.8, rc[:, 1] - 10.3) - 2) < 0.5))   # on r = σ
    (True, True)
    """
    img = np.where(valid, image, 0).astype(np.float32)
    g = np.hypot(cv2.Sobel(img, cv2.CV_32F, 1, 0, ksize=3, scale=0.125),
                 cv2.Sobel(img, cv2.CV_32F, 0, 1, ksize=3, scale=0.125))
    inner = cv2.erode(valid.astype(np.uint8), np.ones((5, 5), np.uint8), borderValue=0).astype(bool)
    ring = np.ones((3, 3), np.uint8)
    ring[1, 1] = 0
    crest = inner & (g > cv2.dilate(g, ring)) & (g > min_gradient)
    return np.argwhere(crest), g[crest]


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
    moved behind the camera: ready for :func:`sparse_template_pixels` without ``normals``.
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


def _crop(uv: np.ndarray, intr: Intrinsics, margin: int = 4) -> tuple[Intrinsics, int, int] | None:
    """Intrinsics of the image window around projected points ``uv`` (n, 2); None if off-image."""
    lo = np.floor([uv[:, 0].min(), uv[:, 1].min()]).astype(int) - margin      # per column: a fast reduction
    hi = np.ceil([uv[:, 0].max(), uv[:, 1].max()]).astype(int) + margin
    u0, v0 = max(lo[0], 0), max(lo[1], 0)
    u1, v1 = min(hi[0], intr.width - 1), min(hi[1], intr.height - 1)
    if u1 <= u0 or v1 <= v0:
        return None
    return Intrinsics(intr.fx, intr.fy, intr.cx - u0, intr.cy - v0, u1 - u0 + 1, v1 - v0 + 1), u0, v0


def _strongest(rc: np.ndarray, strength: np.ndarray, n: int) -> np.ndarray:
    return rc[np.argsort(-strength, kind="stable")[:n]]


def _grid_fill(valid: np.ndarray, taken: np.ndarray, n: int) -> np.ndarray:
    """Up to ``n`` pixels of ``valid`` not in ``taken`` on an even grid (rows, cols)."""
    free = valid.copy()
    if len(taken):
        free[taken[:, 0], taken[:, 1]] = False
    rc = np.argwhere(free)
    if len(rc) <= n:
        return rc
    return rc[np.linspace(0, len(rc) - 1, n).astype(int)]


def smooth_valid(image: np.ndarray, valid: np.ndarray, sigma: float) -> np.ndarray:
    """Gaussian smoothing of ``image`` over ``valid`` pixels only (normalised convolution); fills
    the small holes a point z-buffer leaves. NaN where no valid pixel is near."""
    v = valid.astype(np.float32)
    num = cv2.GaussianBlur(np.where(valid, image, 0).astype(np.float32), (0, 0), sigma)
    den = cv2.GaussianBlur(v, (0, 0), sigma)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(den > 0.2, num / den, np.nan)


class TemplatePixels(NamedTuple):
    """A sparse template at one pose: model point indices of the colour template, their grey
    level as drawn (smoothed like the input), and the model point indices of the depth template."""

    colour: np.ndarray
    value: np.ndarray
    depth: np.ndarray


def sparse_template_pixels(albedo: np.ndarray, xyz: np.ndarray, intr: Intrinsics, n_colour: int,
                           n_depth: int = 0, radius: int = 1, sigma: float = 1.0,
                           select_sigma: float = 0.5, normals: np.ndarray | None = None,
                           groups: np.ndarray | None = None, edge_fill: bool = False) -> TemplatePixels:
    """The sparse template of a model drawn at one pose (§2.2, §4.3).

    Parameters
    ----------
    albedo : (M,) grey level of the model points, NaN = unknown
    xyz : (M, 3) the model points in the camera frame at the previous pose
    n_colour : at most this many points where the drawn intensity (smoothed by ``sigma`` px, as
        the input is) is a local max/min, strongest ``|I − local mean|`` first
    sigma, select_sigma : Gaussian σ (px) of the drawing the values are read from, and of the one
        whose extrema are picked
    normals : (M, 3) camera-frame normals — points facing away are not drawn (back-face culling,
        so a back surface cannot show through the gaps between a sparse model's points)
    groups : (M,) int part of each point — then every part drawn gets an equal share of
        ``n_colour`` and ``n_depth`` (a share a part cannot fill goes to the others)
    edge_fill : when the extrema number fewer than ``n_colour``, fill up with the crests of the
        drawing's gradient magnitude (:func:`gradient_maxima`), strongest first — points whose
        image value changes to first order with the pose (at an extremum the change is second
        order); extrema stay first. Not with ``groups``.
    n_depth : this many points where the z-buffer depth is a local max/min, filled up on an even
        grid over the visible surface when there are fewer (planar faces have none)

    Returns
    -------
    TemplatePixels
    """
    empty = TemplatePixels(np.zeros(0, int), np.zeros(0), np.zeros(0, int))
    xyz, box = cull_and_bound(xyz, normals, intr)
    if box is None:
        return empty
    win = _crop(box, intr)
    if win is None:
        return empty
    r = splat(xyz, win[0])
    drawn = r.index >= 0
    k = np.ones((3, 3), np.uint8)
    surface = cv2.morphologyEx(drawn.astype(np.uint8), cv2.MORPH_CLOSE, k).astype(bool)   # z-buffer holes closed
    raw = np.where(drawn, albedo[np.maximum(r.index, 0)], np.nan)
    intensity = smooth_valid(np.nan_to_num(raw), drawn & np.isfinite(raw), sigma)
    known = surface & np.isfinite(intensity)
    known = cv2.erode(known.astype(np.uint8), k, iterations=2, borderValue=0).astype(bool)   # off the silhouette
    # Extrema of the lightly smoothed drawing (more of them, N ≤ n_colour); values from the smoothed one.
    fine = smooth_valid(np.nan_to_num(raw), drawn & np.isfinite(raw), select_sigma) if select_sigma > 0 else raw
    rc, strength = local_extrema(np.nan_to_num(fine), known & np.isfinite(fine), radius)
    if groups is None:
        rc = _strongest(rc, strength, n_colour) if len(rc) else rc
        if edge_fill and len(rc) < n_colour:
            rc_e, g_e = gradient_maxima(np.nan_to_num(fine), known & np.isfinite(fine))
            rc = np.concatenate([rc, _strongest(rc_e, g_e, n_colour - len(rc))]) if len(rc_e) else rc
    else:
        rc = _by_group(rc, strength, groups[np.maximum(r.index[tuple(rc.T)], 0)], n_colour)
    colour = _nearest_point(r.index, drawn, rc)
    first = np.sort(np.unique(colour, return_index=True)[1])        # a point reached from two pixels: once
    colour, rc = colour[first], rc[first]
    value = _bilinear(np.nan_to_num(intensity), xyz[np.maximum(colour, 0)], win[0])   # at the point's projection
    depth_idx = np.zeros(0, int)
    if n_depth > 0:
        inner = cv2.erode(drawn.astype(np.uint8), k, iterations=2, borderValue=0).astype(bool)
        rc_d, s_d = local_extrema(np.where(drawn, r.depth, 0), drawn, radius)
        if groups is None:
            pick = _strongest(rc_d, s_d, n_depth)
            pick = np.concatenate([pick, _grid_fill(inner, pick, n_depth - len(pick))]) if len(pick) < n_depth else pick
        else:
            grid = _grid_fill(inner, rc_d, 4 * n_depth)
            cand = np.concatenate([rc_d, grid])
            score = np.concatenate([s_d + 1.0, np.zeros(len(grid))])          # extrema first, then the grid
            pick = _by_group(cand, score, groups[np.maximum(r.index[tuple(cand.T)], 0)], n_depth)
        depth_idx = r.index[tuple(pick.T)] if len(pick) else depth_idx
    keep = (colour >= 0) & np.isfinite(albedo[np.maximum(colour, 0)])   # an occluder's point is no template point
    return TemplatePixels(colour[keep], np.asarray(value, float)[keep], np.asarray(depth_idx, int))


def _bilinear(image: np.ndarray, xyz: np.ndarray, intr: Intrinsics) -> np.ndarray:
    """``image`` read bilinearly where camera points (n, 3) project."""
    if len(xyz) == 0:
        return np.zeros(0)
    u = intr.fx * xyz[:, 0] / xyz[:, 2] + intr.cx
    v = intr.fy * xyz[:, 1] / xyz[:, 2] + intr.cy
    return cv2.remap(image.astype(np.float32), u.astype(np.float32)[None], v.astype(np.float32)[None],
                     cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)[0].astype(float)


def equal_shares(counts: np.ndarray, n: int) -> np.ndarray:
    """Quotas (G,) summing to ``min(n, Σ counts)``: every group the same share of ``n``, a share a
    group cannot fill passed on to the others (water-filling); a remainder smaller than the number
    of open groups goes one each to the first of them."""
    counts = np.asarray(counts, int)
    quota = np.zeros(len(counts), int)
    left = int(n)
    while left > 0:
        open_ = np.flatnonzero(quota < counts)
        if len(open_) == 0:
            break
        share = left // len(open_)
        if share == 0:
            quota[open_[:left]] += 1
            break
        add = np.minimum(counts[open_] - quota[open_], share)
        quota[open_] += add
        left -= int(add.sum())
    return quota


def _by_group(rc: np.ndarray, strength: np.ndarray, group: np.ndarray, n: int) -> np.ndarray:
    """Up to ``n`` pixels, strongest first within each group, the groups sharing ``n`` equally."""
    if len(rc) == 0:
        return rc
    order = np.argsort(-strength, kind="stable")
    rc, group = rc[order], group[order]
    names, slot, counts = np.unique(group, return_inverse=True, return_counts=True)
    rank = np.zeros(len(rc), int)
    for g in range(len(names)):
        rank[slot == g] = np.arange(counts[g])
    return rc[rank < equal_shares(counts, n)[slot]]


def _nearest_point(index: np.ndarray, drawn: np.ndarray, rc: np.ndarray) -> np.ndarray:
    """Model point drawn at each pixel ``rc``, or at its nearest drawn 3×3 neighbour (−1: none)."""
    if len(rc) == 0:
        return np.zeros(0, int)
    out = index[rc[:, 0], rc[:, 1]].astype(int)
    h, w = index.shape
    for dr, dc in ((0, 1), (1, 0), (0, -1), (-1, 0), (1, 1), (-1, -1), (1, -1), (-1, 1)):
        miss = out < 0
        if not miss.any():
            break
        rr = np.clip(rc[miss, 0] + dr, 0, h - 1)
        cc = np.clip(rc[miss, 1] + dc, 0, w - 1)
        out[miss] = index[rr, cc]
    return out


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
    albedo[seen] = _bilinear(np.asarray(grey, np.float32), xyz[seen], intr)
    return albedo
