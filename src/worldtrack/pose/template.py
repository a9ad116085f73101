"""The sparse template (paper 003, §2.2, §4.3): the points of a model drawn at the previous pose
where the rendered intensity is a local maximum or minimum (N ≤ 1024 for a face, N = 128 for a
body), and for RGB-D the z-buffer's own local extrema (the depth template, N′ points).
"""

from __future__ import annotations

from typing import NamedTuple

import cv2
import numpy as np

from worldtrack.pose.render import Intrinsics, sample_bilinear, cull_and_bound, splat


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
    if select_sigma == sigma:
        fine = intensity
    else:
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
    value = sample_bilinear(np.nan_to_num(intensity), xyz[np.maximum(colour, 0)], win[0])   # at the point's projection
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
