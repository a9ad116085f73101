"""Searches along lines of sight, beyond the paper's 9-candidate steps: placing newcomers, rescues.

One camera cannot tell depth: a blob's foot point is uncertain along its line of sight, and E has
a second peak there behind a row of desks. The 9-candidate steps climb E locally and cannot cross
what is not walkable, so two searches look along the lines of sight instead:

* :func:`birth_search` places a just-proposed person by a coarse grid along the proposing
  camera's ray (and the ray of the camera that sees them largest);
* :func:`rescue` moves a tracked person along each seeing camera's ray when a place there scores
  clearly higher; :func:`rescue_people` runs it on failing tracks and, periodically, on everyone.

Both score on a :class:`~.joint.JointImage`, everybody else fixed.
"""

from __future__ import annotations

from typing import NamedTuple, Sequence

import numpy as np

from worldtrack.trackers.base import Person
from worldtrack.trackers.ellipsoid.cameras import CameraView, ray_direction
from worldtrack.trackers.ellipsoid.joint import JointImage


def birth_search(joint: JointImage, k: int, search_m: float, proposer: CameraView | None = None) -> None:
    """Place just-proposed person ``k`` by a coarse grid search before the 9-candidate steps.

    A blob's foot point is uncertain mostly along the line of sight of the camera the blob was
    found in (``proposer``: feet lost in a hole of the mask, two people merged, a head
    back-projected at the default height), so candidates spread ±``search_m`` (m) along that
    camera's ray through the guess and ±0.2 m across it, 0.1 m apart — and likewise along the ray
    of the camera that sees the guess largest (the only one without ``proposer``) — all scored
    over every camera. The person moves to the best (in ``joint``), or stays where no candidate
    is seen.
    """
    xy = joint.xy
    axes = [joint.axes(k, along_ray=True)]
    if proposer is not None:
        ray = ray_direction(proposer.camera, xy[k])
        if not np.allclose(ray, axes[0][0]):  # the same camera: nothing new to search
            axes.append((ray, np.array([-ray[1], ray[0]])))
    along = np.arange(-search_m, search_m + 1e-9, 0.1)
    across = np.array([-0.2, -0.1, 0.0, 0.1, 0.2])
    grid = np.array([(a, c) for a in along for c in across])
    cand = np.concatenate([xy[k] + grid[:, :1] * d[0] + grid[:, 1:] * d[1] for d in axes])
    cand = cand[joint.walkable(cand)]
    if len(cand) == 0:
        return
    # Scored with the ring (and, by default, the unexplained foreground): without them the
    # smallest, farthest ellipse that fits inside the blob would win (the paper's Fig. 2).
    e, den, forms = joint.score(k, cand, use_ring=True)
    b = int(np.argmax(e))
    if not np.isfinite(e[b]):
        return
    joint.move(k, cand[b], forms, b)


class RescueArgs(NamedTuple):
    """The rescue search: along each line of sight ±``search_m`` (m), a place must beat the current
    E by ``gain``; never within ``min_separation_m`` (m) of somebody else."""

    search_m: float
    gain: float
    min_separation_m: float


def rescue(joint: JointImage, k: int, args: RescueArgs) -> tuple[float, float] | None:
    """Search the lines of sight of person ``k`` for a clearly better place.

    The current place is scored in the same call as the candidates: E depends on the pixels
    visited (the union of the candidates' boxes, on a stride that keeps ``target_pixels``), so
    only scores from one call compare.

    Returns
    -------
    (E, denominator) of the new place (the person has moved there in ``joint``), or None.
    """
    xy = joint.xy
    along = np.arange(-args.search_m, args.search_m + 1e-9, 0.15)
    along = along[np.abs(along) > 0.2]
    # Along every seeing camera's line of sight: with two cameras the error lies along the one
    # that fixes depth worse, not necessarily the one that sees the person largest.
    cand = np.concatenate([xy[k] + along[:, None] * d for d in joint.ray_directions(k)])
    others = np.delete(xy, k, axis=0)
    ok = joint.walkable(cand)
    if len(others):
        dist = np.min(np.linalg.norm(cand[:, None, :] - others[None, :, :], axis=2), axis=1)
        ok &= dist >= args.min_separation_m
    if not ok.any():
        return None
    cand = np.vstack([xy[k], cand[ok]])                   # row 0: where the person is now
    e, den, forms = joint.score(k, cand, use_ring=True)
    num = np.where(np.isfinite(e), e, 0.0) * den          # Σ sim·real (0 where not in view)
    e_here = float(e[0]) if np.isfinite(e[0]) else 0.0
    # E is a ratio: a place where less of the person is in view (past the image border) can
    # score higher on less evidence. A move must also raise the net matched evidence.
    e[num < num[0]] = -np.inf
    e[0] = -np.inf
    b = int(np.argmax(e))
    if not np.isfinite(e[b]) or e[b] < e_here + args.gain:
        return None
    joint.move(k, cand[b], forms, b)
    return float(e[b]), float(den[b])


class RescueSchedule(NamedTuple):
    """When people are searched: ``every`` frames (0: never periodically) counting frames with
    ``frame``; a failing track that found nothing waits ``retry_s`` seconds; ``half_frame`` (s) of
    slack for rounded time stamps."""

    frame: int
    every: int
    retry_s: float
    half_frame: float


def rescue_people(joint: JointImage, people: Sequence[Person], best_e: np.ndarray, best_den: np.ndarray,
                  args: RescueArgs, when: RescueSchedule, t: float) -> None:
    """Run :func:`rescue` on the tracked people of ``people`` (person ``k`` is ``joint``'s ``k``)
    whose support is failing (counter ``low``) and, periodically, on each; a rescued person's E
    and denominator replace theirs in ``best_e``, ``best_den`` (in place).

    A failing track whose search found nothing waits ``retry_s`` before the next
    (``Person.rescue_after``): the same line of sight a frame later rarely holds a new answer.
    """
    for k, p in enumerate(people):
        # Periodically too, for everyone (a rescue never moves onto somebody else).
        periodic = when.every > 0 and (when.frame + p.id) % when.every == 0
        failing = p.count("low") > 0 and t + when.half_frame >= p.rescue_after
        if p.mode == "tracking" and (failing or periodic):
            found = rescue(joint, k, args)
            if found is not None:
                best_e[k], best_den[k] = found
            elif failing:
                p.rescue_after = t + when.retry_s


__all__ = ["RescueArgs", "RescueSchedule", "birth_search", "rescue", "rescue_people"]
