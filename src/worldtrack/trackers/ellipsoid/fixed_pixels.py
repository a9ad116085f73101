"""Each camera scores a tracked person's candidates on a fixed pixel set (issue 37, crowd 10).

Eq. 5 is a ratio, ``E = Σ sim·real / Σ |sim|``, and each candidate is drawn anew: the pixels it
counts are its own visible ellipse and ring. With two cameras facing each other, a person half
hidden from one camera (c1) by a nearer neighbour shows c1 only a sliver of their ellipse past the
neighbour's. A candidate farther from c1 is drawn smaller and its sliver shrinks; the sliver is
mostly background (``sim·real = 0``), so the denominator falls and c1's ratio rises towards the
neighbour's well-fitting pixels. c1 then pushes the track away from itself, which is along the
other camera's line of sight, where nothing holds it (dev seed 33, person 5, track 8: c1's
denominator 543 → 418 at −0.5 m with the same numerator, its ratio 0.460 → 0.598).
:func:`~.match.held_scores` fixes each camera's weight, not this gain.

With ``score.fixed_pixels`` a candidate is scored, in each camera, on its own pixels **and** the
pixels the person counts at their current place: a pixel the current place counts and the
candidate does not is added to the candidate's denominator with nothing in the numerator. Leaving
background then neither gains nor costs; leaving foreground costs, covering background costs,
covering foreground gains and leaving the real image's −1 ring (an ellipse too large) gains, as
before. :func:`dropped_pixels` counts those pixels per candidate on the very pixels
:func:`~.score.score_candidates` visits.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from worldtrack.trackers.ellipsoid.args import DrawArgs, Forms, People
from worldtrack.trackers.ellipsoid.forms import ideal_position, inside
from worldtrack.trackers.ellipsoid.score import _reference_masks, sample_region


@njit(cache=True)
def _counted(o, x, y, f_ring, box, dist, u, v):
    """Whether a candidate's ring ellipse (its ellipse and ring) covers visited pixel (u, v) at
    ideal position (x, y), not hidden by an obstacle at floor distance ``o`` nearer than it."""
    return box[0] <= u < box[1] and box[2] <= v < box[3] and o >= dist and inside(f_ring, x, y)


@njit(cache=True)
def dropped_pixels(cam, real, cand, others, ref, opts):
    """Per candidate, the visited pixels the denominator of E counts at candidate ``ref`` and not at it.

    Parameters
    ----------
    cam : CameraArgs
    real : (H, W) int8 — this camera's ternary real image
    cand : Forms — the candidates' ellipses (C,), as :func:`~.score.score_candidates` takes them
    others : Forms — the other people's (M,), those with ``valid`` False left out
    ref : int — the candidate that is the person's current place
    opts : ScoreArgs — ``use_ring`` (False: nothing is dropped, 0 everywhere),
        ``target_pixels``, ``count_unexplained``

    Returns
    -------
    (C,) float64 — pixels of ``ref``'s own ellipse and ring (visible, not covered by anybody
    else's ellipse or ring, and not foreground when ``count_unexplained``, which is counted
    anyway) that candidate ``c`` does not cover; 0 at ``ref`` and for undrawn candidates.
    """
    C = cand.inner.shape[0]
    out = np.zeros(C)
    if not opts.use_ring or not cand.valid[ref]:
        return out
    u0, u1, v0, v1, stride = sample_region(cand, real.shape, opts.target_pixels)
    rb = cand.box[ref]
    lo_u, hi_u, lo_v, hi_v = max(u0, rb[0]), min(u1, rb[1]), max(v0, rb[2]), min(v1, rb[3])
    if lo_u >= hi_u or lo_v >= hi_v:
        return out
    # The same grid as score_candidates: aligned to absolute coordinates on the stride.
    us, vs = lo_u + (-lo_u) % stride, lo_v + (-lo_v) % stride
    for v in range(vs, hi_v, stride):
        for u in range(us, hi_u, stride):
            x, y = ideal_position(cam.grid, cam.has_dist, v, u)
            o = np.float64(cam.occ[v, u])
            if not _counted(o, x, y, cand.ring[ref], rb, cand.dist[ref], u, v):
                continue
            if opts.count_unexplained and real[v, u] > 0:
                continue
            covered = False
            for m in range(others.inner.shape[0]):
                if others.valid[m] and o >= others.dist[m] and inside(others.ring[m], x, y):
                    covered = True
                    break
            if covered:
                continue
            for c in range(C):
                if cand.valid[c] and not _counted(o, x, y, cand.ring[c], cand.box[c], cand.dist[c], u, v):
                    out[c] += 1.0
    return out


def dropped_pixels_reference(camera, real: np.ndarray, cand: People, forms: Forms, others: People, ring_px: float,
                             draw: DrawArgs, ref: int, count_unexplained: bool = True) -> np.ndarray:
    """:func:`dropped_pixels` from whole-frame masks, every pixel visited (``target_pixels`` 0), no
    obstacles: ``|D_ref \\ D_c|`` over the sampled region, ``D`` the pixels eq. 5's denominator counts.

    Parameters
    ----------
    camera : Camera; real : (H, W) int8
    cand : People — the candidates (C); forms : Forms — their forms (for the sampled region)
    others : People — everybody else (M)
    ring_px : float; draw : DrawArgs; ref : int; count_unexplained : bool

    Returns
    -------
    (C,) float64
    """
    occ = np.full(real.shape, np.inf)
    c_in, c_rg = _reference_masks(camera, occ, cand, ring_px, draw)
    o_in, o_rg = _reference_masks(camera, occ, others, ring_px, draw)
    u0, u1, v0, v1, _ = sample_region(forms, real.shape, 0)
    region = np.zeros(real.shape, bool)
    region[v0:v1, u0:u1] = True
    base = np.zeros(real.shape, bool) | (real > 0 if count_unexplained else False)
    for a, b in zip(o_in, o_rg):
        base |= a | b
    counted = [region & (base | a | b) for a, b in zip(c_in, c_rg)]
    return np.array([(counted[ref] & ~d).sum() for d in counted], dtype=float)


__all__ = ["dropped_pixels", "dropped_pixels_reference"]
