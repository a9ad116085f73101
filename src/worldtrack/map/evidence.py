"""What a worker knows about a person from its cameras: which of their body points its cameras
show (inside the image, not behind an obstacle of the scene nor behind another person), how finely
they resolve the floor there, and what its tracker measured (support, covariance).

These are the weights of :mod:`worldtrack.map.fusion`: the view in which a person stands in front,
feet visible, tells their depth; the one that sees them behind somebody else, or through a door,
counts less along its line of sight.

>>> from worldtrack.geometry.camera import Camera
>>> cam = Camera.look_at("c", 320, 240, [0.0, 0.0, 3.0], [4.0, 0.0, 0.0], hfov_deg=60)
>>> front = people_boxes(cam, np.array([[3.0, 0.0, 1.7, 0.45]]))          # somebody at 3 m
>>> free = floor_information([cam], np.array([6.0, 0.0]), 1.7)
>>> behind = floor_information([cam], np.array([6.0, 0.0]), 1.7, blockers=[front])
>>> bool(behind[0] < 0.8 * free[0])        # along the line of sight: feet hidden, depth unsure
True
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from worldtrack.geometry.camera import Camera
from worldtrack.trackers.base import Person, Track, Tracker

#: The lead of a person is a worker whose cameras show at least this share of their body, if any
#: does (a tracker fitting a head at the image's edge is no lead, however near the camera).
LEAD_SHARE = 0.6


def people_boxes(cam: Camera, people: np.ndarray) -> np.ndarray:
    """The image boxes of ``people`` (m, 4: x, y, height, width in metres) in ``cam``, as
    (m, 5) ``u0, v0, u1, v1, floor distance`` (pixels, m): an upright box from feet to head,
    as wide as the person across the camera's line of sight. People behind the camera get an
    empty box."""
    people = np.asarray(people, float).reshape(-1, 4)
    if not len(people):
        return np.zeros((0, 5))
    along, dist = cam.floor_rays(people[:, :2])
    across = np.column_stack([-along[:, 1], along[:, 0]]) * people[:, 3:4] / 2
    corners = np.concatenate([np.column_stack([people[:, :2] + s * across, np.full(len(people), z * 1.0) * zs])
                              for s in (-1, 1) for z, zs in ((0.0, 0.0), (1.0, people[:, 2]))])
    uv, depth = cam.project(corners, return_depth=True)
    uv, depth = uv.reshape(4, -1, 2), depth.reshape(4, -1)
    box = np.column_stack([uv[..., 0].min(0), uv[..., 1].min(0), uv[..., 0].max(0), uv[..., 1].max(0), dist])
    box[~((depth > 0).all(0) & np.isfinite(box).all(1))] = [0, 0, -1, -1, np.inf]
    return box


def _body_points(cam: Camera, xy: np.ndarray, height: float, occlusion: np.ndarray | None,
                 step_m: float, blockers: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Five points on a person's axis (feet to head) and four neighbours of each a step away on
    the floor, in ``cam``'s image: (5, 5, 2) pixels, and which of the five show (inside the image,
    not behind an obstacle, nor inside the box of a person of ``blockers`` (:func:`people_boxes`)
    nearer to the camera), (5,) bool."""
    offsets = np.array([[0.0, 0.0], [step_m, 0.0], [-step_m, 0.0], [0.0, step_m], [0.0, -step_m]])
    heights = np.linspace(0.0, height, 5)
    pts = np.concatenate([np.column_stack([xy[None, :] + offsets, np.full(5, z)]) for z in heights])
    uv = cam.project(pts).reshape(len(heights), 5, 2)
    seen = cam.in_image(uv[:, 0]) & np.isfinite(uv).all(axis=(1, 2))
    if (occlusion is not None or blockers is not None) and seen.any():
        mine = float(cam.floor_distance(np.append(xy, 0.0)[None, :])[0])
        if occlusion is not None:
            px = np.clip(np.nan_to_num(np.round(uv[:, 0])).astype(int), 0, [cam.width - 1, cam.height - 1])
            seen &= occlusion[px[:, 1], px[:, 0]] > mine - 0.3
        if blockers is not None and len(blockers):
            b = blockers[blockers[:, 4] < mine - 0.3]
            u, v = uv[:, 0, 0][:, None], uv[:, 0, 1][:, None]
            seen &= ~((u >= b[:, 0]) & (u <= b[:, 2]) & (v >= b[:, 1]) & (v <= b[:, 3])).any(axis=1)
    return uv, seen


def visible_share(cameras: Sequence[Camera], xy: np.ndarray, height: float,
                  occlusion: Sequence[np.ndarray | None] | None = None,
                  blockers: Sequence[np.ndarray | None] | None = None) -> float:
    """The largest share, over ``cameras``, of a person's five axis points (feet to head) that the
    camera shows: 1 in full view, 0.2 when one camera sees only their head through a door.
    ``occlusion`` and ``blockers``: per camera, as in :func:`floor_information`."""
    shares = [_body_points(cam, xy, height, occlusion[k] if occlusion else None, 0.05,
                           blockers[k] if blockers else None)[1].mean()
              for k, cam in enumerate(cameras)]
    return float(max(shares, default=0.0))


def in_views(cameras: Sequence[Camera], xy: np.ndarray, height: float, margin_m: float = 0.0) -> list[bool]:
    """Per camera: does a person ``height`` m tall at floor point ``xy`` show in its image (feet or head
    inside, the paper's rule), or come within ``margin_m`` metres of doing so."""
    offsets = np.array([[0, 0], [1, 0], [-1, 0], [0, 1], [0, -1]], float) * margin_m
    pts = xy[None, :] + (offsets if margin_m > 0 else offsets[:1])
    points = np.concatenate([np.column_stack([pts, np.full(len(pts), z)]) for z in (0.0, height)])
    return [bool(cam.in_image(cam.project(points)).any()) for cam in cameras]


def floor_information(cameras: Sequence[Camera], xy: np.ndarray, height: float, sigma_px: float = 1.0,
                      step_m: float = 0.05, occlusion: Sequence[np.ndarray | None] | None = None,
                      blockers: Sequence[np.ndarray | None] | None = None) -> tuple[float, float, float]:
    """How finely ``cameras`` resolve a person standing at floor point ``xy`` (metres): the
    information matrix ``Σ Jᵀ J / σ²`` (1/m², as ``ixx, ixy, iyy``) of five points on the person's
    axis (feet to head), ``J`` the pixels a point moves per metre on the floor, ``σ = sigma_px``.
    Points outside a camera's image, or hidden there by a structure (``occlusion``: per camera the
    scene's floor-distance map of obstacles, (H, W) metres) or behind another person
    (``blockers``: per camera the others' :func:`people_boxes`) add nothing; so a person seen only
    through a door, or behind somebody, counts for less. No visible point gives ``(nan, nan, nan)``.

    >>> from worldtrack.geometry.camera import Camera
    >>> cam = Camera.look_at("c", 320, 240, [0.0, 0.0, 3.0], [4.0, 0.0, 0.0], hfov_deg=60)
    >>> near, far = (floor_information([cam], np.array([x, 0.0]), 1.7) for x in (2.0, 6.0))
    >>> near[0] > 4 * far[0]                      # depth resolves worse far away
    True
    """
    info = np.zeros((2, 2))
    for k, cam in enumerate(cameras):
        uv, seen = _body_points(cam, xy, height, occlusion[k] if occlusion is not None else None, step_m,
                                blockers[k] if blockers is not None else None)
        for i in np.flatnonzero(seen):
            J = np.column_stack([(uv[i, 1] - uv[i, 2]) / (2 * step_m), (uv[i, 3] - uv[i, 4]) / (2 * step_m)])
            info += J.T @ J / sigma_px ** 2
    if not info.any():
        return float("nan"), float("nan"), float("nan")
    return float(info[0, 0]), float(info[0, 1]), float(info[1, 1])



def with_ray_error(info: np.ndarray, sigma_m: float) -> np.ndarray:
    """The information (2, 2) 1/m² of an estimate whose pixel information is ``info`` (1/m²) once a
    model error of ``sigma_m`` metres along the worker's line of sight is added: the covariance
    ``info⁻¹ + sigma_m² d dᵀ``, ``d`` the direction ``info`` resolves worst (a camera's line of sight
    on the floor), inverted again. A one-camera tracker's depth errs by tenths of a metre when it
    slides along the ray (a person behind another, the feet cut), far beyond what a pixel's error
    explains; two workers whose cameras look along one axis then count about alike along it, and
    two at an angle still triangulate (each fixes the other's depth across its own ray).

    >>> along = with_ray_error(np.diag([400.0, 4000.0]), 0.3)   # x: the line of sight
    >>> round(float(1 / along[0, 0]), 4), round(float(1 / along[1, 1]), 6)   # 0.0025 + 0.09 m² along; across as before
    (0.0925, 0.00025)
    """
    if sigma_m <= 0:
        return info
    values, vectors = np.linalg.eigh(info)
    d = vectors[:, 0]                                   # the smallest eigenvalue: along the ray
    cov = np.linalg.inv(info) + sigma_m ** 2 * np.outer(d, d)
    return np.linalg.inv(cov)

#: A place looks empty when less than this share of the pixels of a person's box there that no
#: other person explains is foreground (a person standing there fills ~half of their box).
EMPTY_SHARE = 0.1


def looks_empty(cam: Camera, mask: np.ndarray | None, xy: np.ndarray, height: float, width: float,
                occlusion: np.ndarray | None = None, blockers: np.ndarray | None = None,
                min_share: float = 0.6) -> bool:
    """Negative evidence: does ``cam`` show floor point ``xy`` (m) clearly, with nobody there?

    Yes when at least ``min_share`` of a person's axis points (``height``, ``width`` m) there
    show in the image (not behind an obstacle of ``occlusion``, (H, W) floor distance, nor behind
    a person of ``blockers``, :func:`people_boxes`), at least 30 % of their image box is neither
    cut by the image border, nor behind an obstacle, nor covered by a box of ``blockers`` (their
    foreground is explained), and less than :data:`EMPTY_SHARE` of that part is foreground in
    ``mask`` (H, W, nonzero = foreground). No mask: False (nothing to tell).

    >>> from worldtrack.geometry.camera import Camera
    >>> cam = Camera.look_at("c", 320, 240, [0.0, 0.0, 3.0], [4.0, 0.0, 0.0], hfov_deg=60)
    >>> empty = np.zeros((240, 320), np.uint8)
    >>> looks_empty(cam, empty, np.array([4.0, 0.0]), 1.7, 0.45)
    True
    >>> u0, v0, u1, v1, _ = people_boxes(cam, np.array([[4.0, 0.0, 1.7, 0.45]]))[0].astype(int)
    >>> empty[v0:v1, u0:u1] = 1                      # somebody there
    >>> looks_empty(cam, empty, np.array([4.0, 0.0]), 1.7, 0.45)
    False
    """
    if mask is None or mask.shape[:2] != (cam.height, cam.width):
        return False
    shown, open_share, foreground = emptiness(cam, mask, xy, height, width, occlusion, blockers)
    return shown >= min_share and open_share >= 0.3 and foreground < EMPTY_SHARE


def emptiness(cam: Camera, mask: np.ndarray, xy: np.ndarray, height: float, width: float,
              occlusion: np.ndarray | None = None, blockers: np.ndarray | None = None) -> tuple[float, float, float]:
    """What :func:`looks_empty` decides by: the share of the axis points that show, the share of
    the box left open (inside the image, not behind an obstacle, not covered by ``blockers``) and
    the foreground share of that open part (NaN when nothing is open)."""
    shown = visible_share([cam], xy, height, [occlusion], [blockers])
    u0, v0, u1, v1, dist = people_boxes(cam, np.array([[xy[0], xy[1], height, width]]))[0]
    iu0, iv0 = max(0, int(math.floor(u0))), max(0, int(math.floor(v0)))
    iu1, iv1 = min(cam.width, int(math.ceil(u1))), min(cam.height, int(math.ceil(v1)))
    if not (u1 > u0 and v1 > v0 and iu1 > iu0 and iv1 > iv0):
        return shown, 0.0, float("nan")
    open_ = np.ones((iv1 - iv0, iu1 - iu0), bool)
    if occlusion is not None:
        open_ &= occlusion[iv0:iv1, iu0:iu1] > dist - 0.3
    for b in (blockers if blockers is not None else ()):
        bu0, bv0 = max(iu0, int(math.floor(b[0]))), max(iv0, int(math.floor(b[1])))
        bu1, bv1 = min(iu1, int(math.ceil(b[2]))), min(iv1, int(math.ceil(b[3])))
        if bu1 > bu0 and bv1 > bv0:
            open_[bv0 - iv0:bv1 - iv0, bu0 - iu0:bu1 - iu0] = False
    if not open_.any():
        return shown, 0.0, float("nan")
    return shown, float(open_.sum() / ((u1 - u0) * (v1 - v0))), float((mask[iv0:iv1, iu0:iu1] != 0)[open_].mean())


#: The covariance fields of an estimate whose tracker measured none.
NO_COVARIANCE = (float("nan"),) * 3


def tracker_covariance(tracker: Tracker, person: Person | None, t: float) -> np.ndarray | None:
    """The (2, 2) m² position covariance ``tracker`` measured for ``person`` at ``t`` from its
    cameras' images, or None when it measured none then (not shown, not confirmed, or a tracker
    that does not measure one). The ellipsoid tracker's comes from the curvature of its score
    (:mod:`worldtrack.trackers.ellipsoid.uncertainty`): larger along the line of sight, and larger
    where others hide the person."""
    parts = getattr(getattr(tracker, "uncertainty", None), "components", None)
    found = parts.get(person) if parts is not None and person is not None else None
    if found is None or found.t != t:
        return None
    from worldtrack.trackers.ellipsoid.uncertainty import position_covariance
    return position_covariance(*found[:4])


def support_of(person: Person | None, tr: Track) -> float:
    for v in (getattr(person, "support", float("nan")), (person.extra if person is not None else {}).get("support"),
              tr.extra.get("support")):
        if v is not None and math.isfinite(float(v)):
            return float(v)
    return float("nan")


__all__ = ["EMPTY_SHARE", "LEAD_SHARE", "NO_COVARIANCE", "floor_information", "in_views", "looks_empty", "people_boxes",
           "support_of", "tracker_covariance", "visible_share", "with_ray_error"]
