"""A track one camera cannot see, looked for along the seeing camera's line of sight where it can.

With two cameras, depth along camera A's line of sight is fixed by camera B. Where B's image does
not reach a track's place (out of its image, behind a pillar), B says nothing — neither for nor
against — and the track can sit anywhere along A's ray: one camera's line-of-sight problem again.
In the two-camera crowds most ghost rows and many displaced ones are such places (issue 37).

:func:`cross_view` looks along A's ray, over a range longer than the rescue's, at the places B
does show, at least ``clear_m`` from everybody else, and scores them with every camera, everybody
else fixed. The person moves to the best if B there shows them (B's own E at least
``min_ratio``), the matched evidence with every camera rises, and E with every camera beats E at
the current place (where B's unexplained foreground in the searched region counts against
staying) by ``gain``. Where B shows nobody along the ray, the person stays where B cannot see:
those are the only depths left.

Opt-in (``ellipsoid.cross_view.search_m`` > 0). Crowd 10, paired in one session: dev seeds 20–39
0.920 → 0.936 (12 better, 1 worse); held-out 140–199 0.914 → 0.920 (33 better, 21 worse),
never-used 200–219 0.897 → 0.909, but 140–159 alone 0.932 → 0.925. What B shows along A's ray is *a*
person, not necessarily this one: a track that truly stands where B cannot see can be pulled
onto somebody B shows (issue 37).

>>> import numpy as np
>>> ray_candidates(np.array([1.0, 2.0]), [np.array([1.0, 0.0])], 0.5, 0.25).round(2).tolist()
[[0.5, 2.0], [0.75, 2.0], [1.25, 2.0], [1.5, 2.0]]
"""

from __future__ import annotations

from typing import Callable, Mapping, NamedTuple, Sequence

import numpy as np

from worldtrack.trackers.base import Person
from worldtrack.trackers.ellipsoid.cameras import CameraView, ray_direction
from worldtrack.trackers.ellipsoid.joint import JointImage


#: A last test of a move: (joint image, person index, unseeing camera ids, new place (2,) m) → allowed.
Accept = Callable[[JointImage, int, Sequence[str], np.ndarray], bool]


class CrossViewArgs(NamedTuple):
    """Along each camera's line of sight ±``search_m`` (m) in steps of ``step_m`` (m); a camera
    shows a place when ``min_share`` of the ellipse is in its image and not hidden by obstacles;
    a new place must have the unseeing camera's E at least ``min_ratio`` there and raise E with
    every camera by ``gain``; never within ``min_separation_m`` (m) of somebody else."""

    search_m: float
    step_m: float
    min_share: float
    min_ratio: float
    gain: float
    min_separation_m: float


def shown_share(view: CameraView, xy: np.ndarray, height: float, width: float) -> np.ndarray:
    """Share (M,) of a person's ellipse at each of ``xy`` (M, 2) m that is inside ``view``'s image
    and not hidden by an obstacle (0 behind the camera)."""
    pts = np.asarray(xy, float).reshape(-1, 2)
    inner, _, _, valid, _ = view.forms(pts, np.full(len(pts), height), np.full(len(pts), width))
    det = inner[:, 2] * inner[:, 4] - inner[:, 3] ** 2
    area = np.where(valid & (det > 0), np.pi / np.sqrt(np.maximum(det, 1e-12)), 0.0)
    seen = np.array([view.visible_pixels(p, height, width) for p in pts], float)
    return np.where(area > 0, np.minimum(seen / np.maximum(area, 1e-9), 1.0), 0.0)


def ray_candidates(xy: np.ndarray, rays: Sequence[np.ndarray], search_m: float, step_m: float) -> np.ndarray:
    """Places (M, 2) along each unit floor direction of ``rays`` through ``xy`` (2,), ±``search_m``
    in steps of ``step_m`` (m), ``xy`` itself left out."""
    along = np.arange(-search_m, search_m + 1e-9, step_m)
    along = along[np.abs(along) > 1e-9]
    return np.concatenate([xy + along[:, None] * d for d in rays]) if rays else np.empty((0, 2))


def cross_view(joint: JointImage, k: int, unseeing: Sequence[str], args: CrossViewArgs,
               accept: Accept | None = None) -> tuple[float, float] | None:
    """Search the rays of the cameras that show person ``k`` for a place that the cameras
    ``unseeing`` (which do not show where ``k`` is now) show and confirm; ``accept(joint, k,
    unseeing, xy)``, when given, must allow the best place too (:mod:`.cross_view_colour`).

    Returns (E, denominator) of the new place (the person has moved there in ``joint``), or None.
    """
    xy = joint.xy
    height, width = joint.people.heights[k], joint.people.widths[k]
    seeing = [c for c in joint.cids if c not in unseeing]
    rays = [ray_direction(joint.views[c].camera, xy[k]) for c in seeing]
    cand = ray_candidates(xy[k], rays, args.search_m, args.step_m)
    ok = joint.walkable(cand) if len(cand) else np.zeros(0, bool)
    others = np.delete(xy, k, axis=0)
    if len(others) and len(cand):
        ok &= np.min(np.linalg.norm(cand[:, None, :] - others[None, :, :], axis=2), axis=1) >= args.min_separation_m
    cand = cand[ok]
    shown = np.zeros(len(cand), bool)
    for c in unseeing:
        shown |= shown_share(joint.views[c], cand, height, width) >= args.min_share
    cand = cand[shown]
    if len(cand) == 0:
        return None
    cand = np.vstack([xy[k], cand])                        # row 0: where the person is now
    num, den, forms = joint.camera_sums(k, cand, use_ring=True)
    tot_num, tot_den = num.sum(axis=0), den.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        e = np.where(tot_den > 0, tot_num / np.maximum(tot_den, 1e-12), -np.inf)
        rows = [joint.cids.index(c) for c in unseeing]
        ratio = np.where(den[rows] > 0, num[rows] / np.maximum(den[rows], 1e-12), -np.inf).max(axis=0)
    e_here = float(e[0]) if np.isfinite(e[0]) else 0.0
    good = (ratio >= args.min_ratio) & (tot_num > tot_num[0])
    good[0] = False
    e = np.where(good, e, -np.inf)
    b = int(np.argmax(e))
    if not np.isfinite(e[b]) or e[b] < e_here + args.gain:
        return None
    if accept is not None and not accept(joint, k, unseeing, cand[b]):
        return None
    joint.move(k, cand[b], forms, b)
    return float(e[b]), float(tot_den[b])


def cross_view_people(joint: JointImage, people: Sequence[Person], views: Mapping[str, CameraView],
                      best_e: np.ndarray, best_den: np.ndarray, args: CrossViewArgs,
                      accept: Accept | None = None) -> int:
    """Run :func:`cross_view` on each tracked person of ``people`` (person ``k`` is ``joint``'s
    ``k``) whose place some camera of ``joint`` does not show; a moved person's E and denominator
    replace theirs in ``best_e``, ``best_den`` (in place). Returns how many moved."""
    if len(joint.cids) < 2:
        return 0
    moved = 0
    for k, p in enumerate(people):
        if p.mode != "tracking":
            continue
        here = joint.xy[k]
        unseeing = [c for c in joint.cids
                    if shown_share(views[c], here, p.height, p.width)[0] < args.min_share]
        if not unseeing or len(unseeing) == len(joint.cids):
            continue
        found = cross_view(joint, k, unseeing, args, accept)
        if found is not None:
            best_e[k], best_den[k] = found
            moved += 1
    return moved


__all__ = ["CrossViewArgs", "cross_view", "cross_view_people", "ray_candidates", "shown_share"]
