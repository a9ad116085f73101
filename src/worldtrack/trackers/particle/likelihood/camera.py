"""One camera as the likelihood kernels read it: :class:`CameraLikelihood`, and its floor geometry.

:class:`CameraLikelihood` holds a camera's constants as the kernels take them (:class:`CameraArgs`,
built once) and calls the kernels with them: the height column (:meth:`~CameraLikelihood.column`),
the top edge, the point, the objects' image boxes, and the floor geometry the column needs — the
lines of sight on the floor (:func:`floor_along`), floor distances, the point a column stands on
``surface_offset`` nearer to the camera (:func:`toward_camera`) and the columns beside a centre
(:func:`columns_beside`). Each kernel's arithmetic is that of :meth:`Camera.floor_rays` or
:meth:`Camera.project` (tested equal).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from worldtrack.geometry.camera import Camera
from worldtrack.trackers.particle.likelihood.boxes import Box, box_pixels
from worldtrack.trackers.particle.likelihood.column import ColumnOut, ColumnSpec, column_counts
from worldtrack.trackers.particle.likelihood.images import NO_OCCLUDERS, read_codes
from worldtrack.trackers.particle.likelihood.point import point_values
from worldtrack.trackers.particle.likelihood.reading import (CameraArgs, ReadAs, Reading, filter_rows, floor_unit,
                                                                 per_filter_int, per_object, pixel_scales)
from worldtrack.trackers.particle.likelihood.top_edge import EdgeSpec, top_edge_terms

_NO_READ = ReadAs()


class CameraLikelihood:
    """One camera's constants for the kernels (contiguous float64 arrays), built once.

    Parameters
    ----------
    camera : Camera

    Attributes
    ----------
    camera : Camera
    args : CameraArgs — what the kernels take
    work : dict — work arrays of compiled calls, kept from call to call
    """

    def __init__(self, camera: Camera):
        self.camera = camera
        self.args = CameraArgs(np.ascontiguousarray(camera.R, dtype=np.float64),
                               np.ascontiguousarray(camera.t, dtype=np.float64),
                               np.ascontiguousarray(camera.K, dtype=np.float64),
                               np.ascontiguousarray(camera.dist, dtype=np.float64), bool(camera.has_distortion),
                               int(camera.width), int(camera.height),
                               np.ascontiguousarray(camera.centre[:2], dtype=np.float64),
                               np.ascontiguousarray(camera.floor_direction, dtype=np.float64))
        self.no_owner = np.zeros((camera.height, camera.width), dtype=np.uint8)
        self._codes: np.ndarray | None = None     # read_codes' output, reused call to call
        self.work: dict = {}

    @property
    def K(self) -> np.ndarray:
        return self.args.K

    def along(self, xy: np.ndarray) -> np.ndarray:
        """(N, 2) the camera's lines of sight on the floor through ``xy`` (N, 2), metres: the
        ``along`` of :meth:`Camera.floor_rays`, by the kernel :func:`floor_along`."""
        xy = np.ascontiguousarray(np.asarray(xy, dtype=np.float64).reshape(-1, 2))
        out = np.empty_like(xy)
        floor_along(xy, self.args, out)
        return out

    def near_surface(self, xy: np.ndarray, offset: float) -> np.ndarray:
        """(N, 2) floor points ``offset`` m nearer to the camera than ``xy`` (N, 2) (or the first two
        columns of (N, ≥ 2)), metres, along its lines of sight: ``xy − offset·along``
        (:func:`toward_camera`)."""
        xy = np.asarray(xy, dtype=np.float64)
        if xy.ndim != 2 or xy.shape[1] < 2:
            xy = xy.reshape(-1, 2)
        out = np.empty((len(xy), 2))
        toward_camera(xy, float(offset), self.args, out)
        return out

    def boxes(self, xy: np.ndarray, widths: np.ndarray, heights: np.ndarray, margin: float,
              depth: float = 0.0) -> list[Box | None]:
        """:func:`~worldtrack.trackers.particle.likelihood.boxes.image_boxes` of objects at ``xy`` (K, 2) with
        ``widths, heights`` (K,) — by the kernel :func:`~worldtrack.trackers.particle.likelihood.boxes.box_pixels`."""
        return [tuple(b) if b[0] >= 0 else None for b in self.box_array(xy, widths, heights, margin, depth).tolist()]

    def box_array(self, xy: np.ndarray, widths: np.ndarray, heights: np.ndarray, margin: float,
                  depth: float = 0.0) -> np.ndarray:
        """:meth:`boxes` as (K, 4) int64 ``(u0, u1, v0, v1)``, rows of −1 for no box."""
        xy = np.ascontiguousarray(np.asarray(xy, dtype=np.float64).reshape(-1, 2))
        k = len(xy)
        out = np.empty((k, 4), dtype=np.int64)
        box_pixels(xy, per_object(widths, k), per_object(heights, k), float(margin), float(depth), self.args, out)
        return out

    def distances(self, xy: np.ndarray) -> np.ndarray:
        """(N,) the floor distances (m) of ``xy`` (N, 2) from the camera's foot point: :meth:`Camera.floor_rays`'
        ``distance``, by a kernel."""
        xy = np.ascontiguousarray(np.asarray(xy, dtype=np.float64).reshape(-1, 2))
        out = np.empty(len(xy))
        floor_distances(xy, self.args.centre, out)
        return out

    def beside(self, xy: np.ndarray, offset: float, spread: np.ndarray) -> np.ndarray:
        """(3K, 2) metres: for each of ``xy`` (K, 2), its column ``offset`` m nearer to the camera
        (as :meth:`near_surface`; ``xy`` itself for ``offset ≤ 0``) and the two ``spread`` (K,) m to
        either side of it across the line of sight through it, in that order (:func:`columns_beside`)."""
        xy = np.ascontiguousarray(np.asarray(xy, dtype=np.float64).reshape(-1, 2))
        out = np.empty((3 * len(xy), 2))
        columns_beside(xy, float(offset), np.ascontiguousarray(spread, dtype=np.float64), self.args, out)
        return out

    def reading(self, hit: np.ndarray, n: int, read: ReadAs | None = None, tops: np.ndarray | None = None) -> Reading:
        """The :class:`Reading` of ``n`` particles read as ``read`` says, with object heights ``tops``
        (N,) metres (default 0): the labels ``hit`` packed with ``read.owner``'s box counts."""
        read = read or _NO_READ
        boxes, mes, which = filter_rows(read.box, read.me, read.which, n)
        if read.owner is None:
            codes = hit                             # labels 0, 1, 2 are the codes of pixels in no box
        else:
            if self._codes is None or self._codes.shape != hit.shape:
                self._codes = np.empty(hit.shape, dtype=np.uint8)
            codes = read_codes(hit, read.owner, self._codes)
        occ = NO_OCCLUDERS if read.occluders is None else read.occluders
        return Reading(codes, boxes, mes, which, occ.pairs, occ.depths, float(read.margin),
                       pixel_scales(read.px_scale, len(boxes)), per_filter_int(read.k_lo, len(boxes)),
                       np.zeros(n) if tops is None else np.ascontiguousarray(tops, dtype=np.float64))

    def column(self, hit: np.ndarray, xy: np.ndarray, column: ColumnSpec, read: ReadAs | None = None,
               tops: np.ndarray | None = None) -> ColumnOut:
        """The height columns at ``xy`` (N, 2) read from labels ``hit`` as ``read`` says
        (:func:`~.column.column_counts`); without ``tops`` there is no height prior."""
        xy = np.ascontiguousarray(xy, dtype=np.float64)
        out = ColumnOut.empty(len(xy))
        if tops is None and column.top_sigma != 0.0:
            column = column._replace(top_sigma=0.0)
        column_counts(xy, self.args, column, self.reading(hit, len(xy), read, tops), out)
        return out

    def top_edge(self, reading: Reading, xy: np.ndarray, tops: np.ndarray, edge: EdgeSpec, out: np.ndarray) -> None:
        """Add the top-edge terms (:func:`~.top_edge.top_edge_terms`) of the particles ``xy`` (N, ≥ 2)
        at heights ``tops`` (N,), metres, to ``out`` (N,) in place, read as ``reading`` says."""
        top_edge_terms(np.ascontiguousarray(xy, dtype=np.float64), np.ascontiguousarray(tops, dtype=np.float64),
                       edge, self.args, reading, out)

    def point(self, F: np.ndarray, xyz: np.ndarray, owner: np.ndarray | None = None,
              box=None, which: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(F values (N,) float64, seen (N,) bool) at the points ``xyz`` (N, 3) — eq. 7; ``box``
        and ``which`` as in :class:`ReadAs`."""
        xyz = np.ascontiguousarray(xyz, dtype=np.float64)
        boxes, _, which = filter_rows(box, -1, which, len(xyz))
        values = np.empty(len(xyz), dtype=np.float64)
        seen = np.empty(len(xyz), dtype=np.bool_)
        point_values(xyz, self.args, F, self.no_owner if owner is None else owner, boxes, which, values, seen)
        return values, seen


# ---------------------------------------------------------------------------- floor geometry kernels

@njit(cache=True)
def floor_along(xy, camera, out):
    """The camera's lines of sight on the floor through ``xy`` (N, 2), metres, in place: ``out``
    (N, 2) unit vectors from its foot point towards the points, its ``floor_direction`` within
    1e-9 m of it — :meth:`Camera.floor_rays`' ``along``, the same arithmetic (tested equal)."""
    for i in range(xy.shape[0]):
        out[i, 0], out[i, 1] = floor_unit(xy[i, 0], xy[i, 1], camera.centre, camera.floor_direction)


@njit(cache=True)
def floor_distances(xy, centre, out):
    """``out`` (N,), in place: the floor distances of ``xy`` (N, 2) from ``centre`` (2,), metres —
    :meth:`Camera.floor_rays`' ``distance`` (``np.hypot``: the same C ``hypot``; tested equal)."""
    for i in range(xy.shape[0]):
        out[i] = math.hypot(xy[i, 0] - centre[0], xy[i, 1] - centre[1])


@njit(cache=True)
def toward_camera(xy, offset, camera, out):
    """``xy − offset·along`` (N, 2), metres, in place: the floor points ``offset`` m nearer to the
    camera along its lines of sight (:func:`floor_along`); tested equal to the NumPy expression."""
    for i in range(xy.shape[0]):
        ax, ay = floor_unit(xy[i, 0], xy[i, 1], camera.centre, camera.floor_direction)
        out[i, 0] = xy[i, 0] - offset * ax
        out[i, 1] = xy[i, 1] - offset * ay


@njit(cache=True)
def columns_beside(xy, offset, spread, camera, out):
    """``out`` (3K, 2), in place: per point of ``xy`` (K, 2), metres, ``c`` = the point moved ``offset``
    nearer to the camera (:func:`toward_camera`; the point itself for ``offset ≤ 0``), then
    ``c ± spread·(−a_y, a_x)`` with ``a`` the line of sight through ``c`` (:func:`floor_along`) —
    the arithmetic of :func:`columns_beside_reference`."""
    centre, floor_direction = camera.centre, camera.floor_direction
    for i in range(xy.shape[0]):
        x, y = xy[i, 0], xy[i, 1]
        if offset > 0.0:
            ax, ay = floor_unit(x, y, centre, floor_direction)
            x, y = x - offset * ax, y - offset * ay
        ax, ay = floor_unit(x, y, centre, floor_direction)
        sx, sy = -ay * spread[i], ax * spread[i]
        out[3 * i, 0], out[3 * i, 1] = x, y
        out[3 * i + 1, 0], out[3 * i + 1, 1] = x + sx, y + sy
        out[3 * i + 2, 0], out[3 * i + 2, 1] = x - sx, y - sy


def columns_beside_reference(camera: Camera, xy: np.ndarray, offset: float, spread: np.ndarray) -> np.ndarray:
    """:func:`columns_beside` with :meth:`Camera.floor_rays` in NumPy (the tracker's former code)."""
    centre = xy - offset * camera.floor_rays(xy)[0] if offset > 0 else xy
    along, _ = camera.floor_rays(centre)
    across = np.column_stack([-along[:, 1], along[:, 0]]) * np.asarray(spread)[:, None]
    return np.stack([centre, centre + across, centre - across], axis=1).reshape(-1, 2)


__all__ = ["CameraLikelihood", "columns_beside", "columns_beside_reference", "floor_along", "floor_distances",
           "toward_camera"]
