"""Each worker's own view rays of a person, and the height the head rays of several workers tell.

A one-camera worker's depth slides along its line of sight (0.4–0.9 m on two-rooms, issue 39m)
while the pixels it rests on do not: the top of the head and the bottom of the feet in its
foreground fix two *directions* from its camera, whatever height and depth its tracker settled
on. A worker that sees a person only with its own camera cannot measure their height when the
feet are hidden, and the workers copy the map's height (0.075 m off on two-rooms dev seeds, one
process 0.035) — and a height 0.1 m off moves a head-only depth ~0.5 m at 7 m from a 3 m camera.

So, with ``map.head_rays``, a worker publishes per person and camera the camera's centre and the
unit directions through those two pixels (:func:`view_rays`, NaN where a pixel is not clearly
shown), and the fusion triangulates the height where two workers' cameras show the head
(:func:`ray_height`): two cameras facing each other along one axis see a person's floor point on
one line, but their head rays cross in 3-D at ~30° (from 3 m above the floor to a 1.7 m head
5 m from each). The map keeps the median of a person's last such heights
(:mod:`worldtrack.map.fusion`). Their *place* the rays tell worse than the trackers' fits
(two-rooms seed 17, clear frames: 0.10 m against 0.086 m), so it is left to them.

>>> o = np.array([0.3, 2.5, 3.0])
>>> ray_height([ViewRay(1, *o, 0.9, 0.0, -0.3)], np.array([5.0, 2.5, 1.7])) is None    # one camera: no height
True
"""

from __future__ import annotations

import math
from typing import Any, Mapping, NamedTuple, Sequence

import numpy as np

from worldtrack.geometry.camera import Camera
from worldtrack.map.evidence import people_boxes

#: Foreground pixels a person's region needs before its ends are read.
MIN_PIXELS = 20
#: The region around a person's image box searched for their silhouette's ends, as a share of the
#: box's height above and below it (a depth 0.6 m off at 5 m from a 3 m camera moves the feet by 0.17).
SEARCH_MARGIN = 0.35


class ViewRay(NamedTuple):
    """One camera's rays of one person (metres, unit vectors): its centre ``ox, oy, oz``, the
    direction through the top of the head ``hx, hy, hz`` and through the bottom of the feet
    ``fx, fy, fz`` (NaN where the camera does not show that end clearly)."""

    id: int
    ox: float
    oy: float
    oz: float
    hx: float = float("nan")
    hy: float = float("nan")
    hz: float = float("nan")
    fx: float = float("nan")
    fy: float = float("nan")
    fz: float = float("nan")


def _ends(fg: np.ndarray, down: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The top and bottom (u, v) of the foreground pixels ``fg`` (n, 2) along image direction
    ``down``: the mean of the extreme 1 % on each side (with those within half a pixel of them), moved half
    a pixel outwards."""
    if len(fg) < MIN_PIXELS:
        return None
    along = fg @ down
    n = max(1, len(fg) // 100)
    lo, hi = np.partition(along, [n - 1, len(along) - n])[[n - 1, len(along) - n]]
    # All pixels level with the cut: a flat top (a box, a hat) is taken whole, not its left end.
    return fg[along <= lo + 0.5].mean(0) - 0.5 * down, fg[along >= hi - 0.5].mean(0) + 0.5 * down


def view_rays(cam: Camera, mask: np.ndarray | None, people: np.ndarray, ids: Sequence[int],
              occlusion: np.ndarray | None = None) -> list[ViewRay]:
    """The head and feet rays of ``people`` (n, 4: x, y, height, width m) in ``cam``'s foreground
    ``mask`` (H, W, 1 = foreground), one :class:`ViewRay` per person that shows (ids ``ids``).

    A person's pixels are the foreground in their image box (:func:`~worldtrack.map.evidence.people_boxes`,
    1.25× as wide, :data:`SEARCH_MARGIN` taller on each side) not inside the box of a person nearer
    to the camera, nor inside a farther person's box outside their own. An end counts only where
    it is clearly shown: the pixel two steps beyond it is inside the image and the searched region
    (not cut), not in a nearer person's box, not another person's foreground (the silhouette may
    go on there), and for the feet not behind an obstacle
    (``occlusion``: (H, W) floor distance of the scene's obstacles, m); a silhouette touching the
    image's left or right edge gives none (a sliver)."""
    people = np.asarray(people, float).reshape(-1, 4)
    if mask is None or mask.shape[:2] != (cam.height, cam.width) or not len(people):
        return []
    boxes = people_boxes(cam, people * [1, 1, 1, 1.25])
    out = []
    for k, (u0, v0, u1, v1, dist) in enumerate(boxes):
        if not (u1 > u0 and v1 > v0):
            continue
        pad = SEARCH_MARGIN * (v1 - v0)
        iu0, iv0 = max(0, int(math.floor(u0))), max(0, int(math.floor(v0 - pad)))
        iu1, iv1 = min(cam.width, int(math.ceil(u1))), min(cam.height, int(math.ceil(v1 + pad)))
        if iu1 <= iu0 or iv1 <= iv0:
            continue
        vv, uu = np.mgrid[iv0:iv1, iu0:iu1]
        own = (uu >= u0) & (uu <= u1) & (vv >= v0) & (vv <= v1)
        region = np.ones_like(own)
        nearer = np.zeros_like(own)
        for j, (bu0, bv0, bu1, bv1, bdist) in enumerate(boxes):
            if j == k or not (bu1 > bu0):
                continue
            inside = (uu >= bu0) & (uu <= bu1) & (vv >= bv0) & (vv <= bv1)
            if bdist < dist - 0.3:
                nearer |= inside
            else:
                region &= ~inside | own
        region &= ~nearer
        fg = mask[iv0:iv1, iu0:iu1] == 1
        pts = np.column_stack([uu[fg & region], vv[fg & region]]).astype(float)
        mine = fg & region
        if len(pts) < MIN_PIXELS or (iu0 == 0 and mine[:, 0].any()) or (iu1 == cam.width and mine[:, -1].any()):
            continue
        down = cam.image_down_direction(pts.mean(0)[None])[0]
        ends = _ends(pts, down) if np.isfinite(down).all() else None
        if ends is None:
            continue
        dirs = []
        for end, step in zip(ends, (-2.0, 2.0)):
            q = end + step * down
            iq = np.round(q).astype(int)
            ok = bool(cam.in_image(q[None])[0]) and iv0 <= iq[1] < iv1 and iu0 <= iq[0] < iu1
            ok = ok and not nearer[iq[1] - iv0, iq[0] - iu0] and (region[iq[1] - iv0, iq[0] - iu0] or not fg[
                iq[1] - iv0, iq[0] - iu0])
            if ok and step > 0 and occlusion is not None:
                ok = bool(occlusion[iq[1], iq[0]] > dist - 0.3)
            d = cam.rays(end[None])[1].reshape(3) if ok else np.full(3, np.nan)
            dirs.append(d if np.isfinite(d).all() else np.full(3, np.nan))
        if np.isfinite(np.concatenate(dirs)).any():
            out.append(ViewRay(int(ids[k]), *(float(v) for v in cam.centre), *(float(v) for v in np.concatenate(dirs))))
    return out


def camera_rays(cameras: Mapping[str, Camera], tracker: Any, cams: Sequence[str], tracks: Sequence[Any],
                ids: set[int], occlusion: Mapping[str, np.ndarray]) -> dict[str, tuple[ViewRay, ...]]:
    """Per camera of ``cams``, the :func:`view_rays` of the people ``ids`` among ``tracks`` (a
    worker's tracker's tracks: everybody it holds, whose image boxes tell who covers whom) in the
    foreground its ``tracker`` read last (``tracker.overlay(camera).mask``)."""
    bodies = np.array([[tr.x, tr.y, tr.height, tr.width] for tr in tracks], float).reshape(-1, 4)
    held = [tr.id for tr in tracks]
    out = {}
    for c in cams:
        mask = getattr(tracker.overlay(c), "mask", None) if hasattr(tracker, "overlay") else None
        out[c] = tuple(r for r in view_rays(cameras[c], mask, bodies, held, occlusion.get(c)) if r.id in ids)
    return out


#: ``map.head_rays``: the map's height of a person is the median of their last this many heights
#: from head rays (:func:`ray_height`), once three are in (:func:`map_height`).
RAY_HEIGHTS = 15


def map_height(heights: Sequence[float], previous: float, deadband_m: float = 0.0) -> float:
    """The map's height (m) of a person from their last ray heights ``heights`` (m, at least
    three): their median, or ``previous`` (the map's height so far, m) while the median is within
    ``deadband_m`` of it (every change, the first from the workers' height included, moves the
    depth each one-camera worker reads from the head: ~0.5 m per 0.1 m at 7 m from a 3 m camera).

    >>> map_height([1.70, 1.74, 1.75], 1.73, 0.03), map_height([1.70, 1.74, 1.75], 1.70, 0.03)
    (1.73, 1.74)
    """
    h = float(np.median(heights))
    return previous if math.isfinite(previous) and abs(h - previous) <= deadband_m and deadband_m > 0 else h


#: The top of a silhouette is a ray tangent to the head (a sphere of about this radius, m), not
#: through the crown: from a camera above, it passes the far side of the head.
HEAD_RADIUS_M = 0.1
#: The bottom of a silhouette is the near edge of the feet: this far (m) from the body's axis
#: towards the camera.
FEET_REACH_M = 0.15
#: The angular error (rad) of a silhouette's end: ~1.7 px at 277 px focal length (two-rooms).
SIGMA_RAD = 0.006


def _targets(r: ViewRay, near: np.ndarray):
    """The rays of ``r`` that are given, each as (origin (3,), direction (3,), on the floor, offset
    (3,) of the point the ray touches from ``(x, y, height)`` resp. ``(x, y, 0)``)."""
    o = np.array([r.ox, r.oy, r.oz])
    towards = np.append(near[:2] - o[:2], 0.0)
    towards /= max(float(np.linalg.norm(towards)), 1e-9)
    for d, floor in ((np.array([r.hx, r.hy, r.hz]), False), (np.array([r.fx, r.fy, r.fz]), True)):
        if not np.isfinite(d).all():
            continue
        if floor:
            yield o, d, True, -FEET_REACH_M * towards
        else:
            below = -np.array([0.0, 0.0, 1.0]) + d[2] * d            # down, across the ray
            n = below / max(float(np.linalg.norm(below)), 1e-9)
            yield o, d, False, -HEAD_RADIUS_M * (np.array([0.0, 0.0, 1.0]) + n)


def triangulate(rays: Sequence[ViewRay], near: np.ndarray, sigma_rad: float = SIGMA_RAD
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """The place and height ``(x, y, height)`` (m) that fit ``rays`` best, its covariance (3, 3)
    m² and how far (m) each given ray passes from where it should, in order (head rays first per
    :class:`ViewRay`).

    Each head ray is a tangent to the head (:data:`HEAD_RADIUS_M`, its centre that far below
    ``height``), each feet ray goes through the near edge of the feet (:data:`FEET_REACH_M`
    towards its camera from ``(x, y, 0)``); least squares, each ray weighed by
    ``1 / (sigma_rad · range)²`` (``range`` from its origin to ``near`` (3,), the person's
    current place and height). Without head rays the height is ``near``'s (variance 0). None when
    the rays do not fix the point (one head ray alone, parallel rays).
    """
    near = np.asarray(near, float)
    m, b, heads, rows = np.zeros((3, 3)), np.zeros(3), 0, []
    for r in rays:
        for o, d, floor, off in _targets(r, near):
            s = np.diag([1.0, 1.0, 0.0]) if floor else np.eye(3)
            p = np.eye(3) - np.outer(d, d)
            w = 1.0 / (sigma_rad * max(float(np.linalg.norm(s @ near + off - o)), 0.5)) ** 2
            m += w * s.T @ p @ s
            b += w * s.T @ p @ (o - off)
            heads += not floor
            rows.append((o, d, s, off))
    n = 3 if heads else 2
    sub = m[:n, :n]
    if not rows or not np.isfinite(sub).all() or np.linalg.det(sub) <= 0 or np.linalg.cond(sub) > 1e8:
        return None
    cov = np.zeros((3, 3))
    cov[:n, :n] = np.linalg.inv(sub)
    point = near.copy()
    point[:n] = cov[:n, :n] @ b[:n]
    gaps = []
    for o, d, s, off in rows:
        v = s @ point + off - o
        gaps.append(float(np.linalg.norm(v - (v @ d) * d)))
    return point, cov, np.array(gaps)


def ray_height(rays: Sequence[ViewRay], near: np.ndarray, max_shift_m: float = 0.5,
               height_range_m: tuple[float, float] = (1.2, 2.2)) -> float | None:
    """A person's height (m) from the head rays of two cameras or more (with whatever feet rays
    are given), or None when they do not fix it or do not agree: some ray passes farther than
    three of its σ (plus 5 cm) from the fit, the fit is more than ``max_shift_m`` from ``near``
    (3,: the estimates' place and height) or its height is implausible or unsure (σ ≥ 5 cm).
    Then some view's top of the head is another person's, or the views are too nearly alike.
    Rays of a camera that sees the person from above (floor distance below its height less half
    the person's) are left out."""
    near = np.asarray(near, float)
    # From above (floor distance below the camera's height less half the person's), the top of
    # the silhouette is the far side of the head and shoulders: the tracker's rule (height.py).
    rays = [r for r in rays if math.hypot(near[0] - r.ox, near[1] - r.oy) >= r.oz - 0.5 * near[2]]
    if len({(r.ox, r.oy, r.oz) for r in rays if math.isfinite(r.hx)}) < 2:
        return None
    found = triangulate(rays, near)
    if found is None:
        return None
    point, cov, gaps = found
    ranges = np.array([np.linalg.norm(s @ point + off - o) for r in rays for o, _, floor, off in _targets(r, near)
                       for s in [np.diag([1.0, 1.0, 0.0]) if floor else np.eye(3)]])
    lo, hi = height_range_m
    if (gaps > 3 * SIGMA_RAD * ranges + 0.05).any() or np.hypot(*(point[:2] - near[:2])) > max_shift_m:
        return None
    return float(point[2]) if lo <= point[2] <= hi and np.sqrt(cov[2, 2]) < 0.05 else None


__all__ = ["FEET_REACH_M", "HEAD_RADIUS_M", "MIN_PIXELS", "RAY_HEIGHTS", "SEARCH_MARGIN", "SIGMA_RAD", "ViewRay",
           "camera_rays", "map_height", "ray_height", "triangulate", "view_rays"]
