"""The pixel loops of eq. 5 (paper 000): each visited pixel's terms ``sim·real`` and ``|sim|``.

:func:`~.score.score_candidates` chooses the pixels (a window on a stride) and calls one of these:
:func:`pixels_by_rows` for a pinhole camera (each ellipse meets a row in an interval, so a row is
read once for all candidates) or :func:`pixels_distorted` under lens distortion (each pixel tested
at its ideal position). Both add into ``Sums`` in place, and both give exactly the sums of
:func:`~.score.score_candidates_reference`, which visits every pixel for every candidate (the tests
compare them to the last bit).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from worldtrack.trackers.ellipsoid.forms import inside


@njit(cache=True, inline="always")
def _terms(within, other_in, ring, use_ring, r, count_unexplained):
    """One pixel's terms of eq. 5, ``E = Σ sim·real / Σ |sim|``: (sim·real, |sim|).

    The joint simulated image is 1 inside anybody, −1 in a ring, 0 else; with
    ``count_unexplained`` a foreground pixel that no ellipse covers adds 1 to the denominator.
    """
    if within or other_in:
        return np.float64(r), 1.0
    if use_ring and ring:
        return np.float64(-r), 1.0
    if count_unexplained and r > 0:
        return 0.0, 1.0
    return 0.0, 0.0



@njit(cache=True)
def pixels_distorted(cam, real, cand, others, near, window, opts, sums):
    """The pixel loop for a distorted camera: each pixel's ideal position from ``cam.grid``."""
    grid, occ = cam.grid, cam.occ
    c_inner, c_ring, c_box, c_dist, c_valid = cand.inner, cand.ring, cand.box, cand.dist, cand.valid
    o_inner, o_ring, o_dist = others.inner, others.ring, others.dist
    use_ring, count_unexplained = opts.use_ring, opts.count_unexplained
    num, den, n_in = sums.num, sums.den, sums.n_in
    C = c_inner.shape[0]
    for v in range(window.vs, window.v1, window.stride):
        for uu in range(window.us, window.u1, window.stride):
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
                    if inside(o_inner[m], x, y):
                        other_in = True
                        break
                    if use_ring and not other_ring and inside(o_ring[m], x, y):
                        other_ring = True
            for c in range(C):
                if not c_valid[c]:
                    continue
                within = False
                ring = other_ring
                if c_box[c, 0] <= uu < c_box[c, 1] and c_box[c, 2] <= v < c_box[c, 3] and o >= c_dist[c]:
                    within = inside(c_inner[c], x, y)
                    if use_ring and not within and not ring:
                        ring = inside(c_ring[c], x, y)
                dn, dd = _terms(within, other_in, ring, use_ring, r, count_unexplained)
                num[c] += dn
                den[c] += dd
                if within:
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
def pixels_by_rows(occ, real, cand, others, near, window, opts, sums):
    """The pixel loop for a pinhole camera, one row at a time.

    Each ellipse meets a row in an interval of u (one square root per row and ellipse). A pixel's
    terms depend on the candidate only through whether the candidate's ellipse or ring covers it,
    so each row is read once: the terms without the candidate (the others' joint image) and,
    as running sums along the row, how much they change where a candidate's ellipse or ring
    lies. A candidate then costs two interval lookups per row instead of a test per pixel, plus
    a correction at each pixel of its interval where an obstacle nearer than it hides it (those
    keep their terms without the candidate). Sums are identical to visiting every pixel for
    every candidate (:func:`score_candidates_reference`).

    Compiled, and one function: the row's running sums and the candidates' lookups share the
    row's arrays, which the compiler keeps local.
    """
    c_inner, c_ring, c_box, c_dist, c_valid = cand.inner, cand.ring, cand.box, cand.dist, cand.valid
    o_inner, o_ring, o_dist = others.inner, others.ring, others.dist
    use_ring, count_unexplained = opts.use_ring, opts.count_unexplained
    num, den, n_in = sums.num, sums.den, sums.n_in
    vs, v1, us, u1, stride = window
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


__all__ = ["pixels_by_rows", "pixels_distorted"]
