"""The height column (seed 004, eqs. 11–12): how much of an object stands at a particle's floor position.

For a particle at floor position ``(x_i, y_i)`` the points ``(x_i, y_i, k·dz)``, ``k = 0 … T``, are
projected and those that land on ``F > γ`` counted::

    π_i = Σ_k δ(x_i, y_i, k·dz),   δ = 1 if F(x_i, y_i, k·dz) > γ else 0          (eqs. 11, 12)

A particle inside the object keeps hitting the object's image all the way up its column; one that is
merely on the same line of sight as the object (in front of or behind it, Fig. 5) does not.

The kernel also returns a second statistic of the same samples, the log-likelihood ratio of the best
object top (``ratio``, worldtrack's): an object standing at the particle and reaching up to sample
``k`` explains samples ``0 … k``; each adds ``on`` if it hits, ``off`` if it reads background and
nothing if it reads "no evidence" (a shadow, label 2; an occluded sample). A ring round the column
must read background (the column's counterpart of seed 000's −1 ring): ``n_below`` samples below the
floor and the ``n_above`` samples above the top add ``below`` (< 0) each if they hit. The best top
``k ≥ k_min`` is kept. A column can be a thin cylinder (``radius > 0``): a sample hits if its pixel
or one of the two pixels ``f_x·radius / depth`` to its left and right hits.

A sample that projects outside the image, or lies behind the camera, does not make the camera "see"
the particle; it reads background (the paper) or, with ``outside_unknown``, no evidence, and is
never counted in ``counts``. Pixels are read at the nearest pixel centre.

:func:`column_counts` is the compiled kernel; :func:`column_counts_reference` the same written
plainly with :meth:`Camera.project` (the tests check that they agree).

>>> column_heights(0.3, 0.1).tolist()
[0.0, 0.1, 0.2, 0.30000000000000004]
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from worldtrack.geometry._kernels import camera_to_pixel, lens, nearest_index
from worldtrack.geometry.camera import Camera
from worldtrack.trackers.particle.likelihood.reading import (OCCLUDED, OUT_OF_VIEW, ReadAs, box_of, filter_rows,
                                                                 occluded, per_filter_int, pixel_scales, read_line)


class ColumnSpec(NamedTuple):
    """The column and how its samples score (one per tracker; :func:`column_spec` builds it).

    heights (S,) float64, metres — ``n_below`` heights below the floor, then ``k·dz``, k = 0 … T,
    then ``n_above`` heights above ``T·dz``; radius, metres — 0: a line of points (the paper), > 0: a
    thin cylinder; on, off, below — log-ratio terms of a sample on / off the object and of a ring
    sample that reads object; n_below, n_above — how many of ``heights`` are ring samples; k_min — the
    top is searched from this index of ``heights`` up; top_sigma, metres — with ``> 0``, a top at
    height z adds ``−(z − tops[i])² / (2·top_sigma²)``; outside_unknown — a sample out of view adds
    nothing (no evidence) instead of ``off``.
    """

    heights: np.ndarray
    radius: float
    on: float
    off: float
    below: float
    n_below: int
    n_above: int
    k_min: int
    top_sigma: float
    outside_unknown: bool


class ColumnOut(NamedTuple):
    """The column kernel's outputs for N particles.

    counts (N,) int32 — samples ``k·dz``, k = 0 … T, on ``F > γ`` (π_i, eq. 11); ratio (N,) float64 —
    the best log-likelihood ratio; top (N,) int32 — its index into ``heights``; seen (N,) bool — some
    sample projects into the image; hidden (N,) int32 — how many of the lowest samples are hidden
    (occluded, or out of view with ``outside_unknown``).
    """

    counts: np.ndarray
    ratio: np.ndarray
    top: np.ndarray
    seen: np.ndarray
    hidden: np.ndarray

    @staticmethod
    def empty(n: int) -> "ColumnOut":
        return ColumnOut(np.empty(n, dtype=np.int32), np.empty(n, dtype=np.float64), np.empty(n, dtype=np.int32),
                         np.empty(n, dtype=np.bool_), np.empty(n, dtype=np.int32))


def column_spec(heights: np.ndarray, on: float = 1.0, off: float = -1.0, k_min: int = 0, radius: float = 0.0,
                below: float = 0.0, n_below: int = 0, n_above: int = 0, top_sigma: float = 0.0,
                outside_unknown: bool = False) -> ColumnSpec:
    """A :class:`ColumnSpec` with the kernel's types (parameters as its fields)."""
    return ColumnSpec(np.ascontiguousarray(heights, dtype=np.float64), float(radius), float(on), float(off),
                      float(below), int(n_below), int(n_above), int(k_min), float(top_sigma), bool(outside_unknown))


def column_heights(max_height: float, dz: float) -> np.ndarray:
    """The column's sample heights ``k·dz``, ``k = 0 … T`` with ``T = round(max_height / dz)``, metres."""
    T = int(round(max_height / dz))
    return np.arange(T + 1, dtype=float) * dz


# A compiled kernel over particles × samples: one pass reads, labels and scores each column (the
# parts share the per-sample labels and projections), so it is longer than 100 lines.
@njit(cache=True)
def column_counts(xy, camera, column, reading, out):
    """Height-column likelihood of the particles of one or more filters for one camera, in place.

    Parameters
    ----------
    xy : (N, 2) float64, metres — particles' floor positions (the columns' feet)
    camera : CameraArgs
    column : ColumnSpec
    reading : Reading — the labels and boxes, each particle's filter and object height
    out : ColumnOut — written
    """
    codes, boxes, which, pairs, depths, mes = (reading.codes, reading.boxes, reading.which, reading.pairs,
                                               reading.depths, reading.mes)
    margin, px_scale, k_lo, tops = reading.margin, reading.px_scale, reading.k_lo, reading.tops
    heights, radius, on, off, below = column.heights, column.radius, column.on, column.off, column.below
    n_below, n_above, top_sigma, outside_unknown = column.n_below, column.n_above, column.top_sigma, \
        column.outside_unknown
    counts, ratio, top, seen, hidden = out.counts, out.ratio, out.top, out.seen, out.hidden
    R, t, centre, has_dist = camera.R, camera.t, camera.centre, camera.has_dist
    H, W = codes.shape
    S = heights.shape[0]
    last = S - n_above - 1
    k_min = max(column.k_min, n_below)
    lens_ = lens(camera.K, camera.dist)
    fx = lens_[0]
    r02, r12, r22 = R[0, 2], R[1, 2], R[2, 2]
    label = np.zeros(S, dtype=np.uint8)
    us = np.zeros(S)
    vs = np.zeros(S)
    wt = np.ones(S)
    weighted = False                                        # wt holds a weighted particle's lengths
    for i in range(xy.shape[0]):
        box = box_of(boxes, which[i])
        me = mes[which[i]]
        ps = px_scale[which[i]]
        hb = 0                                              # hidden samples from the bottom up so far
        depth = math.hypot(xy[i, 0] - centre[0], xy[i, 1] - centre[1])
        # Camera-frame coordinates of the floor point; the column is linear in z.
        b0 = R[0, 0] * xy[i, 0] + R[0, 1] * xy[i, 1] + t[0]
        b1 = R[1, 0] * xy[i, 0] + R[1, 1] * xy[i, 1] + t[1]
        b2 = R[2, 0] * xy[i, 0] + R[2, 1] * xy[i, 1] + t[2]
        s = False
        for k in range(S):
            z = heights[k]
            cz = b2 + r22 * z
            u, v = camera_to_pixel(b0 + r02 * z, b1 + r12 * z, cz, lens_, has_dist)
            us[k] = u
            vs[k] = v
            lab = OUT_OF_VIEW                               # until a pixel in the image is read
            iv = nearest_index(v, H)
            if iv >= 0:
                # The centre, then (cylinder) the pixels ``radius`` to the left and right at this
                # depth, until one reads object: object if any reads object, else no evidence if
                # any reads so — as a pixel in the box of a nearer object does (looked up last,
                # only if nothing else decides).
                iu0 = nearest_index(u, W)
                lab, o0 = read_line(codes, box, iu0, iv, lab)
                o1 = o2 = False
                iu1 = iu2 = -1
                if lab != 1 and radius > 0.0:
                    d = fx * radius / cz
                    if d > 0.0:
                        iu1 = nearest_index(u - d, W)
                        lab, o1 = read_line(codes, box, iu1, iv, lab)
                        if lab != 1:
                            iu2 = nearest_index(u + d, W)
                            lab, o2 = read_line(codes, box, iu2, iv, lab)
                if lab == 0 and (o0 or o1 or o2):
                    if ((o0 and occluded(pairs, depths, me, iu0, iv, depth, margin))
                            or (o1 and occluded(pairs, depths, me, iu1, iv, depth, margin))
                            or (o2 and occluded(pairs, depths, me, iu2, iv, depth, margin))):
                        lab = OCCLUDED
                if lab != OUT_OF_VIEW:
                    s = True
            label[k] = lab
            # Hidden from the bottom up: occluded, or out of view when that is no evidence.
            if hb == k and (lab == OCCLUDED or (lab == OUT_OF_VIEW and outside_unknown)):
                hb = k + 1
        hidden[i] = hb
        if ps > 0.0:
            for k in range(S):
                wt[k] = _sample_length(us, vs, k) * ps
            weighted = True
        elif weighted:
            for k in range(S):
                wt[k] = 1.0
            weighted = False
        c = 0
        for k in range(n_below, last + 1):
            if label[k] == 1 or label[k] == 2 or label[k] == OCCLUDED:
                c += 1
        # The samples below ``k_lo`` of the particle's filter read no evidence.
        for k in range(min(k_lo[which[i]], S)):
            label[k] = 2
        base = 0.0
        for k in range(n_below):
            if label[k] == 1:
                base += below * wt[k]
        # Ring above the top: the weight of the ``n_above`` samples above index k that read object.
        ring = 0.0
        for k in range(k_min + 1, min(k_min + n_above, S - 1) + 1):
            if label[k] == 1:
                ring += wt[k]
        run = base
        best = -1e300
        kbest = k_min
        for k in range(n_below, last + 1):
            lab = label[k]
            if lab == 1:
                run += on * wt[k]
            elif lab == 0 or (lab == OUT_OF_VIEW and not outside_unknown):
                run += off * wt[k]
            if k >= k_min:
                if k > k_min and n_above > 0:
                    # Slide the ring up by one sample: k leaves it, k + n_above enters.
                    if label[k] == 1:
                        ring -= wt[k]
                    if k + n_above < S and label[k + n_above] == 1:
                        ring += wt[k + n_above]
                score = run + ring * below
                if top_sigma > 0.0:
                    e = (heights[k] - tops[i]) / top_sigma
                    score -= 0.5 * e * e
                if score > best:
                    best = score
                    kbest = k
        counts[i] = c
        ratio[i] = best
        top[i] = kbest
        seen[i] = s


@njit(cache=True, inline="always")
def _sample_length(us, vs, k):
    """Image length (pixels) a column sample stands for: half the distance between its neighbours'
    projections (one neighbour at the ends); 0 where a projection is undefined."""
    S = us.shape[0]
    lo = k - 1 if k > 0 else k
    hi = k + 1 if k < S - 1 else k
    if hi == lo:
        return 0.0
    du = us[hi] - us[lo]
    dv = vs[hi] - vs[lo]
    if not (du == du and dv == dv):
        return 0.0
    return math.sqrt(du * du + dv * dv) / (hi - lo)


# ---------------------------------------------------------------------------- NumPy reference

def column_points(xy: np.ndarray, heights: np.ndarray) -> np.ndarray:
    """(N, S, 3) world points of vertical columns: floor positions ``xy`` (N, 2) at ``heights`` (S,), metres."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    heights = np.asarray(heights, dtype=float)
    pts = np.empty((len(xy), len(heights), 3))
    pts[:, :, :2] = xy[:, None, :]
    pts[:, :, 2] = heights[None, :]
    return pts


def pixels(camera: Camera, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Nearest pixel (iu, iv) of world points (..., 3) and whether they fall in the image."""
    uv = camera.project(points)
    inside = camera.in_image(uv) & np.isfinite(uv).all(axis=-1)
    iu = np.where(inside, np.floor(np.nan_to_num(uv[..., 0]) + 0.5), 0).astype(np.int64)
    iv = np.where(inside, np.floor(np.nan_to_num(uv[..., 1]) + 0.5), 0).astype(np.int64)
    return iu, iv, inside


def readable(owner: np.ndarray | None, boxes: np.ndarray, iu: np.ndarray, iv: np.ndarray) -> np.ndarray:
    """False where a pixel lies in another object's box; ``boxes`` (N, 4) is the own box of the
    particle each row of ``iu, iv`` (N, ...) belongs to."""
    if owner is None:
        return np.ones(iu.shape, dtype=bool)
    b = boxes.reshape((len(boxes),) + (1,) * (iu.ndim - 1) + (4,))
    own = (iu >= b[..., 0]) & (iu < b[..., 1]) & (iv >= b[..., 2]) & (iv < b[..., 3])
    return owner[iv, iu].astype(int) <= own


def column_counts_reference(camera: Camera, hit: np.ndarray, xy: np.ndarray, column: ColumnSpec,
                            read: ReadAs | None = None, tops: np.ndarray | None = None):
    """:func:`column_counts` written plainly: every (particle, height) point through :meth:`Camera.project`.

    Returns a :class:`ColumnOut` (int64 counts, top and hidden).
    """
    read = read or ReadAs()
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    heights = column.heights
    n, s = len(xy), len(heights)
    n_below, n_above, on, off, below = column.n_below, column.n_above, column.on, column.off, column.below
    boxes, mes, which = filter_rows(read.box, read.me, read.which, n)
    own_box, own_index = boxes[which], mes[which][:, None]
    scale = pixel_scales(read.px_scale, len(boxes))[which][:, None]
    uv, depth = camera.project(column_points(xy, heights), return_depth=True)
    hits = np.zeros((n, s), dtype=bool)
    unsure = np.zeros((n, s), dtype=bool)
    seen = np.zeros(n, dtype=bool)
    in_view = np.zeros((n, s), dtype=bool)               # some pixel of the sample is in the image
    hidden_by = np.zeros((n, s), dtype=bool)             # some pixel in a nearer object's box
    offsets = [0.0] if column.radius <= 0 else [0.0, -1.0, 1.0]
    with np.errstate(divide="ignore", invalid="ignore"):
        d = np.where(depth > 1e-9, camera.K[0, 0] * column.radius / depth, 0.0)
    for o in offsets:
        uo = uv.copy()
        uo[..., 0] += o * d
        inside = camera.in_image(uo) & np.isfinite(uo).all(axis=-1)
        iu = np.where(inside, np.floor(np.nan_to_num(uo[..., 0]) + 0.5), 0).astype(np.int64)
        iv = np.where(inside, np.floor(np.nan_to_num(uo[..., 1]) + 0.5), 0).astype(np.int64)
        ok = inside & readable(read.owner, own_box, iu, iv)
        hits |= ok & (hit[iv, iu] == 1)
        unsure |= ok & (hit[iv, iu] == 2)
        if read.occluders is not None and read.occluders.pairs.size:
            # In a nearer object's box: occluded, no evidence.
            particle_depth = camera.floor_rays(xy)[1][:, None]
            hidden_by |= inside & ~ok & (read.occluders.depth_for(own_index, iv, iu) < particle_depth - read.margin)
        seen |= inside.any(axis=1)
        in_view |= inside
    hidden_by &= ~hits & ~unsure
    unsure |= hidden_by
    unsure &= ~hits
    hid = hidden_by | (~in_view if column.outside_unknown else False)
    hidden = np.where(hid.all(axis=1), s, np.argmin(hid, axis=1))
    if column.outside_unknown:
        unsure |= ~in_view
    counts = ((hits | unsure) & in_view)[:, n_below:s - n_above].sum(axis=1).astype(np.int64)
    # The samples below each filter's k_lo read no evidence.
    cut = np.arange(s)[None, :] < per_filter_int(read.k_lo, len(boxes))[which][:, None]
    hits, unsure = hits & ~cut, unsure | cut
    # Each sample stands for half the image distance between its neighbours (one at the ends).
    lo = np.maximum(np.arange(s) - 1, 0)
    hi = np.minimum(np.arange(s) + 1, s - 1)
    with np.errstate(invalid="ignore"):
        length = np.nan_to_num(np.hypot(*(uv[:, hi] - uv[:, lo]).transpose(2, 0, 1)) / (hi - lo), nan=0.0)
    weight = np.where(scale > 0, length * scale, 1.0)
    last = s - n_above                                   # one past the highest possible top
    terms = np.where(hits, on, np.where(unsure, 0.0, off)) * weight
    terms[:, :n_below] = np.where(hits[:, :n_below], below, 0.0) * weight[:, :n_below]
    run = np.cumsum(terms[:, :last], axis=1)
    # The ring above a top at index k: samples k + 1 … k + n_above that read object.
    ring = np.zeros_like(run)
    hit_weight = np.where(hits, weight, 0.0)
    for j in range(1, n_above + 1):
        ring += np.pad(hit_weight[:, j:last + j], ((0, 0), (0, max(0, last + j - s))))[:, :last]
    run = run + below * ring
    if column.top_sigma > 0 and tops is not None:
        z = np.asarray(heights, dtype=float)[None, :last]
        run = run - 0.5 * ((z - np.asarray(tops, dtype=float)[:, None]) / column.top_sigma) ** 2
    run[:, :max(column.k_min, n_below)] = -np.inf
    top = np.argmax(run, axis=1)
    return ColumnOut(counts, run[np.arange(n), top], top, seen, hidden)


__all__ = ["ColumnOut", "ColumnSpec", "column_counts", "column_counts_reference", "column_heights", "column_points",
           "column_spec"]
