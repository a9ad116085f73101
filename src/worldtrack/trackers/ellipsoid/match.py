"""The matching rounds of seed 000 for everybody, in one compiled loop.

Each round moves every person in turn to the best of 9 candidates (−s, 0, +s along the viewing
direction of the camera that sees them largest and its perpendicular), with everybody else fixed
in the joint simulated image, and adapts the step (coarse to fine). With several cameras a tracked
person's candidates are scored with the cameras weighed as at their current place
(:func:`held_scores`). This is
``EllipsoidTracker._rounds_python`` — the readable version it is tested against — without the
Python overhead per person and round, which at 640×480 was ~40 % of the tracker's time.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from worldtrack.trackers.ellipsoid.score import score_camera

#: The 9 candidate offsets in units of the step, along (viewing direction, perpendicular).
OFFSETS = np.array([(i, j) for i in (-1, 0, 1) for j in (-1, 0, 1)], dtype=np.float64)
#: Index of "stay" among the candidates.
STAY = 4


@njit(cache=True)
def walkable_lookup(walk, origin, resolution, x, y):
    """True when floor point (x, y) falls in a walkable cell of the raster ``walk``."""
    fi = (x - origin[0]) / resolution
    fj = (y - origin[1]) / resolution
    if not (0.0 <= fi < walk.shape[1] and 0.0 <= fj < walk.shape[0]):
        return False
    return walk[int(fj), int(fi)]


@njit(cache=True)
def held_scores(num: np.ndarray, den: np.ndarray, ref: int) -> np.ndarray:
    """E of each candidate with every camera weighed as at candidate ``ref`` (the current place).

    Parameters
    ----------
    num, den : (C, J) — each camera's Σ sim·real and Σ|sim| for each of J candidates
    ref : int — the candidate that is the person's current place

    Returns
    -------
    (J,) — Σ_c den[c, ref] · num[c, j] / den[c, j] over Σ_c den[c, ref]. A camera that shows
    candidate ``j`` none of the person counts at its ratio at ``ref``; one that shows nothing at
    ``ref`` does not count; −inf where no camera shows candidate ``j`` or none shows ``ref``.
    At ``ref`` this is Σ num / Σ den; with one camera it is num / den everywhere.

    With Σ num / Σ den for every candidate, each camera weighs in by how much of the candidate
    it shows, so a candidate gains by sliding out of the view of a camera that fits the person
    badly (at the image border, from steeply above), and with two cameras facing each other a
    track slid 0.5–1 m along their shared line of sight.
    """
    C, J = num.shape
    total = 0.0
    for c in range(C):
        total += den[c, ref]
    e = np.full(J, -np.inf)
    if not total > 0:
        return e
    for j in range(J):
        seen = False
        acc = 0.0
        for c in range(C):
            seen = seen or den[c, j] > 0
            w = den[c, ref]
            if w > 0:
                acc += w * (num[c, j] / den[c, j] if den[c, j] > 0 else num[c, ref] / w)
        if seen:
            e[j] = acc / total
    return e


def held_scores_reference(num: np.ndarray, den: np.ndarray, ref: int) -> np.ndarray:
    """:func:`held_scores` in plain NumPy, the version it is tested against."""
    w = den[:, ref]
    e = np.full(num.shape[1], -np.inf)
    if not w.sum() > 0:
        return e
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.where(den > 0, num / den, (num[:, ref] / w)[:, None])
    mean = (w[:, None] * np.where(w[:, None] > 0, ratio, 0.0)).sum(axis=0) / w.sum()
    seen = (den > 0).any(axis=0)
    e[seen] = mean[seen]
    return e


@njit(cache=True)
def run_rounds(xy, hs, ws, n_moving, use_ring, cam_P, cam_K, cam_dist, cam_has_dist, cam_size, cam_centre,
               cam_dir, cam_ring_px, ring_fraction, grids, occs, reals,
               s_inner, s_ring, s_box, s_valid, s_dist, walk, walk_origin, walk_res,
               step_m, min_step, max_step, iterations, max_iterations, adaptive, min_gain, target_pixels,
               symmetric, min_depth, held):
    """Move people ``0 … n_moving − 1`` round after round; the others stay fixed.

    Parameters
    ----------
    xy : (N, 2) — floor positions, updated in place
    hs, ws : (N,) — ellipsoid heights and widths
    use_ring : (n_moving,) bool — False for people in capture mode
    cam_* : per camera (C, …) — P, K, distortion, has_dist, (width, height), centre, floor viewing
        direction (unit (2,)), ring width (px)
    grids, occs : typed lists of per-camera arrays (ideal pixel grid, obstacle floor distances),
        built once per tracker
    reals : tuple of the per-camera ternary real images (C of them, int8): a tuple costs nothing
        to pass each frame, where building a typed list took ~0.1 ms
    s_inner, s_ring, s_box, s_valid, s_dist : (C, N, …) — everybody's ellipse forms per camera,
        updated in place for the people who move
    walk, walk_origin, walk_res : the walkable raster
    step_m … min_depth : the tracker's configuration
    held : bool — score the candidates of tracked people (not those in capture mode, still sliding
        into their blob) with :func:`held_scores`, cameras weighed as at the current place, instead
        of Σ num / Σ den

    Returns
    -------
    best_e, best_den : (n_moving,) — E and its denominator at each person's final place
    """
    C = cam_P.shape[0]
    n = n_moving
    step = np.full(n, step_m)
    done = np.zeros(n, dtype=np.bool_)
    best_e = np.zeros(n)
    best_den = np.zeros(n)
    rounds = max_iterations if adaptive else iterations
    cand = np.empty((9, 2))
    h9 = np.empty(9)
    w9 = np.empty(9)
    f_inner = np.empty((C, 9, 5))
    f_ring = np.empty((C, 9, 5))
    f_box = np.empty((C, 9, 4), dtype=np.int64)
    f_valid = np.empty((C, 9), dtype=np.bool_)
    f_dist = np.empty((C, 9))
    for it in range(rounds):
        for k in range(n):
            if done[k]:
                continue
            # Axes: the viewing direction of the camera that sees the person largest.
            best_cam = 0
            best_area = -1
            for c in range(C):
                area = 0
                if s_valid[c, k]:
                    area = max(0, s_box[c, k, 1] - s_box[c, k, 0]) * max(0, s_box[c, k, 3] - s_box[c, k, 2])
                if area > best_area:
                    best_cam = c
                    best_area = area
            dx, dy = cam_dir[best_cam, 0], cam_dir[best_cam, 1]
            for j in range(9):
                a, b = OFFSETS[j, 0] * step[k], OFFSETS[j, 1] * step[k]
                cand[j, 0] = xy[k, 0] + a * dx - b * dy
                cand[j, 1] = xy[k, 1] + a * dy + b * dx
                h9[j] = hs[k]
                w9[j] = ws[k]
            num = np.zeros((C, 9))
            den = np.zeros((C, 9))
            for c in range(C):
                nu, de, ci, cr, cb, cv, cd = score_camera(
                    cam_P[c], cam_K[c], cam_dist[c], cam_has_dist[c], cam_size[c, 0], cam_size[c, 1], cam_centre[c],
                    grids[c], occs[c], reals[c], use_ring[k], cand, h9, w9, cam_ring_px[c], min_depth,
                    ring_fraction, s_inner[c], s_ring[c], s_box[c], s_dist[c], s_valid[c], k, target_pixels,
                    use_ring[k] and symmetric)
                f_inner[c] = ci
                f_ring[c] = cr
                f_box[c] = cb
                f_valid[c] = cv
                f_dist[c] = cd
                num[c] = nu
                den[c] = de
            den_all = den.sum(axis=0)
            if not den_all[STAY] > 0:
                # Nobody sees this person at all: nothing to match.
                done[k] = True
                best_e[k] = 0.0
                best_den[k] = den_all[STAY]
                continue
            if held and C > 1 and use_ring[k]:  # tracked people; one camera: the same either way
                e = held_scores(num, den, STAY)
            else:
                num_all = num.sum(axis=0)
                e = np.full(9, -np.inf)
                for j in range(9):
                    if den_all[j] > 0:
                        e[j] = num_all[j] / den_all[j]
            for j in range(9):
                if j != STAY and not walkable_lookup(walk, walk_origin, walk_res, cand[j, 0], cand[j, 1]):
                    e[j] = -np.inf
            b = int(np.argmax(e))
            if adaptive and e[b] - e[STAY] < min_gain:
                b = STAY
            best_e[k] = e[b]
            best_den[k] = den_all[b]
            if b != STAY:
                xy[k, 0] = cand[b, 0]
                xy[k, 1] = cand[b, 1]
                for c in range(C):
                    s_inner[c, k] = f_inner[c, b]
                    s_ring[c, k] = f_ring[c, b]
                    s_box[c, k] = f_box[c, b]
                    s_valid[c, k] = f_valid[c, b]
                    s_dist[c, k] = f_dist[c, b]
            if adaptive:
                if b == STAY:
                    if step[k] <= min_step * 1.001:
                        done[k] = True
                    else:
                        step[k] = max(step[k] / 2, min_step)
                elif it >= iterations - 1:
                    step[k] = min(step[k] * 2, max_step)
        if done.all():
            break
    return best_e, best_den
