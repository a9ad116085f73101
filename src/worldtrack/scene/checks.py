"""Checks of a scene beyond field types: limits, polygon shapes, and what each camera can see.

:func:`scene_problems` returns the errors (a scene that cannot work) and :func:`scene_warnings`
the odd but valid things worth a line (a camera that sees none of the walkable floor). Both are
bounded in time and memory whatever the input: every count and coordinate has a limit, checked
before any grid or pairwise test is built.

>>> polygon_problem([[0, 0], [2, 2], [2, 0], [0, 2]])     # a bow tie
'edges 1 and 3 cross (expected a simple polygon)'
>>> polygon_problem([[0, 0], [2, 0], [2, 2], [0, 2]]) is None
True
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Sequence

import numpy as np
from numpy.typing import ArrayLike

if TYPE_CHECKING:
    from worldtrack.geometry.camera import Camera
    from worldtrack.scene.floor import WalkableArea

#: Limits of a scene file: its size (bytes; a 1000-vertex floor takes 20 kB), counts, image sizes
#: (pixels) and coordinates (metres).
MAX_FILE_BYTES = 100_000
MAX_CAMERAS = 64
MAX_POLYGONS = 100
MAX_VERTICES = 1000            # per polygon ring
MAX_OBSTACLES = 500
MAX_ENTRY_REGIONS = 100
MAX_IMAGE_SIDE = 20_000        # pixels
MAX_COORDINATE_M = 10_000.0    # any world coordinate
MAX_FLOOR_EXTENT_M = 1_000.0   # the floor's bounding box, each side
#: Characters a camera id may use, so that ``--video CAM=PATH`` can name it.
CAMERA_ID_CHARACTERS = "letters, digits, '_', '-' and '.'"


def camera_id_problem(camera_id: str) -> str | None:
    """Why ``camera_id`` cannot be named on the command line (``--video CAM=PATH``), or None.

    >>> camera_id_problem("a=b")
    "expected letters, digits, '_', '-' and '.' (the id is written --video ID=PATH), got 'a=b'"
    """
    import re

    if re.fullmatch(r"[A-Za-z0-9_.\-]{1,64}", camera_id):
        return None
    from worldtrack.io.safe_yaml import short
    return f"expected {CAMERA_ID_CHARACTERS} (the id is written --video ID=PATH), got {short(camera_id)}"


def polygon_problem(ring: ArrayLike) -> str | None:
    """Why a floor polygon ring (M, 2) is not a simple polygon (edges crossing), or None.

    Tests every pair of non-adjacent edges (vectorised; M ≤ :data:`MAX_VERTICES`).
    """
    a = np.asarray(ring, dtype=float)
    m = len(a)
    if m > MAX_VERTICES:
        return f"expected at most {MAX_VERTICES} vertices, got {m}"
    p, q = a, np.roll(a, -1, axis=0)
    i, j = np.triu_indices(m, k=2)
    keep = ~((i == 0) & (j == m - 1))                         # the closing edge touches edge 0
    i, j = i[keep], j[keep]
    if i.size == 0:
        return None
    hit = _segments_cross(p[i], q[i], p[j], q[j])
    if hit.any():
        k = int(np.flatnonzero(hit)[0])
        return f"edges {i[k] + 1} and {j[k] + 1} cross (expected a simple polygon)"
    return None


def _segments_cross(p1: np.ndarray, q1: np.ndarray, p2: np.ndarray, q2: np.ndarray) -> np.ndarray:
    """(K,) bool: segments p1-q1 and p2-q2 intersect (touching counts; collinear overlap counts)."""
    def orient(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
        v = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
        scale = np.maximum(1.0, np.abs(b - a).max(axis=1) * np.abs(c - a).max(axis=1))
        return np.where(np.abs(v) <= 1e-12 * scale, 0.0, np.sign(v))

    def on_segment(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
        return ((np.minimum(a[:, 0], b[:, 0]) <= c[:, 0]) & (c[:, 0] <= np.maximum(a[:, 0], b[:, 0]))
                & (np.minimum(a[:, 1], b[:, 1]) <= c[:, 1]) & (c[:, 1] <= np.maximum(a[:, 1], b[:, 1])))

    o1, o2 = orient(p1, q1, p2), orient(p1, q1, q2)
    o3, o4 = orient(p2, q2, p1), orient(p2, q2, q1)
    proper = (o1 * o2 < 0) & (o3 * o4 < 0)
    touch = (((o1 == 0) & on_segment(p1, q1, p2)) | ((o2 == 0) & on_segment(p1, q1, q2))
             | ((o3 == 0) & on_segment(p2, q2, p1)) | ((o4 == 0) & on_segment(p2, q2, q1)))
    return proper | touch


def hole_problem(outer: ArrayLike, hole: ArrayLike) -> str | None:
    """Why ``hole`` is not a hole of ``outer`` (not inside it, or crossing its edges), or None."""
    from worldtrack.scene.floor import points_in_polygon

    o, h = np.asarray(outer, dtype=float), np.asarray(hole, dtype=float)
    if not points_in_polygon(h, o).all():
        return "expected a hole inside the outer polygon, but some of its vertices lie outside"
    oi = np.arange(len(o))
    hi = np.arange(len(h))
    i, j = (g.ravel() for g in np.meshgrid(oi, hi, indexing="ij"))
    if _segments_cross(o[i], np.roll(o, -1, axis=0)[i], h[j], np.roll(h, -1, axis=0)[j]).any():
        return "expected a hole inside the outer polygon, but its edges cross the outer ones"
    return None


def camera_problem(camera: "Camera") -> str | None:
    """Why ``camera`` cannot see the floor at all — its image holds no point of the plane Z = 0 in
    front of it (it looks at the sky or along the horizon) — or None."""
    uv = _image_samples(camera)
    floor = camera.backproject(uv, 0.0)
    if np.isfinite(floor).all(axis=-1).any():
        return None
    return ("looks at the sky: no pixel of its image sees the floor plane Z = 0 (check the sign of its "
            "rotation, look_at or t)")


def _image_samples(camera: "Camera", n: int = 24) -> np.ndarray:
    """(n², 2) pixels spread over the image, borders included."""
    u = np.linspace(0, camera.width - 1, n)
    v = np.linspace(0, camera.height - 1, n)
    return np.stack(np.meshgrid(u, v), axis=-1).reshape(-1, 2)


def sees_walkable_floor(camera: "Camera", walkable: "WalkableArea", max_points: int = 40_000) -> bool:
    """Whether some walkable floor point (on a grid of at most ``max_points``) is in the image."""
    x0, x1, y0, y1 = walkable.bounds
    step = max(np.sqrt((x1 - x0) * (y1 - y0) / max_points), 1e-3)
    xs = np.arange(x0 + step / 2, x1, step)
    ys = np.arange(y0 + step / 2, y1, step)
    gx, gy = np.meshgrid(xs, ys)
    xy = np.column_stack([gx.ravel(), gy.ravel()])
    xy = xy[walkable.on_floor(xy)]
    if len(xy) == 0:
        return False
    uv, depth = camera.project(np.column_stack([xy, np.zeros(len(xy))]), return_depth=True)
    return bool((camera.in_image(uv) & (depth > 0)).any())


def scene_warnings(cameras: Sequence["Camera"], walkable: "WalkableArea") -> list[str]:
    """Odd but valid: cameras that see none of the walkable floor."""
    return [f"camera {cam.id!r} sees none of the walkable floor (check its pose and the floor polygon)"
            for cam in cameras if not sees_walkable_floor(cam, walkable)]


def floor_extent_problem(walkable: "WalkableArea") -> str | None:
    """Why the floor is too large to raster (wider than :data:`MAX_FLOOR_EXTENT_M`), or None."""
    x0, x1, y0, y1 = walkable.bounds
    if max(x1 - x0, y1 - y0) > MAX_FLOOR_EXTENT_M:
        return (f"expected a floor at most {MAX_FLOOR_EXTENT_M:g} m across, got {x1 - x0:.4g} x {y1 - y0:.4g} m "
                "(coordinates are metres: were they given in millimetres?)")
    return None


__all__ = ["CAMERA_ID_CHARACTERS", "MAX_CAMERAS", "MAX_FILE_BYTES", "MAX_COORDINATE_M", "MAX_ENTRY_REGIONS", "MAX_FLOOR_EXTENT_M",
           "MAX_IMAGE_SIDE", "MAX_OBSTACLES", "MAX_POLYGONS", "MAX_VERTICES", "camera_id_problem", "camera_problem",
           "floor_extent_problem", "hole_problem", "polygon_problem", "scene_warnings", "sees_walkable_floor"]
