"""How particles read one camera's frame: the kernels' argument containers and the per-pixel rules.

Every likelihood kernel (column, top edge, point) reads the same things, bundled:

* :class:`CameraArgs` — a camera's constants (rotation, translation, intrinsics, distortion, image
  size, foot point, floor direction), built once per camera;
* :class:`Reading` — one camera's frame as the particles of one or more filters read it: the
  labels packed with the box counts (:func:`~.images.read_codes`), each filter's own box and index
  among the occluders, the occluders, each filter's pixel-weight scale and hidden samples, and each
  particle's object height; :class:`ReadAs` is the same at the Python level (what callers give);
* the per-pixel rules the kernels inline: the nearest pixel of a world point (through the one lens
  kernel, :mod:`worldtrack.geometry._kernels`), whether a pixel lies in another object's box and
  whether that object stands nearer to the camera.

>>> boxes, mes, which = filter_rows([(0, 4, 0, 4), None], [0, 1], np.array([1, 0, 1]), 3)
>>> boxes.tolist(), mes.tolist(), which.tolist()
([[0, 4, 0, 4], [-1, -1, -1, -1]], [0, 1], [1, 0, 1])
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, NamedTuple, Sequence

import numpy as np
from numba import njit

from worldtrack.geometry._kernels import nearest_index, world_to_pixel
from worldtrack.trackers.particle.likelihood.images import Occluders

#: A column sample's label when none of its pixels is in the image.
OUT_OF_VIEW = 3
#: A sample in the box of a nearer object: no evidence, like label 2.
OCCLUDED = 4

#: The "no box" value of a filter's own box (a detection filter's).
NO_BOX = np.array([-1, -1, -1, -1], dtype=np.int64)
_NO_BOX_TUPLE = tuple(NO_BOX.tolist())


class CameraArgs(NamedTuple):
    """A camera's constants as the compiled kernels read them (contiguous float64 arrays).

    R (3, 3), t (3,) — world → camera; K (3, 3), dist (5,) — intrinsics and OpenCV distortion;
    has_dist — apply the distortion; width, height — image size, pixels; centre (2,) — the camera's
    foot point on the floor, metres; floor_direction (2,) — its viewing direction on the floor.
    """

    R: np.ndarray
    t: np.ndarray
    K: np.ndarray
    dist: np.ndarray
    has_dist: bool
    width: int
    height: int
    centre: np.ndarray
    floor_direction: np.ndarray


class Reading(NamedTuple):
    """One camera's frame as the particles of F filters read it (the kernels' form of :class:`ReadAs`).

    codes (H, W) uint8 — label in bits 0–1, box count in bits 2–7 (:func:`~.images.read_codes`);
    boxes (F, 4) int64 — each filter's own box (:data:`NO_BOX` for none); mes (F,) int64 — each
    filter's index among the occluders' boxes; which (N,) int64 — each particle's filter; pairs
    (H, W) int32, depths (B + 1,) float64 — :class:`~.images.Occluders`; margin — metres;
    px_scale (F,) float64 — pixel-weight scales (0: unweighted); k_lo (F,) int64 — lowest samples
    read as no evidence; tops (N,) float64 — each particle's object height, metres.
    """

    codes: np.ndarray
    boxes: np.ndarray
    mes: np.ndarray
    which: np.ndarray
    pairs: np.ndarray
    depths: np.ndarray
    margin: float
    px_scale: np.ndarray
    k_lo: np.ndarray
    tops: np.ndarray


@dataclass(frozen=True)
class ReadAs:
    """How particles read a camera's labels; by default every pixel reads its own label.

    Attributes
    ----------
    owner : (H, W) uint8, optional — object boxes per pixel (:func:`~.images.owner_image`): a pixel
        in a box other than the particle's filter's own reads background
    box : the filter's own box ``(u0, u1, v0, v1)`` or None; with ``which``, a sequence of F
    me : int — the filter's index among the occluders' boxes; with ``which``, F of them
    which : (N,) int, optional — each particle's filter, 0 … F − 1 (None: all of one filter)
    occluders : Occluders, optional — with ``me`` and ``margin`` (m): a sample in the box of an
        object nearer to the camera by more than ``margin`` is occluded (no evidence)
    px_scale : float or (F,) — pixel-weight scale, 1 / pixels (0: every sample weighs 1)
    k_lo : int or (F,) — the samples ``heights[:k_lo]`` read no evidence in the ratio
    """

    owner: np.ndarray | None = None
    box: Any = None
    me: int | Sequence[int] = -1
    which: np.ndarray | None = None
    occluders: Occluders | None = None
    margin: float = 0.0
    px_scale: float | Sequence[float] = 0.0
    k_lo: int | Sequence[int] = 0


def filter_rows(box, me: int | Sequence[int], which: np.ndarray | None,
                n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The kernels' per-filter arguments for ``n`` particles of one or more filters.

    Parameters
    ----------
    box : one filter's box ``(u0, u1, v0, v1)`` or None; with ``which``, a sequence of F of them
        (or None for none)
    me : int — the filter's index among the occluders' boxes; with ``which``, a sequence of F (or
        one int for all)
    which : (n,) int, optional — each particle's filter (0 … F − 1); None: all of one filter
    n : int

    Returns
    -------
    boxes : (F, 4) int64 — :data:`NO_BOX` for None
    mes : (F,) int64
    which : (n,) int64
    """
    if which is None:
        box, me, which = [box], [me], np.zeros(n, dtype=np.int64)
    elif box is None:
        box = [None] * (len(me) if np.ndim(me) else int(np.max(which, initial=-1)) + 1)
    boxes = np.array([_NO_BOX_TUPLE if b is None else b for b in box], dtype=np.int64).reshape(-1, 4)
    return boxes, per_filter_int(me, len(boxes)), np.ascontiguousarray(which, dtype=np.int64)


def per_object(v, k: int) -> np.ndarray:
    """(K,) float64 of one value for all ``k`` objects or one per object."""
    if isinstance(v, np.ndarray) and v.dtype == np.float64 and v.shape == (k,) and v.flags.c_contiguous:
        return v
    return np.ascontiguousarray(np.broadcast_to(np.asarray(v, dtype=np.float64), (k,)))


def per_filter_int(v: int | Sequence[int], f: int) -> np.ndarray:
    """(F,) int64 of one value for all ``f`` filters or one per filter."""
    if isinstance(v, np.ndarray) and v.dtype == np.int64 and v.shape == (f,) and v.flags.c_contiguous:
        return v
    if isinstance(v, int):
        return np.full(f, v, dtype=np.int64)
    return np.ascontiguousarray(np.broadcast_to(np.asarray(v, dtype=np.int64), (f,)))


def pixel_scales(px_scale: float | Sequence[float], f: int) -> np.ndarray:
    """(F,) float64 pixel-weight scales (1 / pixels) of ``f`` filters from one scale for all or one
    per filter (0: unweighted samples)."""
    if isinstance(px_scale, np.ndarray) and px_scale.dtype == np.float64 and px_scale.shape == (f,) \
            and px_scale.flags.c_contiguous:
        return px_scale
    return np.ascontiguousarray(np.broadcast_to(np.asarray(px_scale, dtype=np.float64), (f,)))


# ---------------------------------------------------------------------------- per-pixel rules (inlined)

@njit(cache=True, inline="always")
def pixel_of(px, py, pz, camera, lens_, W, H):
    """World point → integer pixel (iu, iv) of an image W × H, or (−1, −1) if behind the camera or
    outside it: :meth:`Camera.project` (:func:`~worldtrack.geometry._kernels.world_to_pixel`), then
    the nearest pixel centre. ``lens_`` from :func:`~worldtrack.geometry._kernels.lens`."""
    u, v = world_to_pixel(px, py, pz, camera.R, camera.t, lens_, camera.has_dist)
    iu, iv = nearest_index(u, W), nearest_index(v, H)
    if iu < 0 or iv < 0:
        return -1, -1
    return iu, iv


@njit(cache=True, inline="always")
def box_of(boxes, f):
    """Row ``f`` of ``boxes`` (F, 4) as a tuple ``(u0, u1, v0, v1)``."""
    return boxes[f, 0], boxes[f, 1], boxes[f, 2], boxes[f, 3]


@njit(cache=True, inline="always")
def in_other_box(n, box, iu, iv):
    """True if pixel (iu, iv), covered by ``n`` object boxes, lies in the box of an object other than
    ``box`` (the filter's own)."""
    if n == 0:
        return False
    own = 1 if (box[0] <= iu < box[1] and box[2] <= iv < box[3]) else 0
    return n > own


@njit(cache=True, inline="always")
def occluded(pairs, depths, me, iu, iv, depth, margin):
    """True if the nearest other object's box over pixel (iu, iv) is nearer than ``depth − margin``."""
    if pairs.shape[0] == 0:
        return False
    p = pairs[iv, iu]
    first = p & 0xFFFF
    d = depths[p >> 16] if first - 1 == me else depths[first]
    return d < depth - margin


@njit(cache=True, inline="always")
def read_line(codes, box, iu, iv, lab):
    """Read one line's pixel (iu, iv) of a column sample whose label so far is ``lab`` (not 1).

    Returns the new label — :data:`OUT_OF_VIEW` until a pixel in the image is read, then 1 if this
    pixel reads object, 2 if it reads no evidence, else unchanged (0 once in the image) — and
    whether the pixel lies in another object's box (then its label is not read)."""
    if iu < 0:
        return lab, False
    if lab == OUT_OF_VIEW:
        lab = 0
    c = codes[iv, iu]
    if in_other_box(c >> 2, box, iu, iv):
        return lab, True
    p = c & 3
    return (p if p == 1 or p == 2 else lab), False


@njit(cache=True, inline="always")
def floor_unit(x, y, centre, floor_direction):
    """Unit floor vector (a_x, a_y) from the camera's foot point ``centre`` towards (x, y); the
    camera's ``floor_direction`` within 1e-9 m of it (:meth:`Camera.floor_rays`' ``along``)."""
    dx = x - centre[0]
    dy = y - centre[1]
    n = math.hypot(dx, dy)
    if n > 1e-9:
        return dx / n, dy / n
    return floor_direction[0], floor_direction[1]


__all__ = ["NO_BOX", "OCCLUDED", "OUT_OF_VIEW", "CameraArgs", "ReadAs", "Reading", "filter_rows", "per_filter_int",
           "per_object", "pixel_scales"]
