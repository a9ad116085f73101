"""The matching rounds of paper 000 (§5): every person in turn to the best of 9 candidates, K times.

Each round moves every person in turn to the best of 9 candidates (−s, 0, +s along the viewing
direction of the camera that sees them largest and its perpendicular), with everybody else fixed
in the joint simulated image (:mod:`.joint`), and adapts the step (coarse to fine). With several
cameras a tracked person's candidates are scored with the cameras weighed as at their current
place (:func:`held_scores`).

Two implementations, chosen by name (``ellipsoid.match.rounds``) from :data:`ROUNDS`:
``compiled`` (:func:`run_rounds`, one compiled loop; at 640×480 the Python overhead per person and
round was ~40 % of the tracker's time) and ``python`` (:func:`rounds_python`, the readable version
it is tested against: the same tracks).

>>> held_scores_reference(np.array([[6.0, 8.0]]), np.array([[10.0, 10.0]]), 0).tolist()
[0.6, 0.8]
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

import numpy as np
from numba import njit

from worldtrack.registry import Registry
from worldtrack.trackers.ellipsoid.args import Forms, ScoreArgs, StepArgs
from worldtrack.trackers.ellipsoid.fixed_pixels import dropped_pixels
from worldtrack.trackers.ellipsoid.score import score_camera

if TYPE_CHECKING:
    from worldtrack.trackers.ellipsoid.joint import JointImage

#: The 9 candidate offsets in units of the step, along (viewing direction, perpendicular).
OFFSETS = np.array([(i, j) for i in (-1, 0, 1) for j in (-1, 0, 1)], dtype=np.float64)
#: Index of "stay" among the candidates.
STAY = 4


@njit(cache=True)
def walkable_lookup(walk, x, y):
    """True when floor point (x, y) falls in a walkable cell of the raster ``walk`` (:class:`Walkable`)."""
    fi = (x - walk.origin[0]) / walk.resolution
    fj = (y - walk.origin[1]) / walk.resolution
    inside = walk.inside
    if not (0.0 <= fi < inside.shape[1] and 0.0 <= fj < inside.shape[0]):
        return False
    return inside[int(fj), int(fi)]


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
def adapt_step(step, moved, it, steps):
    """The adaptive step after person's move in round ``it``: (new step, done). Halved when "stay"
    won (done once at ``min_step_m``), doubled up to ``max_step_m`` when still moving after the K
    rounds (coarse to fine, and fast walkers are followed)."""
    if not moved:
        if step <= steps.min_step_m * 1.001:
            return step, True
        return max(step / 2, steps.min_step_m), False
    if it >= steps.iterations - 1:
        return min(step * 2, steps.max_step_m), False
    return step, False


@njit(cache=True)
def run_rounds(people, n_moving, use_ring, cams, reals, state, walk, steps, scoring):
    """Move people ``0 … n_moving − 1`` round after round; the others stay fixed.

    Compiled, and one loop: the per-person candidates' arrays are allocated once for all rounds
    (the readable version is :func:`rounds_python`, which the tests compare it with).

    Parameters
    ----------
    people : People — floor positions (N, 2), updated in place; heights, widths (N,)
    n_moving : int
    use_ring : (n_moving,) bool — False for people in capture mode
    cams : tuple of CameraArgs — the cameras (C of them)
    reals : tuple of the per-camera ternary real images (C of them, int8): a tuple costs nothing
        to pass each frame, where building a typed list took ~0.1 ms
    state : Forms — everybody's ellipse forms per camera, (C, N, …), updated in place for the
        people who move
    walk : Walkable — the walkable raster
    steps : StepArgs
    scoring : Scoring — how candidates are drawn and scored; ``held``: score the candidates
        of tracked people (not those in capture mode, still sliding into their blob) with
        :func:`held_scores`, cameras weighed as at the current place, instead of Σ num / Σ den;
        with ``fixed_pixels`` too, each camera's denominators also count the pixels counted at the
        current place (:func:`~.fixed_pixels.dropped_pixels`)

    Returns
    -------
    best_e, best_den : (n_moving,) — E and its denominator at each person's final place
    """
    xy, hs, ws = people
    s_inner, s_ring, s_box, s_valid, s_dist = state
    C = len(cams)
    n = n_moving
    step = np.full(n, steps.step_m)
    done = np.zeros(n, dtype=np.bool_)
    best_e = np.zeros(n)
    best_den = np.zeros(n)
    adaptive = steps.adaptive
    rounds = steps.max_iterations if adaptive else steps.iterations
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
            dx, dy = cams[best_cam].floor_direction[0], cams[best_cam].floor_direction[1]
            for j in range(9):
                a, b = OFFSETS[j, 0] * step[k], OFFSETS[j, 1] * step[k]
                cand[j, 0] = xy[k, 0] + a * dx - b * dy
                cand[j, 1] = xy[k, 1] + a * dy + b * dx
                h9[j] = hs[k]
                w9[j] = ws[k]
            num = np.zeros((C, 9))
            den = np.zeros((C, 9))
            opts = ScoreArgs(use_ring[k], scoring.target_pixels, use_ring[k] and scoring.symmetric)
            for c in range(C):
                others = Forms(s_inner[c], s_ring[c], s_box[c], s_valid[c], s_dist[c])
                nu, de, ci, cr, cb, cv, cd = score_camera(cams[c], reals[c], cand, h9, w9, scoring.draw, others, k,
                                                          opts)
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
            if scoring.held and C > 1 and use_ring[k]:  # tracked people; one camera: the same either way
                if scoring.fixed_pixels:
                    for c in range(C):
                        ov = s_valid[c].copy()
                        ov[k] = False
                        den[c] += dropped_pixels(cams[c], reals[c], Forms(f_inner[c], f_ring[c], f_box[c], f_valid[c],
                                                                          f_dist[c]),
                                                 Forms(s_inner[c], s_ring[c], s_box[c], ov, s_dist[c]), STAY, opts)
                e = held_scores(num, den, STAY)
            else:
                num_all = num.sum(axis=0)
                e = np.full(9, -np.inf)
                for j in range(9):
                    if den_all[j] > 0:
                        e[j] = num_all[j] / den_all[j]
            for j in range(9):
                if j != STAY and not walkable_lookup(walk, cand[j, 0], cand[j, 1]):
                    e[j] = -np.inf
            b = int(np.argmax(e))
            if adaptive and e[b] - e[STAY] < steps.min_gain:
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
                step[k], done[k] = adapt_step(step[k], b != STAY, it, steps)
        if done.all():
            break
    return best_e, best_den


class Rounds(Protocol):
    """The matching rounds: move people ``0 … n_moving − 1`` of ``joint`` round after round (the
    others fixed); return E and its denominator at each one's final place, (n_moving,) each."""

    def __call__(self, joint: "JointImage", use_ring: np.ndarray, steps: StepArgs) -> tuple[np.ndarray, np.ndarray]:
        ...


#: The implementations of :class:`Rounds` by name (``ellipsoid.match.rounds``).
ROUNDS: Registry[Rounds] = Registry("ellipsoid.match.rounds")


@ROUNDS.register("compiled")
def rounds_compiled(joint: "JointImage", use_ring: np.ndarray, steps: StepArgs) -> tuple[np.ndarray, np.ndarray]:
    """:func:`run_rounds` on a :class:`~.joint.JointImage` (positions and forms updated in place)."""
    cams = tuple(joint.views[cid].args for cid in joint.cids)
    reals = tuple(joint.real[cid] for cid in joint.cids)
    return run_rounds(joint.people, len(use_ring), use_ring, cams, reals, joint.stacked, joint.walk, steps,
                      joint.settings)


@ROUNDS.register("python")
def rounds_python(joint: "JointImage", use_ring: np.ndarray, steps: StepArgs) -> tuple[np.ndarray, np.ndarray]:
    """The matching rounds in plain Python: the reference for :func:`run_rounds`."""
    n = len(use_ring)
    step = np.full(n, steps.step_m)
    done = np.zeros(n, dtype=bool)
    best_e = np.zeros(n)
    best_den = np.zeros(n)
    rounds = steps.max_iterations if steps.adaptive else steps.iterations
    for it in range(rounds):
        for k in range(n):
            if done[k]:
                continue
            e, den, cand, forms, ok = _score_person(joint, k, step[k], bool(use_ring[k]))
            if not ok:
                done[k] = True
                best_e[k], best_den[k] = e[STAY], den[STAY]
                continue
            b = int(np.argmax(e))
            if steps.adaptive and e[b] - e[STAY] < steps.min_gain:
                b = STAY
            best_e[k], best_den[k] = e[b], den[b]
            if b != STAY:
                joint.move(k, cand[b], forms, b)
            if steps.adaptive:
                step[k], done[k] = adapt_step(step[k], b != STAY, it, steps)
        if done.all():
            break
    return best_e, best_den


def _score_person(joint: "JointImage", k: int, step: float, use_ring: bool):
    """E of the 9 candidates of person ``k`` over all cameras: Σ num / Σ den, with the cameras
    weighed as at the current place for a tracked person (``held``)."""
    d, e_perp = joint.axes(k)
    cand = joint.xy[k] + step * (OFFSETS[:, :1] * d + OFFSETS[:, 1:] * e_perp)
    e, den, forms = joint.score(k, cand, use_ring, current=STAY if use_ring else None)
    walk = joint.walkable(cand)
    walk[STAY] = True
    e[~walk] = -np.inf
    ok = bool(den[STAY] > 0)
    if not ok:
        e[:] = 0.0
    return e, den, cand, forms, ok


__all__ = ["OFFSETS", "ROUNDS", "Rounds", "STAY", "adapt_step", "held_scores", "held_scores_reference", "rounds_compiled",
           "rounds_python", "run_rounds", "walkable_lookup"]
