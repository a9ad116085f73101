"""Plan-view detection (seed 001 §2.3): every measured 3-D point onto the floor, dense clusters = people.

From a depth image (metres along the optical axis, 0 = no measurement) and the camera at that
frame, every ``stride``-th pixel's 3-D point is placed in the world. Points between
``min_point_height`` and ``max_point_height`` add their **visible area** to a floor grid: a pixel at
depth Z covers ``(Z·s/fx)·(Z·s/fy)`` m², so a person counts the same near and far (the paper's
point density, made independent of range). Cells that hold points above ``structure_height`` are
walls or buildings and are cleared; so is everything outside the scene's walkable area.

The smoothed area map's local maxima at least ``peak_separation`` apart are the seeds; every point
within ``person_radius`` of a seed belongs to the nearest one (two people side by side stay two).
A seed is a **candidate** when its points cover at least ``min_area`` m², its highest point is a
person's height and its floor extent is a person's. Its position is the area-weighted mean of its
points, pushed back by ``surface_offset`` along the view ray (the camera sees the near surface).

>>> import numpy as np
>>> from worldtrack.geometry.camera import Camera
>>> from worldtrack.follow.config import FollowConfig
>>> cam = Camera.look_at("c", 320, 240, position=(0, 0, 1.1), target=(1, 0, 1.1), hfov_deg=66)
>>> depth = np.zeros((240, 320), np.float32)
>>> depth[60:230, 150:170] = 3.0          # a 0.4 m wide, 1.7 m high board 3 m in front
>>> cands = detect(depth, cam, FollowConfig())
>>> len(cands), [round(float(v), 1) + 0.0 for v in cands.xy[0]]
(1, [3.1, 0.0])
"""

from __future__ import annotations

from typing import NamedTuple

import cv2
import numpy as np

from worldtrack.follow.config import FollowConfig
from worldtrack.geometry.camera import Camera
from worldtrack.scene.floor import FloorGrid


_DEBUG = False


class Points(NamedTuple):
    """Measured 3-D points of one frame (the strided pixels with a valid depth).

    xyz : (M, 3) world, metres; area : (M,) visible area, m²; pixel : (M,) flat index into the
    strided grid of shape ``grid_shape``; depth : (M,) metres
    """

    xyz: np.ndarray
    area: np.ndarray
    pixel: np.ndarray
    depth: np.ndarray
    grid_shape: tuple[int, int]
    stride: int


class Candidates(NamedTuple):
    """The people found in one frame.

    xy : (N, 2) world floor position, metres; top : (N,) highest point, metres; area : (N,)
    visible area, m²; extent : (N,) floor extent, metres; depth : (N,) median depth, metres;
    labels : (h, w) int32 on the strided grid — 0 nothing, i + 1 a point of candidate i;
    stride : int
    """

    xy: np.ndarray
    top: np.ndarray
    area: np.ndarray
    extent: np.ndarray
    depth: np.ndarray
    labels: np.ndarray
    stride: int

    def __len__(self) -> int:
        return len(self.xy)


def auto_stride(width: int, columns: int = 160) -> int:
    """Pixel step that reads about ``columns`` columns of the depth image (1 for small images)."""
    return max(1, int(round(width / columns)))


def back_project(depth: np.ndarray, camera: Camera, stride: int, max_range: float) -> Points:
    """World points of every ``stride``-th pixel with a depth in (0, ``max_range``].

    The sample of block (i, j) is its pixel ``(j·s + s//2, i·s + s//2)``. Depth is along the
    optical axis of a rectified pinhole camera (no distortion).
    """
    s = int(stride)
    sub = depth[s // 2::s, s // 2::s]
    h, w = sub.shape
    z = sub.ravel().astype(np.float64)
    pixel = np.flatnonzero((z > 0) & (z <= max_range))
    z = z[pixel]
    K = camera.K
    u = (pixel % w) * s + s // 2
    v = (pixel // w) * s + s // 2
    yc = (v - K[1, 2]) / K[1, 1] * z
    xc = ((u - K[0, 2]) - K[0, 1] * (v - K[1, 2]) / K[1, 1]) / K[0, 0] * z
    cam_pts = np.column_stack([xc, yc, z])
    xyz = (cam_pts - camera.t) @ camera.R            # X_w = Rᵀ(X_c − t)
    area = (z * s / K[0, 0]) * (z * s / K[1, 1])
    return Points(xyz, area, pixel, z, (h, w), s)


def _walkable(points: Points, walk: FloorGrid | None, margin: float) -> np.ndarray:
    """Points at least a depth-dependent margin inside the walkable area: ``margin·(Z / 4 m)²``,
    at least 0.05 m and at most twice ``margin`` (stereo depth noise grows as Z²)."""
    if walk is None:
        return np.ones(len(points.area), dtype=bool)
    ij = np.floor((points.xyz[:, :2] - walk.origin) / walk.resolution + 0.5).astype(np.int64)
    ny, nx = walk.values.shape
    inside = (ij[:, 0] >= 0) & (ij[:, 0] < nx) & (ij[:, 1] >= 0) & (ij[:, 1] < ny)
    need = np.clip(margin * (points.depth / 4.0) ** 2, 0.05, 2 * margin)
    ok = np.zeros(len(ij), dtype=bool)
    ok[inside] = walk.values[ij[inside, 1], ij[inside, 0]] >= need[inside]
    return ok


class PlanMaps(NamedTuple):
    """The floor grid of one frame: ``area`` and ``top`` (ny, nx) over cells of ``cell`` metres from ``origin``."""

    area: np.ndarray
    top: np.ndarray
    origin: np.ndarray
    cell: float


def plan_maps(points: Points, keep: np.ndarray, config: FollowConfig) -> tuple[PlanMaps, np.ndarray]:
    """Occupancy (visible area, m²) and height maps of the kept points; (maps, cell index per point, −1 = none)."""
    cfg = config
    xy = points.xyz[:, :2]
    z = points.xyz[:, 2]
    use = keep & (z >= cfg.min_point_height)
    cell_of = np.full(len(z), -1, dtype=np.int64)
    if not use.any():
        return PlanMaps(np.zeros((1, 1), np.float32), np.zeros((1, 1), np.float32), np.zeros(2), cfg.cell), cell_of
    margin = 2 * cfg.person_radius
    origin = xy[use].min(axis=0) - margin
    ij = np.floor((xy - origin) / cfg.cell).astype(np.int64)
    nx, ny = (ij[use].max(axis=0) + int(np.ceil(margin / cfg.cell)) + 1)
    inside = use & (ij[:, 0] >= 0) & (ij[:, 1] >= 0) & (ij[:, 0] < nx) & (ij[:, 1] < ny)
    flat = ij[:, 1] * nx + ij[:, 0]
    tall = inside & (z > cfg.structure_height)
    occ = inside & (z <= cfg.max_point_height)
    area = np.bincount(flat[occ], weights=points.area[occ], minlength=nx * ny)
    top = np.zeros(nx * ny)
    np.maximum.at(top, flat[occ], z[occ])
    structure = np.zeros(nx * ny, np.uint8)
    structure[flat[tall]] = 1
    structure = cv2.dilate(structure.reshape(ny, nx), np.ones((3, 3), np.uint8)).ravel().astype(bool)
    area[structure] = 0.0
    cell_of[occ] = flat[occ]
    cell_of[occ & structure[np.clip(flat, 0, nx * ny - 1)]] = -1
    return PlanMaps(area.reshape(ny, nx).astype(np.float32), top.reshape(ny, nx).astype(np.float32), origin,
                    cfg.cell), cell_of


def find_peaks(maps: PlanMaps, config: FollowConfig) -> np.ndarray:
    """(P, 2) floor positions of the seeds: maxima of the smoothed area map, ``peak_separation`` apart."""
    cfg = config
    sigma = cfg.smooth / cfg.cell
    smooth = cv2.GaussianBlur(maps.area, (0, 0), sigma) if sigma > 0.3 else maps.area
    # Cells under a person's height only (their own top, or a neighbour's: legs beside the torso).
    tall_enough = cv2.dilate(maps.top, np.ones((3, 3), np.uint8)) >= cfg.person_top[0]
    r = max(1, int(round(cfg.peak_separation / cfg.cell)))     # no higher cell within peak_separation
    disk = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1))
    local_max = smooth >= cv2.dilate(smooth, disk)
    # The smoothed density of min_area spread over a person's footprint (π·r²): weaker is noise.
    floor_density = cfg.min_area / (np.pi * cfg.person_radius ** 2) * cfg.cell ** 2 / 4
    jj, ii = np.nonzero(local_max & tall_enough & (smooth > floor_density))
    peaks = maps.origin + (np.column_stack([ii, jj]) + 0.5) * maps.cell
    return suppress_nearby(peaks, smooth[jj, ii], cfg.peak_separation)


def suppress_nearby(peaks: np.ndarray, strength: np.ndarray, separation: float) -> np.ndarray:
    """Keep the strongest of any peaks closer than ``separation`` (ties on a flat plateau: the first).

    >>> suppress_nearby(np.array([[0.0, 0.0], [0.1, 0.0], [1.0, 0.0]]), np.ones(3), 0.4).tolist()
    [[0.0, 0.0], [1.0, 0.0]]
    """
    order = np.argsort(-strength, kind="stable")
    p = peaks[order]
    close = np.hypot(*(p[:, None, :] - p[None, :, :]).transpose(2, 0, 1)) < separation
    keep = np.ones(len(p), dtype=bool)
    for i in range(len(p)):                     # peaks, not pixels: a handful per frame
        if keep[i]:
            keep[i + 1:] &= ~close[i, i + 1:]
    return p[keep]


def assign_points(points: Points, cell_of: np.ndarray, peaks: np.ndarray, radius: float) -> np.ndarray:
    """(M,) index of the nearest seed within ``radius`` of each occupancy point, −1 if none."""
    label = np.full(len(cell_of), -1, dtype=np.int64)
    if len(peaks) == 0:
        return label
    idx = np.flatnonzero(cell_of >= 0)
    d2 = ((points.xyz[idx, None, :2] - peaks[None, :, :]) ** 2).sum(axis=2)
    best = d2.argmin(axis=1)
    near = d2[np.arange(len(idx)), best] <= radius ** 2
    label[idx[near]] = best[near]
    return label


def _cluster_stats(points: Points, label: np.ndarray, n: int):
    """Per-seed area, weighted mean xy, highest point, floor extent and median depth."""
    sel = label >= 0
    lab = label[sel]
    w = points.area[sel]
    x, y, z = points.xyz[sel].T
    area = np.bincount(lab, weights=w, minlength=n)
    safe = np.maximum(area, 1e-12)
    mx = np.bincount(lab, weights=w * x, minlength=n) / safe
    my = np.bincount(lab, weights=w * y, minlength=n) / safe
    cxx = np.bincount(lab, weights=w * x * x, minlength=n) / safe - mx ** 2
    cyy = np.bincount(lab, weights=w * y * y, minlength=n) / safe - my ** 2
    cxy = np.bincount(lab, weights=w * x * y, minlength=n) / safe - mx * my
    lam = (cxx + cyy) / 2 + np.sqrt(np.maximum(((cxx - cyy) / 2) ** 2 + cxy ** 2, 0.0))
    extent = 4.0 * np.sqrt(np.maximum(lam, 0.0))          # ±2σ along the long axis
    top = np.zeros(n)
    np.maximum.at(top, lab, z)
    count = np.bincount(lab, minlength=n)
    depth = np.zeros(n)
    order = np.lexsort((points.depth[sel], lab))
    starts = np.concatenate([[0], np.cumsum(count)[:-1]])
    has = count > 0
    depth[has] = points.depth[sel][order][starts[has] + count[has] // 2]
    return area, np.column_stack([mx, my]), top, extent, depth, count


def detect(depth: np.ndarray, camera: Camera, config: FollowConfig, walkable: FloorGrid | None = None) -> Candidates:
    """The person candidates of one depth image (see the module docstring).

    Parameters
    ----------
    depth : (H, W) float32, metres along the optical axis, 0 where there is no measurement
    camera : Camera at this frame (rectified pinhole; K, R, t)
    config : FollowConfig
    walkable : signed distance to walls (``Scene.distance_field``), optional

    Returns
    -------
    Candidates, ordered by distance from the camera.
    """
    cfg = config
    stride = cfg.stride or auto_stride(depth.shape[1])
    pts = back_project(depth, camera, stride, cfg.max_range)
    keep = _walkable(pts, walkable, cfg.wall_margin)
    maps, cell_of = plan_maps(pts, keep, cfg)
    peaks = find_peaks(maps, cfg)
    label = assign_points(pts, cell_of, peaks, cfg.person_radius)
    n = len(peaks)
    area, xy, top, extent, med_depth, count = _cluster_stats(pts, label, n)
    ok = ((area >= cfg.min_area) & (top >= cfg.person_top[0]) & (top <= cfg.person_top[1])
          & (extent <= cfg.max_extent) & (count >= cfg.min_points))
    if _DEBUG:
        print("clusters", np.round(xy, 2).tolist(), np.round(area, 3), np.round(top, 2), np.round(extent, 2), count)
    cam_xy = camera.centre[:2]
    ray = xy - cam_xy
    ray /= np.maximum(np.linalg.norm(ray, axis=1, keepdims=True), 1e-9)
    xy = xy + cfg.surface_offset * ray
    keep_idx = np.flatnonzero(ok)
    keep_idx = keep_idx[np.argsort(med_depth[keep_idx], kind="stable")]
    new_id = np.full(n + 1, -1, dtype=np.int64)
    new_id[keep_idx] = np.arange(len(keep_idx))
    labels = np.zeros(pts.grid_shape[0] * pts.grid_shape[1], dtype=np.int32)
    mine = label >= 0
    labels[pts.pixel[mine]] = new_id[label[mine]] + 1
    return Candidates(xy[keep_idx], top[keep_idx], area[keep_idx], extent[keep_idx], med_depth[keep_idx],
                      labels.reshape(pts.grid_shape), stride)
