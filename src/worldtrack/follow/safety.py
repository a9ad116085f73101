"""The robot's safety layer from the depth image itself (worldtrack; seed 001 has none).

The person detector needs a large enough share of a person in view (plan-view area, height);
somebody at the edge of the image, half out of view, may not be reported, and a robot that only
avoids what the detector reports drives into them. A real robot's bumper-free safety layer reads
the range sensor directly. Here:

* :func:`near_points` — floor positions (m) of every measured point nearer than ``max_range`` at a
  height a body or an obstacle can have (``heights``), thinned to one per ``cell``;
* :func:`unexplained` — those not within ``radius`` of a person the tracker knows, i.e. what the
  planner must treat as an unknown obstacle;
* :func:`free_path` — how far (m) the robot can drive along a planned path before its body
  (``radius``) would touch any of the points: the speed is then limited so that it stops short.

>>> import numpy as np
>>> from worldtrack.geometry.camera import Camera
>>> cam = Camera.look_at("robot", 160, 120, position=(0, 0, 1.1), target=(1, 0, 1.1), hfov_deg=66)
>>> depth = np.zeros((120, 160), np.float32); depth[30:90, 70:90] = 1.0   # something 1 m ahead
>>> pts = near_points(depth, cam)
>>> bool(np.allclose(pts[:, 0], 1.0, atol=0.03)), bool(np.abs(pts[:, 1]).max() < 0.2)
(True, True)
>>> path = np.column_stack([np.linspace(0, 1.5, 16), np.zeros(16)])      # straight ahead
>>> bool(0.6 < free_path(path, pts, radius=0.35) < 0.7)                # touches at about 1 − 0.35 m
True
"""

from __future__ import annotations

import cv2
import numpy as np

from worldtrack.follow.planview import auto_stride, back_project
from worldtrack.geometry.camera import Camera


def near_points(depth: np.ndarray | None, camera: Camera, max_range: float = 3.0, heights=(0.35, 2.0),
                cell: float = 0.05, stride: int = 0, min_support: int = 8) -> np.ndarray:
    """(M, 2) floor positions (m) of the depth image's points within ``max_range`` m of the camera and
    ``heights`` (m) above the floor, one per ``cell`` × ``cell`` m floor cell whose 3 × 3 cell
    neighbourhood holds at least ``min_support`` points (a stereo mismatch is a lone point; a body,
    even at the edge of the image, is many); ``stride`` : pixel step (0: about 160 columns, as the
    detector reads, so the support counts mean the same at any resolution); empty without depth."""
    if depth is None or depth.size == 0:
        return np.zeros((0, 2))
    pts = back_project(depth, camera, stride or auto_stride(depth.shape[1]), max_range)
    z = pts.xyz[:, 2]
    xy = pts.xyz[(z >= heights[0]) & (z <= heights[1]), :2]
    if len(xy) == 0:
        return np.zeros((0, 2))
    ij = np.floor(xy / cell).astype(np.int64)
    low = ij.min(axis=0) - 1
    shape = tuple(ij.max(axis=0) - low + 2)
    counts = np.zeros(shape, np.float32)
    np.add.at(counts, (ij[:, 0] - low[0], ij[:, 1] - low[1]), 1.0)
    support = cv2.boxFilter(counts, -1, (3, 3), normalize=False, borderType=cv2.BORDER_CONSTANT)
    keep = np.argwhere((counts > 0) & (support >= min_support))
    return (keep + low + 0.5) * cell


def unexplained(points: np.ndarray, people_xy: np.ndarray, radius: float = 0.45) -> np.ndarray:
    """The ``points`` (M, 2) farther than ``radius`` m from every person (K, 2) the tracker reports."""
    people_xy = np.asarray(people_xy, float).reshape(-1, 2)
    if len(points) == 0 or len(people_xy) == 0:
        return points
    d = np.hypot(points[:, None, 0] - people_xy[None, :, 0], points[:, None, 1] - people_xy[None, :, 1])
    return points[d.min(axis=1) > radius]


def free_path(path: np.ndarray, points: np.ndarray, radius: float) -> float:
    """Length (m) of the polyline ``path`` (S, 2) — the robot's centre — driven before the robot's
    body (``radius`` m) touches one of ``points`` (M, 2), interpolated within the segment; inf when it
    touches none, 0 when it touches one where it stands."""
    seg = np.hypot(*np.diff(path, axis=0).T)
    length = np.concatenate([[0.0], np.cumsum(seg)])
    if len(points) == 0:
        return np.inf
    d = np.hypot(path[:, None, 0] - points[None, :, 0], path[:, None, 1] - points[None, :, 1]).min(axis=1)
    hit = np.flatnonzero(d < radius)
    if len(hit) == 0:
        return np.inf
    k = int(hit[0])
    if k == 0:
        return 0.0
    # Between samples k − 1 (clear) and k (touching): linear in the distance.
    f = (d[k - 1] - radius) / max(d[k - 1] - d[k], 1e-9)
    return float(length[k - 1] + f * seg[k - 1])
