"""The floor plan the page draws: the scene as plain JSON in SVG pixels, and which cameras see whom.

The page's SVG has a ``viewBox`` of ``0 0 width height`` in its own pixels; a floor point
``(x, y)`` in metres is drawn at ``u = (x - x_min)·scale``, ``v = (y_max - y)·scale``
(:class:`PlanTransform`: X to the right, Y up, as on the matplotlib floor plans). The plan
spans the walkable area and every camera, with a margin.

>>> from worldtrack.geometry.camera import Camera
>>> t = PlanTransform(x_min=-1.0, y_max=4.0, scale=50.0, width=600, height=300)
>>> t.to_svg([[0.0, 0.0], [2.0, 1.5]]).tolist()
[[50.0, 200.0], [150.0, 125.0]]
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np
from numpy.typing import ArrayLike

from worldtrack.scene.model import Box, Scene
from worldtrack.viz.floorplan import camera_floor_coverage

#: The plan fits this many SVG pixels (width, height).
PLAN_PX = (1000, 720)
#: Five points on a person's axis, feet to head, as shares of their height.
_AXIS = np.linspace(0.0, 1.0, 5)


@dataclass(frozen=True)
class PlanTransform:
    """Floor metres → SVG pixels: ``u = (x - x_min)·scale``, ``v = (y_max - y)·scale``."""

    x_min: float
    y_max: float
    scale: float
    width: int
    height: int

    @classmethod
    def fit(cls, scene: Scene, margin_px: float = 40.0, box_px: tuple[int, int] = PLAN_PX) -> "PlanTransform":
        """The transform that fits the walkable area and the cameras into ``box_px``, with
        ``margin_px`` around them (room for the cameras' icons and labels)."""
        x0, x1, y0, y1 = scene.walkable.bounds
        xs = [x0, x1] + [float(c.centre[0]) for c in scene.cameras.values()]
        ys = [y0, y1] + [float(c.centre[1]) for c in scene.cameras.values()]
        lo, hi = np.array([min(xs), min(ys)]), np.array([max(xs), max(ys)])
        span = np.maximum(hi - lo, 1e-3)
        scale = float(min((box_px[0] - 2 * margin_px) / span[0], (box_px[1] - 2 * margin_px) / span[1]))
        m = margin_px / scale
        return cls(float(lo[0] - m), float(hi[1] + m), scale, int(np.ceil(span[0] * scale + 2 * margin_px)),
                   int(np.ceil(span[1] * scale + 2 * margin_px)))

    def to_svg(self, xy: ArrayLike) -> np.ndarray:
        """(N, 2) floor points (m) → (N, 2) SVG pixels."""
        p = np.asarray(xy, dtype=float).reshape(-1, 2)
        return np.column_stack([(p[:, 0] - self.x_min) * self.scale, (self.y_max - p[:, 1]) * self.scale])

    def as_json(self) -> dict[str, float]:
        return {"x_min": self.x_min, "y_max": self.y_max, "scale": self.scale, "width": self.width,
                "height": self.height}


def _ring(points: ArrayLike, t: PlanTransform) -> list[list[float]]:
    return np.round(t.to_svg(points), 2).tolist()


def coverage_rings(camera, bounds: tuple[float, float, float, float], t: PlanTransform) -> list[list[list[float]]]:
    """The floor a camera sees (image border and lens), as SVG polygons (outer boundaries).

    The floor grid of :func:`~worldtrack.viz.floorplan.camera_floor_coverage` at about 2 plan
    pixels a cell, traced with OpenCV's ``findContours`` and simplified to a cell (the page clips them to the floor).
    """
    x0, x1, y0, y1 = bounds
    resolution = max(0.02, max(x1 - x0, y1 - y0) / 500.0, 2.0 / t.scale)
    xs, ys, seen = camera_floor_coverage(camera, bounds, resolution=resolution)
    if not seen.any():
        return []
    contours, _ = cv2.findContours(seen.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    rings = []
    for c in contours:
        c = cv2.approxPolyDP(c, 1.0, True).reshape(-1, 2).astype(float)
        if len(c) < 3:
            continue
        rings.append(_ring(np.column_stack([xs[0] + c[:, 0] * resolution, ys[0] + c[:, 1] * resolution]), t))
    return rings


def plan_json(scene: Scene, t: PlanTransform | None = None) -> dict[str, Any]:
    """Everything the page draws of the scene, in SVG pixels (see the module docstring).

    Returns
    -------
    dict with ``name``, ``transform`` (:meth:`PlanTransform.as_json`), ``walkable`` (list of
    ``{outer, holes}``), ``obstacles`` (``{name, kind, ring, top_m}``), ``entries`` (``{name, ring}``),
    ``cameras`` (``{id, at, heading, height_m, coverage}``: ``at`` the centre in SVG pixels,
    ``heading`` the floor direction (radians, SVG: clockwise from +u), ``coverage`` polygons).
    """
    t = PlanTransform.fit(scene) if t is None else t
    walkable = [{"outer": _ring(p.outer, t), "holes": [_ring(h, t) for h in p.holes]}
                for p in scene.walkable.polygons]
    obstacles = [{"name": ob.name, "kind": "box" if isinstance(ob, Box) else "patch", "ring": _ring(ob.footprint, t),
                  "top_m": round(ob.top, 2)} for ob in scene.obstacles]
    entries = [{"name": r.name, "ring": _ring(r.polygon, t)} for r in scene.entry_regions]
    x0, x1, y0, y1 = scene.walkable.bounds
    bounds = (x0 - 0.5, x1 + 0.5, y0 - 0.5, y1 + 0.5)
    cameras = []
    for cam in scene.cameras.values():
        d = cam.floor_direction
        cameras.append({"id": cam.id, "at": _ring(cam.centre[:2], t)[0], "heading": float(np.arctan2(-d[1], d[0])),
                        "height_m": round(float(cam.centre[2]), 2), "coverage": coverage_rings(cam, bounds, t)})
    return {"name": scene.name, "transform": t.as_json(), "walkable": walkable, "obstacles": obstacles,
            "entries": entries, "cameras": cameras}


def cameras_seeing(scene: Scene, xy: ArrayLike, height: ArrayLike, min_share: float = 0.4) -> list[list[str]]:
    """For each person, the cameras that show at least ``min_share`` of their body.

    A person is five points on their axis, feet to head (``height`` metres, (N,) or scalar); a
    point shows in a camera when it falls in the image and no obstacle of the scene hides it
    (:meth:`Scene.occlusion`). Vectorised over people, one projection per camera.

    >>> from worldtrack.geometry.camera import Camera
    >>> from worldtrack.scene.floor import FloorPolygon, WalkableArea
    >>> cam = Camera.look_at("c1", 320, 240, [0.0, 0.0, 3.0], [4.0, 0.0, 0.0], hfov_deg=60)
    >>> room = WalkableArea((FloorPolygon(np.array([[0, -3], [8, -3], [8, 3], [0, 3.0]])),))
    >>> cameras_seeing(Scene("s", {"c1": cam}, room), [[4.0, 0.0], [4.0, 2.9]], 1.7)
    [['c1'], []]
    """
    p, h = _people(scene, xy, height)
    seen_by: list[list[str]] = [[] for _ in range(len(p))]
    if len(p) == 0:
        return seen_by
    for cid in scene.cameras:
        share = axis_points_shown(scene, cid, p, h)[1].mean(axis=0)
        for i in np.flatnonzero(share >= min_share):
            seen_by[i].append(cid)
    return seen_by


def _people(scene: Scene, xy: ArrayLike, height: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    p = np.asarray(xy, dtype=float).reshape(-1, 2)
    h = np.broadcast_to(np.asarray(height, dtype=float), (len(p),))
    return p, np.where(np.isfinite(h), h, scene.people.height)


def axis_points_shown(scene: Scene, camera_id: str, xy: np.ndarray, height: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Five points on each person's axis (feet to head) in one camera: pixels (5, N, 2) and whether
    each shows (5, N) bool: in the image, in front of the camera, not hidden by an obstacle."""
    cam, n = scene.cameras[camera_id], len(xy)
    pts = np.concatenate([np.column_stack([xy, height * z]) for z in _AXIS])    # (5N, 3): point k of person i
    uv = cam.project(pts)
    shows = cam.in_image(uv) & np.isfinite(uv).all(axis=1)
    if scene.obstacles and shows.any():
        feet_m = cam.floor_distance(np.column_stack([xy, np.zeros(n)]))
        shows &= ~scene.occlusion(camera_id).hidden(uv, np.tile(feet_m - 0.3, len(_AXIS)))
    return uv.reshape(len(_AXIS), n, 2), shows.reshape(len(_AXIS), n)


def floor_sigma(scene: Scene, xy: ArrayLike, height: ArrayLike, sigma_px: float = 2.0, step_m: float = 0.05,
                unseen_m: float = 1.0) -> np.ndarray:
    """(N,) metres: how sure the cameras can be of where each person stands — the square root of
    the largest eigenvalue of the inverse of :func:`worldtrack.map.fusion.floor_information`
    (the information of a ``sigma_px`` error of the five axis points the cameras show), vectorised
    over people; ``unseen_m`` where no camera shows any of their points.

    >>> from worldtrack.geometry.camera import Camera
    >>> from worldtrack.scene.floor import FloorPolygon, WalkableArea
    >>> cam = Camera.look_at("c1", 320, 240, [0.0, 0.0, 3.0], [4.0, 0.0, 0.0], hfov_deg=60)
    >>> room = WalkableArea((FloorPolygon(np.array([[0, -3], [9, -3], [9, 3], [0, 3.0]])),))
    >>> near, far, outside = floor_sigma(Scene("s", {"c1": cam}, room), [[3, 0], [8, 0], [4, 2.9]], 1.7)
    >>> bool(far > 2 * near), float(outside)
    (True, 1.0)
    """
    p, h = _people(scene, xy, height)
    n = len(p)
    offsets = np.array([[step_m, 0.0], [-step_m, 0.0], [0.0, step_m], [0.0, -step_m]])
    info = np.zeros((n, 3))                                          # ixx, ixy, iyy
    for cid, cam in scene.cameras.items():
        shows = axis_points_shown(scene, cid, p, h)[1]               # (5, N)
        if not shows.any():
            continue
        pts = np.stack([np.column_stack([p + o, h * z]) for z in _AXIS for o in offsets])   # (5·4, N, 3)
        uv = cam.project(pts.reshape(-1, 3)).reshape(len(_AXIS), 4, n, 2)
        jx = (uv[:, 0] - uv[:, 1]) / (2 * step_m)                       # (5, N, 2): pixels per metre of x
        jy = (uv[:, 2] - uv[:, 3]) / (2 * step_m)
        w = shows & np.isfinite(jx).all(axis=2) & np.isfinite(jy).all(axis=2)
        jx, jy = np.where(w[..., None], jx, 0.0), np.where(w[..., None], jy, 0.0)
        info += np.stack([(jx * jx).sum(axis=(0, 2)), (jx * jy).sum(axis=(0, 2)), (jy * jy).sum(axis=(0, 2))], 1)
    info /= sigma_px ** 2
    det = info[:, 0] * info[:, 2] - info[:, 1] ** 2
    ok = det > 1e-12
    # Largest eigenvalue of the inverse = 1 / smallest eigenvalue of the information matrix.
    tr = info[:, 0] + info[:, 2]
    smallest = tr / 2 - np.sqrt(np.maximum((tr / 2) ** 2 - det, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(ok & (smallest > 0), 1.0 / np.sqrt(np.maximum(smallest, 1e-300)), unseen_m)


__all__ = ["PLAN_PX", "PlanTransform", "axis_points_shown", "cameras_seeing", "coverage_rings", "floor_sigma",
           "plan_json"]
