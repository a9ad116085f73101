"""Scoring ellipsoid candidates against a ternary foreground image (seed 000 §4).

The simulated image of a candidate is the union ("joint image") of every person's visible
ellipse: 1 inside, −1 in a ring of ``ring_px`` pixels around it, 0 elsewhere. The real image is
the same ternary coding of the foreground mask. The score is the paper's eq. 5::

    E = Σ sim(x, y)·real(x, y) / Σ |sim(x, y)|        (sums where sim ≠ 0)

Differences from the paper, all to make it faster or well-defined:

* Only the pixels a candidate can touch are summed: the union of the candidates' bounding boxes
  (ring included), on a grid of stride ``s`` chosen so that about ``target_pixels`` pixels are
  visited however large the person appears (``target_pixels = 0``: every pixel, as published).
* The ring of an ellipse with semi-axes (a, b) is the ellipse (a + r, b + r) minus the ellipse —
  the dilation of an ellipse by r pixels up to a sliver at the ends of the major axis.
* A pixel hidden by an obstacle nearer than the person (floor distance, the paper's §3.3) is 0 for
  that person in both the ellipse and its ring: occluded pixels carry no evidence either way.
* With lens distortion each real pixel is tested at its undistorted position (exact silhouette).

Optionally (``count_unexplained``, worldtrack's default in tracking mode) foreground pixels of the
region that no simulated person covers are added to the denominator. Eq. 5 alone measures only
how much of the simulation is right, not how much of the foreground it explains: an ellipse that
drifts away along the viewing direction, shrinking into the upper body while the feet are left
unexplained, loses little. With the extra term the score is a Jaccard-like overlap of the two
ternary images and such drift costs.

Ellipses are passed in a normal form of 5 numbers ``(cx, cy, a11, a12, a22)``: a point (u, v) of
the ideal image is inside when ``a11·du² + 2·a12·du·dv + a22·dv² < 1`` with ``du = u − cx``,
``dv = v − cy``. :func:`ellipse_forms` computes them for people; :func:`score_candidates` is the
optimised kernel and :func:`score_candidates_reference` the plain NumPy version it is tested
against.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
from numba import njit

from worldtrack.geometry import quadric

#: Samples on an ellipse's outline used to bound it after lens distortion.
_OUTLINE_SAMPLES = 24


@njit(cache=True)
def _distort_ideal_pixel(u, v, K, dist):
    """Ideal (pinhole) pixel → real pixel under OpenCV distortion k1, k2, p1, p2, k3."""
    fx, s, cx, fy, cy = K[0, 0], K[0, 1], K[0, 2], K[1, 1], K[1, 2]
    y = (v - cy) / fy
    x = (u - cx - s * y) / fx
    k1, k2, p1, p2, k3 = dist[0], dist[1], dist[2], dist[3], dist[4]
    r2 = x * x + y * y
    radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
    xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x)
    yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y
    return fx * xd + s * yd + cx, fy * yd + cy


@njit(cache=True)
def ellipse_forms(P, K, dist, has_dist, width, height, xy, heights, widths, ring_px, min_depth,
                  ring_fraction=0.0):
    """Normal forms, bounding boxes and floor distances of standing-person ellipsoids.

    Parameters
    ----------
    P : (3, 4) float64 — camera matrix, normalised (third row = depth)
    K : (3, 3), dist : (5,), has_dist : bool — for bounding boxes under lens distortion
    width, height : int — image size
    xy : (N, 2) — floor positions, metres
    heights, widths : (N,) — ellipsoid sizes (2·Rb, 2·Ra), metres
    ring_px : float — ring width in pixels
    min_depth : float — an ellipsoid whose nearest point is closer than this (m) is not drawn
    ring_fraction : float — if > 0, the ring is at most this fraction of the ellipse's semi-minor
        axis (a far, small person gets a narrow ring instead of one wider than itself)

    Returns
    -------
    inner : (N, 5) — normal forms of the ellipses
    ring : (N, 5) — normal forms of the ring-expanded ellipses
    box : (N, 4) int64 — ``u0, u1, v0, v1`` (end exclusive) of the ring ellipse in the real image,
        clipped to the image; empty (u0 ≥ u1) when not visible
    valid : (N,) bool — ellipsoid fully in front of the camera and outline an ellipse
    """
    n = xy.shape[0]
    inner = np.zeros((n, 5))
    ring = np.zeros((n, 5))
    box = np.zeros((n, 4), dtype=np.int64)
    valid = np.zeros(n, dtype=np.bool_)
    Q = np.zeros((4, 4))
    for i in range(n):
        ra = 0.5 * widths[i]
        rb = 0.5 * heights[i]
        c0, c1, c2 = xy[i, 0], xy[i, 1], rb
        # Nearest depth of the ellipsoid: depth(centre) − ‖diag(r)·axis‖ (axis = P[2, :3], unit).
        dc = P[2, 0] * c0 + P[2, 1] * c1 + P[2, 2] * c2 + P[2, 3]
        ext = math.sqrt((ra * P[2, 0]) ** 2 + (ra * P[2, 1]) ** 2 + (rb * P[2, 2]) ** 2)
        if dc - ext < min_depth:
            continue
        # Dual quadric Q* = T·diag(ra², ra², rb², −1)·Tᵀ.
        cc = (c0, c1, c2)
        rr = (ra * ra, ra * ra, rb * rb)
        for a in range(3):
            for b in range(3):
                Q[a, b] = -cc[a] * cc[b]
            Q[a, a] += rr[a]
            Q[a, 3] = -cc[a]
            Q[3, a] = -cc[a]
        Q[3, 3] = -1.0
        # Dual conic C* = P·Q*·Pᵀ.
        PQ = P @ Q
        D = PQ @ P.T
        # Point conic = adjugate of C*; only the 2×2 block and the linear terms are needed.
        A11 = D[1, 1] * D[2, 2] - D[1, 2] * D[2, 1]
        A12 = D[0, 2] * D[2, 1] - D[0, 1] * D[2, 2]
        A22 = D[0, 0] * D[2, 2] - D[0, 2] * D[2, 0]
        B1 = D[0, 1] * D[1, 2] - D[0, 2] * D[1, 1]
        B2 = D[0, 2] * D[1, 0] - D[0, 0] * D[1, 2]
        F = D[0, 0] * D[1, 1] - D[0, 1] * D[1, 0]
        det = A11 * A22 - A12 * A12
        if det <= 0.0:
            continue
        # Centre of the conic and its value there.
        cu = -(A22 * B1 - A12 * B2) / det
        cv = -(-A12 * B1 + A11 * B2) / det
        k = F + B1 * cu + B2 * cv
        # Inside ⇔ (x−c)ᵀA(x−c) < −k: an ellipse needs A and −k of the same sign.
        if k * A11 >= 0.0:
            continue
        s = -1.0 / k
        a11, a12, a22 = A11 * s, A12 * s, A22 * s
        # Semi-axes from the eigenvalues of the normal form.
        tr = a11 + a22
        dd = math.sqrt(max((a11 - a22) ** 2 / 4.0 + a12 * a12, 0.0))
        l1 = tr / 2.0 - dd  # smaller eigenvalue → major axis
        l2 = tr / 2.0 + dd
        if l1 <= 0.0:
            continue
        ax1 = 1.0 / math.sqrt(l1)
        ax2 = 1.0 / math.sqrt(l2)
        # Eigenvector of l1: (l1 − a22, a12) or (a12, l1 − a11), whichever is better conditioned.
        e1x, e1y = l1 - a22, a12
        f1x, f1y = a12, l1 - a11
        if f1x * f1x + f1y * f1y > e1x * e1x + e1y * e1y:
            e1x, e1y = f1x, f1y
        nrm = math.sqrt(e1x * e1x + e1y * e1y)
        if nrm == 0.0:  # a circle: any direction
            e1x, e1y, nrm = 1.0, 0.0, 1.0
        e1x /= nrm
        e1y /= nrm
        e2x, e2y = -e1y, e1x
        r = ring_px
        if ring_fraction > 0.0:
            r = min(ring_px, max(1.0, ring_fraction * ax2))
        bx1 = ax1 + r
        bx2 = ax2 + r
        # Ring ellipse with the same axes directions and expanded semi-axes.
        w1 = 1.0 / (bx1 * bx1)
        w2 = 1.0 / (bx2 * bx2)
        inner[i, 0], inner[i, 1], inner[i, 2], inner[i, 3], inner[i, 4] = cu, cv, a11, a12, a22
        ring[i, 0], ring[i, 1] = cu, cv
        ring[i, 2] = w1 * e1x * e1x + w2 * e2x * e2x
        ring[i, 3] = w1 * e1x * e1y + w2 * e2x * e2y
        ring[i, 4] = w1 * e1y * e1y + w2 * e2y * e2y
        # Bounding box of the ring ellipse in the real image.
        if has_dist:
            umin, umax, vmin, vmax = 1e300, -1e300, 1e300, -1e300
            for j in range(_OUTLINE_SAMPLES):
                t = 2.0 * math.pi * j / _OUTLINE_SAMPLES
                pu = cu + bx1 * math.cos(t) * e1x + bx2 * math.sin(t) * e2x
                pv = cv + bx1 * math.cos(t) * e1y + bx2 * math.sin(t) * e2y
                qu, qv = _distort_ideal_pixel(pu, pv, K, dist)
                umin, umax = min(umin, qu), max(umax, qu)
                vmin, vmax = min(vmin, qv), max(vmax, qv)
            umin -= 1.0
            vmin -= 1.0
            umax += 1.0
            vmax += 1.0
        else:
            hu = math.sqrt((bx1 * e1x) ** 2 + (bx2 * e2x) ** 2)
            hv = math.sqrt((bx1 * e1y) ** 2 + (bx2 * e2y) ** 2)
            umin, umax, vmin, vmax = cu - hu, cu + hu, cv - hv, cv + hv
        u0 = max(0, int(math.floor(umin)))
        u1 = min(width, int(math.ceil(umax)) + 1)
        v0 = max(0, int(math.floor(vmin)))
        v1 = min(height, int(math.ceil(vmax)) + 1)
        box[i, 0], box[i, 1], box[i, 2], box[i, 3] = u0, u1, v0, v1
        valid[i] = True
    return inner, ring, box, valid


@njit(cache=True, inline="always")
def _inside(f, u, v):
    du = u - f[0]
    dv = v - f[1]
    return f[2] * du * du + 2.0 * f[3] * du * dv + f[4] * dv * dv < 1.0


@njit(cache=True)
def score_candidates(grid, has_dist, occ, real, use_ring,
                     c_inner, c_ring, c_box, c_dist, c_valid,
                     o_inner, o_ring, o_box, o_dist, o_valid, target_pixels, count_unexplained=False):
    """Numerators and denominators of E for C candidates of one person in one camera.

    Parameters
    ----------
    grid : (H, W, 2) float32 — ideal coordinates of each real pixel (used when ``has_dist``)
    occ : (H, W) float32 — obstacle floor distance per pixel (inf = none)
    real : (H, W) int8 — ternary real image (1 foreground, −1 ring, 0 else)
    use_ring : bool — False in capture mode: no −1 in either image
    c_* : candidate forms from :func:`ellipse_forms` and their floor distances (C,)
    o_* : the other people's forms and floor distances (M,)
    target_pixels : int — visit about this many pixels (0 = all)
    count_unexplained : bool — also add to the denominator the foreground pixels of the region
        that no simulated person covers (worldtrack's symmetric score; see module notes)

    Returns
    -------
    num, den : (C,) float64 — E = num / den where den > 0
    n_in : (C,) int64 — visited pixels inside the candidate's own visible ellipse
    """
    C = c_inner.shape[0]
    M = o_inner.shape[0]
    num = np.zeros(C)
    den = np.zeros(C)
    n_in = np.zeros(C, dtype=np.int64)
    H, W = real.shape
    u0, u1, v0, v1 = W, 0, H, 0
    for c in range(C):
        if c_valid[c] and c_box[c, 0] < c_box[c, 1] and c_box[c, 2] < c_box[c, 3]:
            u0 = min(u0, c_box[c, 0])
            u1 = max(u1, c_box[c, 1])
            v0 = min(v0, c_box[c, 2])
            v1 = max(v1, c_box[c, 3])
    if u0 >= u1 or v0 >= v1:
        return num, den, n_in
    stride = 1
    if target_pixels > 0:
        stride = max(1, int(math.sqrt((u1 - u0) * (v1 - v0) / target_pixels)))
    # Others whose ring box overlaps the region.
    near = np.empty(M, dtype=np.int64)
    n_near = 0
    for m in range(M):
        if (o_valid[m] and o_box[m, 0] < u1 and o_box[m, 1] > u0
                and o_box[m, 2] < v1 and o_box[m, 3] > v0):
            near[n_near] = m
            n_near += 1
    # Align the sampling grid to absolute coordinates so that every candidate sees the same pixels.
    vs = v0 + (-v0) % stride
    us = u0 + (-u0) % stride
    if has_dist:
        _pixels_distorted(grid, occ, real, use_ring, count_unexplained, c_inner, c_ring, c_box, c_dist, c_valid,
                          o_inner, o_ring, o_dist, near[:n_near], vs, v1, us, u1, stride, num, den, n_in)
    else:
        _pixels_by_rows(occ, real, use_ring, count_unexplained, c_inner, c_ring, c_box, c_dist, c_valid,
                        o_inner, o_ring, o_dist, near[:n_near], vs, v1, us, u1, stride, num, den, n_in)
    return num, den, n_in


@njit(cache=True, inline="always")
def _terms(inside, other_in, ring, use_ring, r, count_unexplained):
    """One pixel's terms of eq. 5, ``E = Σ sim·real / Σ |sim|``: (sim·real, |sim|).

    The joint simulated image is 1 inside anybody, −1 in a ring, 0 else; with
    ``count_unexplained`` a foreground pixel that no ellipse covers adds 1 to the denominator.
    """
    if inside or other_in:
        return np.float64(r), 1.0
    if use_ring and ring:
        return np.float64(-r), 1.0
    if count_unexplained and r > 0:
        return 0.0, 1.0
    return 0.0, 0.0


@njit(cache=True)
def _pixels_distorted(grid, occ, real, use_ring, count_unexplained, c_inner, c_ring, c_box, c_dist, c_valid,
                      o_inner, o_ring, o_dist, near, vs, v1, us, u1, stride, num, den, n_in):
    """The pixel loop for a distorted camera: each pixel's ideal position from ``grid``."""
    C = c_inner.shape[0]
    for v in range(vs, v1, stride):
        for uu in range(us, u1, stride):
            x = np.float64(grid[v, uu, 0])
            y = np.float64(grid[v, uu, 1])
            o = occ[v, uu]
            r = real[v, uu]
            if not use_ring and r < 0:
                r = 0
            other_in = False
            other_ring = False
            for m in near:
                if o >= o_dist[m]:
                    if _inside(o_inner[m], x, y):
                        other_in = True
                        break
                    if use_ring and not other_ring and _inside(o_ring[m], x, y):
                        other_ring = True
            for c in range(C):
                if not c_valid[c]:
                    continue
                inside = False
                ring = other_ring
                if c_box[c, 0] <= uu < c_box[c, 1] and c_box[c, 2] <= v < c_box[c, 3] and o >= c_dist[c]:
                    inside = _inside(c_inner[c], x, y)
                    if use_ring and not inside and not ring:
                        ring = _inside(c_ring[c], x, y)
                dn, dd = _terms(inside, other_in, ring, use_ring, r, count_unexplained)
                num[c] += dn
                den[c] += dd
                if inside:
                    n_in[c] += 1


@njit(cache=True, inline="always")
def _row_span(f, v):
    """Open interval of u where row v is inside the ellipse of normal form f (empty: lo > hi)."""
    dv = v - f[1]
    a = f[2]
    b = f[3] * dv
    disc = b * b - a * (f[4] * dv * dv - 1.0)
    if disc <= 0.0:
        return 1e300, -1e300
    sq = math.sqrt(disc)
    return f[0] + (-b - sq) / a, f[0] + (-b + sq) / a


@njit(cache=True, inline="always")
def _span_indices(lo, hi, us, stride, n):
    """Sampled columns ``us + i·stride`` (i < n) strictly inside the open interval (lo, hi): the
    index range [i0, i1) (empty when i0 ≥ i1).

    Exact in integers: a column u is > lo when u ≥ ⌊lo⌋ + 1 and < hi when u < ⌈hi⌉, the same
    answers as comparing the float coordinate pixel by pixel.
    """
    if not lo < hi:
        return 0, 0
    first = int(math.floor(min(max(lo, -1e9), 1e9))) + 1    # the first column > lo
    end = int(math.ceil(min(max(hi, -1e9), 1e9)))           # the first column ≥ hi
    i0 = min(max(-((us - first) // stride), 0), n)          # ⌈(first − us) / stride⌉
    i1 = min(max(-((us - end) // stride), 0), n)
    return i0, max(i0, i1)


@njit(cache=True)
def _pixels_by_rows(occ, real, use_ring, count_unexplained, c_inner, c_ring, c_box, c_dist, c_valid,
                    o_inner, o_ring, o_dist, near, vs, v1, us, u1, stride, num, den, n_in):
    """The pixel loop for a pinhole camera, one row at a time.

    Each ellipse meets a row in an interval of u (one square root per row and ellipse). A pixel's
    terms depend on the candidate only through whether the candidate's ellipse or ring covers it,
    so each row is read once: the terms without the candidate (the others' joint image) and,
    as running sums along the row, how much they change where a candidate's ellipse or ring
    lies. A candidate then costs two interval lookups per row instead of a test per pixel, plus
    a correction at each pixel of its interval where an obstacle nearer than it hides it (those
    keep their terms without the candidate). Sums are identical to visiting every pixel for
    every candidate (:func:`score_candidates_reference`).
    """
    C = c_inner.shape[0]
    M = near.shape[0]
    n = max(0, (u1 - us + stride - 1) // stride)
    farthest = -np.inf  # obstacles beyond every candidate hide none of them
    for c in range(C):
        if c_valid[c]:
            farthest = max(farthest, c_dist[c])
    o_span = np.empty((M, 4))
    o_row = np.empty(n)
    hiding = np.empty(n, dtype=np.int64)
    # Running sums along the row of (terms inside the candidate − base) and (terms in its ring − base).
    in_n = np.zeros(n + 1)
    in_d = np.zeros(n + 1)
    rg_n = np.zeros(n + 1)
    rg_d = np.zeros(n + 1)
    for v in range(vs, v1, stride):
        fv = np.float64(v)
        for j in range(M):
            m = near[j]
            o_span[j, 0], o_span[j, 1] = _row_span(o_inner[m], fv)
            o_span[j, 2], o_span[j, 3] = _row_span(o_ring[m], fv)
        row_n = 0.0
        row_d = 0.0
        n_hiding = 0
        for i in range(n):
            uu = us + i * stride
            x = np.float64(uu)
            o = np.float64(occ[v, uu])
            r = real[v, uu]
            if not use_ring and r < 0:
                r = 0
            other_in = False
            other_ring = False
            for j in range(M):
                if o >= o_dist[near[j]]:
                    if o_span[j, 0] < x < o_span[j, 1]:
                        other_in = True
                        break
                    if use_ring and o_span[j, 2] < x < o_span[j, 3]:
                        other_ring = True
            bn, bd = _terms(False, other_in, other_ring, use_ring, r, count_unexplained)
            gn, gd = _terms(False, other_in, True, use_ring, r, count_unexplained)
            row_n += bn
            row_d += bd
            in_n[i + 1] = in_n[i] + (np.float64(r) - bn)
            in_d[i + 1] = in_d[i] + (1.0 - bd)
            rg_n[i + 1] = rg_n[i] + (gn - bn)
            rg_d[i + 1] = rg_d[i] + (gd - bd)
            if o < farthest:
                o_row[i] = o
                hiding[n_hiding] = i
                n_hiding += 1
        for c in range(C):
            if not c_valid[c]:
                continue
            num[c] += row_n
            den[c] += row_d
            if not (c_box[c, 2] <= v < c_box[c, 3]):
                continue
            lo, hi = _row_span(c_inner[c], fv)
            rlo, rhi = _row_span(c_ring[c], fv)
            # Outside the candidate's box columns nothing of it is drawn.
            lo = max(lo, c_box[c, 0] - 1.0)
            hi = min(hi, np.float64(c_box[c, 1]))
            rlo = max(rlo, c_box[c, 0] - 1.0)
            rhi = min(rhi, np.float64(c_box[c, 1]))
            a0, a1 = _span_indices(lo, hi, us, stride, n)
            num[c] += in_n[a1] - in_n[a0]
            den[c] += in_d[a1] - in_d[a0]
            n_in[c] += a1 - a0
            b0, b1 = 0, 0
            if use_ring:
                # The ring's pixels that are not inside: [b0, b1) minus [a0, a1).
                b0, b1 = _span_indices(rlo, rhi, us, stride, n)
                if a0 < a1:
                    left_end, right_start = min(a0, b1), max(a1, b0)
                    if left_end > b0:
                        num[c] += rg_n[left_end] - rg_n[b0]
                        den[c] += rg_d[left_end] - rg_d[b0]
                    if b1 > right_start:
                        num[c] += rg_n[b1] - rg_n[right_start]
                        den[c] += rg_d[b1] - rg_d[right_start]
                else:
                    num[c] += rg_n[b1] - rg_n[b0]
                    den[c] += rg_d[b1] - rg_d[b0]
            # Pixels where an obstacle nearer than the candidate hides it keep their base terms.
            start, stop = min(a0, b0) if b0 < b1 else a0, max(a1, b1)
            for h in range(np.searchsorted(hiding[:n_hiding], start), n_hiding):
                i = hiding[h]
                if i >= stop:
                    break
                if o_row[i] >= c_dist[c]:
                    continue
                if a0 <= i < a1:
                    num[c] -= in_n[i + 1] - in_n[i]
                    den[c] -= in_d[i + 1] - in_d[i]
                    n_in[c] -= 1
                elif b0 <= i < b1:
                    num[c] -= rg_n[i + 1] - rg_n[i]
                    den[c] -= rg_d[i + 1] - rg_d[i]


def ternary_real(labels: np.ndarray, ring_px: int) -> np.ndarray:
    """The paper's ternary real image: 1 foreground, −1 in a ring of ``ring_px`` around it, 0 else.

    ``labels`` is a foreground mask (0/1) or foreground labels where 2 marks "unsure"
    (shadow-like) pixels; those stay 0 — no evidence — and the ring does not cover them.

    The ring (a dilation by an octagon inside the (2·ring_px + 1)² square) reaches no farther than
    ``ring_px`` pixels along either axis, so only the foreground's bounding box grown by more than
    that is dilated: the result equals :func:`ternary_real_reference` (the whole frame) exactly.
    The octagon is computed from capped distances in compiled passes (~0.3 instead of ~0.7 ms
    on a 640×480 crowd frame with OpenCV's dilations), equal to the dilations.
    """
    fg = (labels == 1).astype(np.uint8)
    out = fg.astype(np.int8)
    u, v, w, h = cv2.boundingRect(fg)
    if w == 0 or h == 0:
        return out
    H, W = fg.shape
    diag = _octagon_diagonal(ring_px)
    m = max(ring_px, diag) + 1
    u0, u1, v0, v1 = max(0, u - m), min(W, u + w + m), max(0, v - m), min(H, v + h + m)
    if m > 255 or ring_px < 1:  # beyond the uint8 distances of the compiled octagon
        near = _near_foreground(fg[v0:v1, u0:u1], ring_px)
        out[v0:v1, u0:u1][near & (labels[v0:v1, u0:u1] == 0)] = -1
        return out
    # The octagon from the distance along the columns to the nearest foreground pixel: within
    # the square where some column within ring_px has it within ring_px, within the diamond where
    # the city-block distance is within diag. Both along the rows, on the transposed distances.
    crop = np.ascontiguousarray(labels[v0:v1, u0:u1])
    down = _column_distance(crop, np.uint8(m), 1)
    near = cv2.transpose(_octagon_from_column_distance(cv2.transpose(down), np.uint8(m), ring_px, diag))
    _mark_ring(out[v0:v1, u0:u1], crop, near)
    return out


@njit(cache=True)
def _octagon_from_column_distance(t: np.ndarray, cap: np.uint8, ring_px: int, diag: int) -> np.ndarray:
    """Near-foreground mask (uint8) from ``t``, the transposed column distances: within the
    square (L∞ ≤ ``ring_px``) and the diamond (L1 ≤ ``diag``) of a foreground pixel.

    Along ``t``'s columns (the image's rows): the square holds where some entry within
    ``ring_px`` is ≤ ``ring_px`` (a running count); the diamond where the relaxed distance
    ``min_k(|k| + t)`` is ≤ ``diag``.
    """
    H, W = t.shape
    count = np.zeros((H + 1, W), np.int32)         # running count of entries ≤ ring_px
    for y in range(H):
        for x in range(W):
            count[y + 1, x] = count[y, x] + (1 if t[y, x] <= ring_px else 0)
    l1 = t.copy()
    _relax_columns(l1, cap)
    out = np.empty((H, W), np.uint8)
    for y in range(H):
        lo = max(y - ring_px, 0)
        hi = min(y + ring_px + 1, H)
        for x in range(W):
            out[y, x] = 1 if (count[hi, x] - count[lo, x] > 0 and l1[y, x] <= diag) else 0
    return out


@njit(cache=True)
def _mark_ring(out: np.ndarray, labels: np.ndarray, near: np.ndarray) -> None:
    """In place: −1 in ``out`` where ``near`` and the label is 0 (nothing, not "unsure")."""
    H, W = out.shape
    for y in range(H):
        for x in range(W):
            if near[y, x] and labels[y, x] == 0:
                out[y, x] = -1


def ternary_real_reference(labels: np.ndarray, ring_px: int) -> np.ndarray:
    """:func:`ternary_real` with the whole frame dilated: the plain version it is tested against."""
    fg = (labels == 1).astype(np.uint8)
    near = _near_foreground(fg, ring_px)
    out = fg.astype(np.int8)
    out[near & (labels == 0)] = -1
    return out


def _octagon_diagonal(ring_px: int) -> int:
    """The octagon's diagonal half-width (L1 radius): between r and r·√2."""
    return int(round(ring_px * 1.3))


def _near_foreground(fg: np.ndarray, ring_px: int) -> np.ndarray:
    """(H, W) bool: within the octagon of radius ``ring_px`` of a foreground pixel of ``fg`` (uint8 0/1).

    Dilation by an octagon (a square ∩ a diamond, both separable or cheap), close to the paper's
    disc and ~10x faster than an elliptical kernel of radius 20 px at 640x480. Pixels outside the
    array count as background, so a crop holding all the foreground (and the reach) gives the same
    answer as the whole frame.
    """
    side = 2 * ring_px + 1
    square = cv2.dilate(fg, np.ones((side, side), np.uint8))
    return (square > 0) & (within_l1(fg, _octagon_diagonal(ring_px)) > 0)


def within_l1(fg: np.ndarray, radius: int) -> np.ndarray:
    """(H, W) uint8: 1 within city-block distance ``radius`` of a non-zero pixel of ``fg`` (uint8).

    The dilation by a diamond, i.e. ``cv2.dilate`` with a 3×3 cross iterated ``radius`` times
    (:func:`within_l1_reference`), from the separable city-block distance instead: the distance
    along each column (two compiled passes whose inner loops run along rows, so they vectorise),
    then the same on the transposed image; capped at ``radius + 1`` in uint8. ~3× faster than
    the iterated cross at radius 26 (640×480), and independent of the radius.
    """
    if radius <= 0:
        return (fg > 0).astype(np.uint8)
    if radius >= 255:
        return within_l1_reference(fg, radius)
    cap = np.uint8(radius + 1)
    down = _column_distance(np.ascontiguousarray(fg != 0), cap, True)
    return cv2.transpose(_column_distance_within(cv2.transpose(down), cap, np.uint8(radius)))


def within_l1_reference(fg: np.ndarray, radius: int) -> np.ndarray:
    """:func:`within_l1` as the iterated dilation by a 3×3 cross: the plain version it is tested against."""
    if radius <= 0:
        return (fg > 0).astype(np.uint8)
    cross = cv2.getStructuringElement(cv2.MORPH_CROSS, (3, 3))
    return (cv2.dilate((fg > 0).astype(np.uint8), cross, iterations=radius) > 0).astype(np.uint8)


@njit(cache=True)
def _relax_columns(a: np.ndarray, cap: np.uint8) -> None:
    """In place: each pixel's value becomes the least of itself and (its column neighbour's + 1),
    downwards then upwards, never above ``cap`` — a distance along the columns."""
    H, W = a.shape
    for y in range(1, H):
        for x in range(W):
            v = min(a[y - 1, x], cap - 1) + 1
            if v < a[y, x]:
                a[y, x] = v
    for y in range(H - 2, -1, -1):
        for x in range(W):
            v = min(a[y + 1, x], cap - 1) + 1
            if v < a[y, x]:
                a[y, x] = v


@njit(cache=True)
def _column_distance(image: np.ndarray, cap: np.uint8, value) -> np.ndarray:
    """(H, W) uint8: distance along the column to the nearest pixel of ``image`` equal to
    ``value``, capped at ``cap``."""
    H, W = image.shape
    a = np.empty((H, W), np.uint8)
    for y in range(H):
        for x in range(W):
            a[y, x] = 0 if image[y, x] == value else cap
    _relax_columns(a, cap)
    return a


@njit(cache=True)
def _column_distance_within(a: np.ndarray, cap: np.uint8, radius: np.uint8) -> np.ndarray:
    """Relax ``a`` along its columns (in place) and return 1 where it is at most ``radius``."""
    _relax_columns(a, cap)
    H, W = a.shape
    out = np.empty((H, W), np.uint8)
    for y in range(H):
        for x in range(W):
            out[y, x] = 1 if a[y, x] <= radius else 0
    return out


def score_candidates_reference(P, camera, occ, real, use_ring, xy, heights, widths, ring_px,
                               others_xy, others_h, others_w, target_pixels=0, min_depth=0.1,
                               count_unexplained=False, ring_fraction=0.0):
    """Plain NumPy version of :func:`ellipse_forms` + :func:`score_candidates` for tests.

    Renders each candidate's joint ternary image over the whole frame with
    :func:`worldtrack.geometry.quadric.ellipse_mask` and sums eq. 5 on the same pixel grid.
    """
    H, W = real.shape
    grid = camera.ideal_pixel_grid if camera.has_distortion else None
    centre = camera.centre

    def forms(pxy, ph, pw):
        pxy = np.asarray(pxy, float).reshape(-1, 2)
        cen, rad = quadric.person_ellipsoid(pxy, ph, pw)
        conics = quadric.ellipsoid_conics(P, cen, rad)
        ctr, axes, ang = quadric.ellipse_parameters(conics)
        dist = np.hypot(pxy[:, 0] - centre[0], pxy[:, 1] - centre[1])
        depth_c = cen @ P[2, :3] + P[2, 3]
        ext = np.sqrt((rad[:, 0] * P[2, 0]) ** 2 + (rad[:, 1] * P[2, 1]) ** 2 + (rad[:, 2] * P[2, 2]) ** 2)
        ok = (depth_c - ext >= min_depth) & np.isfinite(axes).all(axis=1)
        return ctr, axes, ang, dist, ok

    def masks(ctr, axes, ang, dist, ok, r):
        """Full-image inside/ring masks (list per person), visibility against obstacles applied."""
        if grid is None:
            v, u = np.mgrid[0:H, 0:W].astype(float)
        else:
            u, v = grid[..., 0].astype(float), grid[..., 1].astype(float)
        ins, rng = [], []
        for k in range(len(ctr)):
            if not ok[k]:
                ins.append(np.zeros((H, W), bool))
                rng.append(np.zeros((H, W), bool))
                continue
            du, dv = u - ctr[k, 0], v - ctr[k, 1]
            ca, sa = np.cos(ang[k]), np.sin(ang[k])
            p1 = du * ca + dv * sa
            p2 = -du * sa + dv * ca
            vis = occ >= dist[k]
            rk = min(r, max(1.0, ring_fraction * axes[k, 1])) if ring_fraction > 0 else r
            ins.append(vis & ((p1 / axes[k, 0]) ** 2 + (p2 / axes[k, 1]) ** 2 < 1))
            rng.append(vis & ((p1 / (axes[k, 0] + rk)) ** 2 + (p2 / (axes[k, 1] + rk)) ** 2 < 1))
        return ins, rng

    cand = forms(xy, heights, widths)
    oth = forms(others_xy, others_h, others_w)
    c_in, c_rg = masks(*cand, ring_px)
    o_in, o_rg = masks(*oth, ring_px)
    other_in = np.zeros((H, W), bool)
    other_rg = np.zeros((H, W), bool)
    for a, b in zip(o_in, o_rg):
        other_in |= a
        other_rg |= b
    # The sampled region: union of the candidates' boxes, from the optimised kernel's forms.
    args = (P, camera.K, camera.dist, camera.has_distortion, W, H)
    _, _, box, valid = ellipse_forms(*args, np.asarray(xy, float).reshape(-1, 2),
                                     np.broadcast_to(np.asarray(heights, float), (len(c_in),)).copy(),
                                     np.broadcast_to(np.asarray(widths, float), (len(c_in),)).copy(),
                                     float(ring_px), min_depth, ring_fraction)
    sel = valid & (box[:, 0] < box[:, 1]) & (box[:, 2] < box[:, 3])
    num = np.zeros(len(c_in))
    den = np.zeros(len(c_in))
    if not sel.any():
        return num, den
    u0, u1 = box[sel, 0].min(), box[sel, 1].max()
    v0, v1 = box[sel, 2].min(), box[sel, 3].max()
    stride = 1 if target_pixels <= 0 else max(1, int(np.sqrt((u1 - u0) * (v1 - v0) / target_pixels)))
    vv = np.arange(v0 + (-v0) % stride, v1, stride)
    uu = np.arange(u0 + (-u0) % stride, u1, stride)
    R = real[np.ix_(vv, uu)].astype(float)
    if not use_ring:
        R = np.maximum(R, 0)
    for c in range(len(c_in)):
        if not valid[c]:
            continue
        inside = (c_in[c] | other_in)[np.ix_(vv, uu)]
        ring = ((c_rg[c] | other_rg) if use_ring else np.zeros((H, W), bool))[np.ix_(vv, uu)] & ~inside
        sim = inside.astype(float) - ring.astype(float)
        num[c] = (sim * R).sum()
        den[c] = np.abs(sim).sum()
        if count_unexplained:
            den[c] += ((sim == 0) & (R > 0)).sum()
    return num, den


@njit(cache=True)
def track_support(grid, has_dist, occ, mask, inner, box, dist, valid, target_pixels, covers):
    """How much foreground each person alone explains.

    For every person k, over the visible pixels of its ellipse (not hidden by obstacles) that no
    other person's visible ellipse covers: the number of such pixels and how many of them are
    foreground. A track whose own pixels are mostly background explains nothing the others do
    not — a ghost left behind, or a track that has lost its person.

    Parameters
    ----------
    mask : (H, W) uint8 — foreground (1) / background (0) / unsure (2, not counted)
    inner, box, dist, valid : the people's forms, boxes, floor distances and validity (N, …)
    target_pixels : int — sample about this many pixels per person (0 = all)
    covers : (N,) bool — which people take pixels away from the others (e.g. only confirmed
        tracks: two tentative ones on the same person must not cancel each other out)

    Returns
    -------
    visible : (N,) float64 — pixels of the ellipse inside the image and not hidden by obstacles
        (estimated from the samples: each sample counts stride² pixels)
    own : (N,) float64 — of those, the ones covered by nobody else (not counting unsure pixels)
    own_fg : (N,) float64 — of those, the foreground ones
    area : (N,) float64 — the whole ellipse's area in pixels, image border and obstacles ignored
    """
    n = inner.shape[0]
    visible = np.zeros(n)
    own = np.zeros(n)
    own_fg = np.zeros(n)
    area = np.zeros(n)
    for k in range(n):
        if not valid[k]:
            continue
        area[k] = math.pi / math.sqrt(max(inner[k, 2] * inner[k, 4] - inner[k, 3] ** 2, 1e-300))
        u0, u1, v0, v1 = box[k, 0], box[k, 1], box[k, 2], box[k, 3]
        if u0 >= u1 or v0 >= v1:
            continue
        stride = 1
        if target_pixels > 0:
            stride = max(1, int(math.sqrt((u1 - u0) * (v1 - v0) / target_pixels)))
        for v in range(v0, v1, stride):
            for uu in range(u0, u1, stride):
                if has_dist:
                    x = np.float64(grid[v, uu, 0])
                    y = np.float64(grid[v, uu, 1])
                else:
                    x = np.float64(uu)
                    y = np.float64(v)
                o = occ[v, uu]
                if o < dist[k] or not _inside(inner[k], x, y):
                    continue
                visible[k] += stride * stride
                covered = False
                for m in range(n):
                    if m == k or not valid[m] or not covers[m] or o < dist[m]:
                        continue
                    if uu < box[m, 0] or uu >= box[m, 1] or v < box[m, 2] or v >= box[m, 3]:
                        continue
                    if _inside(inner[m], x, y):
                        covered = True
                        break
                if not covered and mask[v, uu] != 2:
                    own[k] += stride * stride
                    if mask[v, uu] == 1:
                        own_fg[k] += stride * stride
    return visible, own, own_fg, area


@njit(cache=True)
def score_camera(P, K, dist, has_dist, width, height, cam_xy, grid, occ, real, use_ring,
                 cand, heights, widths, ring_px, min_depth, ring_fraction,
                 o_inner, o_ring, o_box, o_dist, o_valid, skip, target_pixels, count_unexplained):
    """:func:`ellipse_forms` of the candidates then :func:`score_candidates`, in one call.

    ``o_*`` describe everybody (the person being moved included, at index ``skip``, which is left
    out of the joint image; −1 for none). Returns ``num, den`` (C,) and the candidates' forms
    ``inner, ring, box, valid`` and floor distances, so the caller can keep the chosen one.
    """
    ci, cr, cb, cv = ellipse_forms(P, K, dist, has_dist, width, height, cand, heights, widths,
                                   ring_px, min_depth, ring_fraction)
    n = cand.shape[0]
    cd = np.empty(n)
    for i in range(n):
        cd[i] = math.hypot(cand[i, 0] - cam_xy[0], cand[i, 1] - cam_xy[1])
    ov = o_valid.copy()
    if skip >= 0:
        ov[skip] = False
    num, den, _ = score_candidates(grid, has_dist, occ, real, use_ring, ci, cr, cb, cd, cv,
                                   o_inner, o_ring, o_box, o_dist, ov, target_pixels, count_unexplained)
    return num, den, ci, cr, cb, cv, cd


@njit(cache=True)
def ellipse_crop(form, box, grid, has_dist):
    """(v1 − v0, u1 − u0) bool: pixels of ``box`` inside the ellipse of normal form ``form``."""
    u0, u1, v0, v1 = box[0], box[1], box[2], box[3]
    out = np.zeros((max(0, v1 - v0), max(0, u1 - u0)), dtype=np.bool_)
    for v in range(v0, v1):
        for uu in range(u0, u1):
            if has_dist:
                x = np.float64(grid[v, uu, 0])
                y = np.float64(grid[v, uu, 1])
            else:
                x = np.float64(uu)
                y = np.float64(v)
            out[v - v0, uu - u0] = _inside(form, x, y)
    return out


@njit(cache=True)
def owner_crop(window, inner, box, valid, grid, has_dist):
    """Who covers each pixel of ``window`` = (u0, u1, v0, v1): (v1 − v0, u1 − u0) int32, the
    index of the one person whose ellipse covers the pixel, −1 nobody, −2 several.

    ``window`` must lie inside the image (a person's box does). Only the people whose boxes meet
    it are visited, so the cost is that of the window, not of the image.

    Parameters
    ----------
    window : (4,) int64
    inner, box, valid : the people's ellipse forms (N, 5), boxes (N, 4) and validity (N,)
    grid : (H, W, 2) float32 — ideal coordinates of each pixel (used when ``has_dist``)
    """
    u0, u1, v0, v1 = window[0], window[1], window[2], window[3]
    out = np.full((max(0, v1 - v0), max(0, u1 - u0)), -1, dtype=np.int32)
    for k in range(inner.shape[0]):
        if not valid[k]:
            continue
        for v in range(max(box[k, 2], v0), min(box[k, 3], v1)):
            for uu in range(max(box[k, 0], u0), min(box[k, 1], u1)):
                if has_dist:
                    x = np.float64(grid[v, uu, 0])
                    y = np.float64(grid[v, uu, 1])
                else:
                    x = np.float64(uu)
                    y = np.float64(v)
                if _inside(inner[k], x, y):
                    out[v - v0, uu - u0] = k if out[v - v0, uu - u0] == -1 else -2
    return out


def owner_map(height: int, width: int, inner: np.ndarray, box: np.ndarray, valid: np.ndarray, grid: np.ndarray,
              has_dist: bool) -> np.ndarray:
    """(H, W) int32: index of the one person whose ellipse covers each pixel, −1 nobody, −2 several
    (:func:`owner_crop` over the whole image)."""
    return owner_crop(np.array([0, width, 0, height], dtype=np.int64), inner, box, valid, grid, has_dist)
