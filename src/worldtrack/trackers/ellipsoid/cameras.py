"""What the ellipsoid tracker keeps about each camera: its kernel arguments, ring width, pixel tests.

:class:`CameraView` holds what does not change from frame to frame (the camera, its obstacle map
and ideal-pixel grid as :class:`~.args.CameraArgs`, the ring width at its image size, its
foreground model) and draws people's ellipses in it (:meth:`CameraView.forms`).

>>> import numpy as np
>>> from worldtrack.scene import scene_from_dict
>>> scene = scene_from_dict({"cameras": [{"id": "c", "image_size": [320, 240], "position": [0, -4, 2.6],
...                          "look_at": [0, 0, 0.8], "hfov_deg": 60}],
...                          "floor": {"walkable": [{"outer": [[-3, -2], [3, -2], [3, 4], [-3, 4]]}]}})
>>> view = camera_view(scene, "c", None, ring_px_160=5.0, draw=DrawArgs(0.1, 2.0))
>>> view.ring_px                          # 5 px at 160x120, scaled with the image's linear size
10
>>> int(view.visible_pixels(np.array([0.0, 0.0]), 1.65, 0.4)) > 1000
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from worldtrack.foreground.background import Foreground
from worldtrack.geometry.camera import Camera
from worldtrack.trackers.ellipsoid.args import CameraArgs, DrawArgs, Forms, camera_args
from worldtrack.trackers.ellipsoid.forms import ellipse_crop, person_forms


@dataclass
class CameraView:
    """One camera as the ellipsoid tracker uses it (constant from frame to frame).

    Attributes
    ----------
    camera : Camera
    args : CameraArgs — what the compiled kernels read
    ring_px : int — width of the −1 ring at this image size, pixels
    foreground : Foreground or None — the camera's foreground model (None: a camera another
        tracker on the map reads, used only to tell whether it shows a person)
    draw : DrawArgs
    """

    camera: Camera
    args: CameraArgs
    ring_px: int
    foreground: Foreground | None
    draw: DrawArgs
    _down: tuple | None = None
    _smallest: float | None = None

    @property
    def grid(self) -> np.ndarray:
        """(H, W, 2) float32: ideal position of each pixel (a placeholder without distortion)."""
        return self.args.grid

    @property
    def occ(self) -> np.ndarray:
        """(H, W) float32: floor distance of the nearest obstacle at each pixel, m (inf: none)."""
        return self.args.occ

    def forms(self, xy: np.ndarray, heights: np.ndarray, widths: np.ndarray) -> Forms:
        """Ellipses of people at ``xy`` (N, 2) m, sizes (N,) m, and their floor distances."""
        return person_forms(self.args, xy, heights, widths, self.draw)

    def down_direction(self, uv: np.ndarray) -> np.ndarray | None:
        """Image direction of world-down at pixel ``uv`` (from a map built once), or None."""
        if self._down is None:
            step = 8  # the direction varies slowly: sample every 8 px, look up the nearest
            v, u = np.mgrid[0:self.camera.height:step, 0:self.camera.width:step]
            d = self.camera.image_down_direction(np.stack([u.ravel(), v.ravel()], axis=1).astype(float))
            self._down = (step, d.reshape(u.shape + (2,)))
        step, grid = self._down
        j = min(int(round(uv[1] / step)), grid.shape[0] - 1)
        i = min(int(round(uv[0] / step)), grid.shape[1] - 1)
        d = grid[max(j, 0), max(i, 0)]
        return d if np.isfinite(d).all() else None

    def visible_pixels(self, xy: np.ndarray, height: float, width: float) -> int:
        """Pixels of a person's ellipse at ``xy`` (2,) m inside the image and not hidden by obstacles."""
        inner, _, box, valid, dist = self.forms(np.asarray(xy, float)[None], np.array([height]), np.array([width]))
        u0, u1, v0, v1 = box[0]
        if not valid[0] or u0 >= u1 or v0 >= v1:
            return 0
        inside = ellipse_crop(inner[0], box[0], self.grid, self.args.has_dist)
        return int((inside & (self.occ[v0:v1, u0:u1] >= dist[0])).sum())

    def smallest_person_px(self, walkable_xy: np.ndarray, height: float, width: float) -> float:
        """Image area (px) of a person of this size at the far end of what the camera sees (the
        5th percentile over the walkable floor points ``walkable_xy`` (N, 2) m), computed once:
        smaller blobs cannot be a person and are not looked at."""
        if self._smallest is None:
            n = len(walkable_xy)
            inner, _, box, valid, _ = self.forms(walkable_xy, np.full(n, height), np.full(n, width))
            seen = valid & (box[:, 0] < box[:, 1]) & (box[:, 2] < box[:, 3])
            det = inner[seen, 2] * inner[seen, 4] - inner[seen, 3] ** 2
            areas = np.pi / np.sqrt(np.maximum(det, 1e-12))
            self._smallest = float(np.percentile(areas, 5)) if len(areas) else 0.0
        return self._smallest


def camera_view(scene, camera_id: str, foreground: Foreground | None, ring_px_160: float, draw: DrawArgs) -> CameraView:
    """The :class:`CameraView` of ``camera_id`` in ``scene``: the ring of ``ring_px_160`` pixels at
    160×120 (the paper's 5 px) scaled with the image's linear size ``sqrt(W·H / (160·120))``."""
    cam = scene.camera(camera_id)
    ring = max(1, int(round(ring_px_160 * math.sqrt(cam.width * cam.height / (160 * 120)))))
    args = camera_args(cam, float(ring), scene.occlusion(camera_id).floor_distance)
    return CameraView(cam, args, ring, foreground, draw)


def ray_direction(cam: Camera, xy: np.ndarray) -> np.ndarray:
    """Unit floor direction of the camera's ray through floor point ``xy`` — the direction along
    which one camera cannot tell depth — or the optical axis's for a point right below the camera."""
    return cam.floor_rays(xy, min_distance=0.3)[0]


def pixel_clear(camera: Camera, occ: np.ndarray | None, p: np.ndarray) -> np.ndarray:
    """Whether point(s) ``p`` (..., 2), rounded to the nearest pixel, are inside the image and
    (unless ``occ`` is None) not on an obstacle (``occ`` finite there); bool (...).

    Compiled (:func:`_pixels_clear`): it is called for a handful of points at a time, where
    NumPy's per-call overhead was most of the cost. :func:`pixel_clear_reference` is the plain
    version.
    """
    q = np.asarray(p, dtype=float)
    flat = np.ascontiguousarray(q.reshape(-1, 2))
    grid = _NO_OCC if occ is None else occ
    out = _pixels_clear(flat, camera.width, camera.height, grid, occ is not None)
    return out.reshape(q.shape[:-1]) if q.ndim > 1 else out[0]


#: Stands in for "no obstacle map" in the compiled :func:`_pixels_clear`.
_NO_OCC = np.zeros((1, 1), np.float32)


@njit(cache=True)
def _pixels_clear(p: np.ndarray, width: int, height: int, occ: np.ndarray, use_occ: bool) -> np.ndarray:
    """(N,) bool for points ``p`` (N, 2): rounded (half to even) inside the image and, with
    ``use_occ``, where ``occ`` is not finite."""
    out = np.empty(p.shape[0], dtype=np.bool_)
    for i in range(p.shape[0]):
        u = np.rint(p[i, 0])
        v = np.rint(p[i, 1])
        ok = 0 <= u < width and 0 <= v < height
        if ok and use_occ:
            ok = not np.isfinite(occ[int(v), int(u)])
        out[i] = ok
    return out


def pixel_clear_reference(camera: Camera, occ: np.ndarray | None, p: np.ndarray) -> np.ndarray:
    """:func:`pixel_clear` in plain NumPy, the version it is tested against."""
    q = np.round(p).astype(int)
    u, v = q[..., 0], q[..., 1]
    inside = (u >= 0) & (u < camera.width) & (v >= 0) & (v < camera.height)
    if occ is None:
        return inside
    return inside & ~np.isfinite(occ[np.clip(v, 0, camera.height - 1), np.clip(u, 0, camera.width - 1)])


__all__ = ["CameraView", "camera_view", "pixel_clear", "pixel_clear_reference", "ray_direction"]
