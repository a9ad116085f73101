"""Likelihoods of seed 004's particle filters: the height column (eqs. 11–13) and the plain point (eq. 7).

Both read one image per camera and frame, computed once from the background difference
``F = sqrt(ΔR² + ΔG² + ΔB²)`` (eq. 13, :func:`worldtrack.foreground.background.colour_distance`)
with values ``F ≤ γ`` set to 0 (§4.2: against slight brightness changes of the background):

* :func:`hit_image` — ``F > γ`` as (H, W) uint8, for the column likelihood;
* :func:`hit_labels` — the same with cast shadows set apart (background or "no evidence", 2) by
  colour and texture (not in the paper; Numba, with :func:`hit_labels_reference` in NumPy);
* :func:`thresholded_difference` — F with ``F ≤ γ`` set to 0, float32, for the point likelihood.

**Height column** (the paper's contribution). For a particle at floor position ``(x_i, y_i)`` the
points ``(x_i, y_i, k·dz)``, ``k = 0 … T``, are projected and those that land on ``F > γ`` counted::

    π_i = Σ_k δ(x_i, y_i, k·dz),   δ = 1 if F(x_i, y_i, k·dz) > γ else 0          (eqs. 11, 12)

A particle inside the object keeps hitting the object's image all the way up its column; one that is
merely on the same line of sight as the object (in front of or behind it, Fig. 5) does not.

The kernel also returns a second statistic of the same samples, the log-likelihood ratio of the best
object top (``ratio``): an object standing at the particle and reaching up to sample ``k`` explains
samples ``0 … k``; each adds ``on`` if it hits, ``off`` if it reads background and nothing if it
reads "no evidence" (a shadow, label 2). A ring round the column must read background (worldtrack's
extension, the column's counterpart of seed 000's −1 ring): ``n_below`` samples below the floor and
the ``n_above`` samples above the top add ``below`` (< 0) each if they hit — an object standing
here has nothing under its feet or over its head, while a column that stands on a body, or stops
short inside one, does. The best top ``k ≥ k_min`` is kept. And a column can be a thin cylinder (``radius > 0``): a sample hits if its pixel or one of
the two pixels ``f_x·radius / depth`` to its left and right hits (the sample's neighbours ``radius``
across the line of sight, for a camera without roll).

**Top edge** (worldtrack's, with the column's ``ratio``). The column finds its top on the ``dz``
grid; :func:`top_edge_terms` reads a few samples just below and just above each particle's own
object height, which the particle carries from frame to frame, so the top edge is read to a pixel
rather than to ``dz``. One camera's column leaves a valley of (depth, height) pairs; with the height
held, the head's edge fixes depth where the feet, moving with the stride, do not.

**Point** (the baseline the paper improves on). The particle's own 3-D point is projected and
``π_i = F(u, v)`` read there (eq. 7).

**Explained pixels.** Every kernel takes an ``owner`` image — how many tracked objects' image boxes
cover each pixel (:func:`owner_image`) — and the box of the filter's own object: a pixel inside some
other object's box reads as background. A filter then cannot take over its neighbour's pixels, and a
detection filter sees only what no track explains.

A sample that projects outside the image, or lies behind the camera, does not make the camera "see"
the particle, and it reads background (the paper: the image is all the evidence there is) or, with
``outside_unknown``, no evidence: it adds ``off`` or nothing to ``ratio``, and is never counted in
``counts``. (With a cylinder a sample is outside only if none of its three pixels is in the image.)
A person standing with the feet below the image's bottom edge otherwise loses ``off`` for every
sample out of view, and the filter drifts away from the camera, to where the whole column is in
view. Pixels are read at the nearest pixel centre (pixel centres at integer coordinates, the image covering ``−0.5 ≤ u < W − 0.5``, as :class:`Camera` defines).

Each kernel (:func:`column_counts`, :func:`top_edge_terms`, :func:`point_values`) has a plain NumPy
reference built on :meth:`Camera.project` (:func:`column_counts_reference`,
:func:`top_edge_terms_reference`, :func:`point_values_reference`); the tests check that they agree.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np
from numba import njit

from worldtrack.foreground.shadows import (CANDIDATE, TEXTURE_NCC, floor_pixels, hit_image, hit_labels,  # noqa: F401
                                           hit_labels_reference, thresholded_difference)
from worldtrack.geometry.camera import Camera

#: Largest possible Euclidean RGB distance, ``sqrt(3)·255``: divides F so that point likelihoods of
#: several cameras multiply on a common scale.
F_MAX = float(math.sqrt(3.0) * 255.0)

#: The "no box" value of a filter's own box (a detection filter's).
NO_BOX = np.array([-1, -1, -1, -1], dtype=np.int64)


# ---------------------------------------------------------------------------- per-frame images

#: A column sample's label when none of its pixels is in the image (:func:`column_counts`).
_OUT_OF_VIEW = 3
_OCCLUDED = 4          # in the box of a nearer object: no evidence, like 2



def owner_image(shape: tuple[int, int], boxes, out: np.ndarray | None = None, previous=()) -> np.ndarray:
    """(H, W) uint8: how many of ``boxes`` — ``(u0, u1, v0, v1)`` pixel ranges, or None — cover each pixel.

    ``out``: an earlier result to reuse, whose ``previous`` boxes are cleared (not the whole frame:
    a fresh 640×480 image costs more in page faults than its boxes cost to fill)."""
    if out is None or out.shape != tuple(shape):
        out, previous = np.zeros(shape, dtype=np.uint8), ()
    _count_boxes(out, _box_rows(previous), _box_rows(boxes))
    return out


def owner_image_reference(shape: tuple[int, int], boxes) -> np.ndarray:
    """:func:`owner_image` in NumPy (box by box, saturating at 255)."""
    out = np.zeros(shape, dtype=np.uint8)
    for b in boxes:
        if b is not None:
            u0, u1, v0, v1 = b
            out[v0:v1, u0:u1] = np.minimum(out[v0:v1, u0:u1], 254) + 1
    return out


def _box_rows(boxes) -> np.ndarray:
    """(K, 4) int64 of the boxes that are not None."""
    rows = [b for b in boxes if b is not None]
    return np.array(rows, dtype=np.int64).reshape(len(rows), 4)


@njit(cache=True)
def _count_boxes(out, clear, boxes):
    """Zero the pixel ranges ``clear`` (K, 4) of ``out``, then add 1 (up to 255) over each of ``boxes``
    — ranges ``(u0, u1, v0, v1)`` as Python slices take them (ends clipped to the image; a start
    beyond the end is empty)."""
    # (Row slices: loops over them compile to vector code, indexing with possibly negative ints does not.)
    H = out.shape[0]
    _clear_ranges(out, clear)
    for j in range(boxes.shape[0]):
        for v in range(_slice_index(boxes[j, 2], H), _slice_index(boxes[j, 3], H)):
            row = out[v, boxes[j, 0]:boxes[j, 1]]
            for u in range(row.shape[0]):
                x = row[u]
                row[u] = x + (x < 255)


@njit(cache=True, inline="always")
def _slice_index(i, n):
    """A slice start or stop as Python takes it on an axis of ``n`` (step 1): negative counts from
    the end, then clipped to [0, n]."""
    return max(i + n, 0) if i < 0 else min(i, n)


@njit(cache=True, inline="always")
def _clear_ranges(a, ranges):
    """Zero the pixel ranges ``(u0, u1, v0, v1)`` (K, 4) of the image ``a`` as Python slices take them."""
    H = a.shape[0]
    for j in range(ranges.shape[0]):
        for v in range(_slice_index(ranges[j, 2], H), _slice_index(ranges[j, 3], H)):
            a[v, ranges[j, 0]:ranges[j, 1]] = 0


def read_codes(hit: np.ndarray, owner: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """(H, W) uint8 what :func:`column_counts` reads per pixel: the label of ``hit`` (0, 1, 2; any
    other value reads as 0, background) in bits 0–1 and the box count of ``owner`` (saturated at
    63, which reads the same: more than one box) in bits 2–7.

    Parameters
    ----------
    hit : (H, W) uint8 — :func:`hit_image` or :func:`hit_labels`
    owner : (H, W) uint8 — :func:`owner_image`
    out : (H, W) uint8, optional — written in place and returned
    """
    hit = np.ascontiguousarray(hit, dtype=np.uint8)
    owner = np.ascontiguousarray(owner, dtype=np.uint8)
    if out is None:
        out = np.empty(hit.shape, dtype=np.uint8)
    _read_codes(hit, owner, out)
    return out


@njit(cache=True)
def _read_codes(hit, owner, out):
    for v in range(hit.shape[0]):
        for u in range(hit.shape[1]):
            h = hit[v, u]
            out[v, u] = (h if h <= 2 else 0) | (min(owner[v, u], 63) << 2)


def occluder_layers(shape: tuple[int, int], boxes, depths, out: "Occluders | None" = None) -> "Occluders":
    """Per pixel, the nearest and second-nearest of ``boxes`` that cover it, for depth-ordered reading.

    Parameters
    ----------
    shape : (H, W)
    boxes : sequence of ``(u0, u1, v0, v1)`` pixel ranges or None, one per tracked object (fewer
        than 32767)
    depths : sequence of float, metres — each object's floor distance from the camera
    out : Occluders, optional — an earlier result to reuse: only the boxes it holds are cleared
        (allocating full frames every frame cost ~1 ms at 640×480)

    Returns
    -------
    Occluders — per pixel the indices of the two nearest boxes (``pairs``) and each box's depth
    (``depths``); read as layers: ``near1`` (H, W) float64, the depth of the nearest box over each
    pixel (inf where none), ``id1`` (H, W) int32 its index in ``boxes`` (−1 where none), ``near2``
    (H, W) float64 the depth of the second nearest (inf where fewer than two)
    """
    if len(boxes) >= _MAX_BOXES:
        raise ValueError(f"occluder_layers: at most {_MAX_BOXES - 1} boxes, got {len(boxes)}")
    if out is None or out.pairs.shape != tuple(shape):
        out = Occluders(np.zeros(shape, dtype=np.int32), np.full(1, np.inf))
    clear = _box_rows(out.filled)                   # last use's boxes only (no full-frame pass)
    given = [k for k, b in enumerate(boxes) if b is not None]
    out.filled = [boxes[k] for k in given]
    out.depths = np.full(len(boxes) + 1, np.inf)
    if given:
        out.depths[np.array(given) + 1] = [depths[k] for k in given]
    # Nearest first (stable: the earlier box first at equal depths); a box of NaN or infinite depth
    # is never one of the two nearest. Each pixel then keeps the first two boxes that cover it.
    order = sorted((k for k in given if out.depths[k + 1] < math.inf), key=lambda k: out.depths[k + 1])
    _fill_layers(out.pairs, clear, np.array([boxes[k] for k in order], dtype=np.int64).reshape(-1, 4),
                 np.array(order, dtype=np.int32))
    return out


#: Box indices of :func:`occluder_layers` are stored plus one in 16 bits (0: none).
_MAX_BOXES = 32767


@njit(cache=True)
def _fill_layers(pairs, clear, boxes, ids):
    """Zero the ranges ``clear`` (K, 4) of ``pairs`` (Python's slice rules), then give each pixel of
    the boxes ``(u0, u1, v0, v1)`` (nearest first, with their indices ``ids``) the first two that
    cover it: index + 1 in bits 0–15, then 16–30, in place."""
    H, W = pairs.shape
    _clear_ranges(pairs, clear)
    for j in range(boxes.shape[0]):
        k = np.int32(ids[j] + 1)
        k2 = np.int32((ids[j] + 1) << 16)
        for v in range(max(boxes[j, 2], 0), min(boxes[j, 3], H)):
            row = pairs[v, max(boxes[j, 0], 0):max(min(boxes[j, 1], W), 0)]
            for u in range(row.shape[0]):
                p = row[u]
                row[u] = k if p == 0 else (p | k2 if p >> 16 == 0 else p)


class Occluders:
    """The two nearest boxes over each pixel, as :func:`occluder_layers` makes them;
    :data:`NO_OCCLUDERS` when there are none.

    Attributes
    ----------
    pairs : (H, W) int32 — ``(i1 + 1) | (i2 + 1) << 16`` with i1 the index of the nearest box over the
        pixel and i2 that of the second nearest (0 for none): what the column kernel reads, one
        4-byte word per pixel
    depths : (B + 1,) float64, metres — ``depths[i + 1]`` the depth of box i, ``depths[0] = inf``
    filled : list — the boxes written into ``pairs`` (cleared on reuse)

    The layers as arrays (:attr:`near1`, :attr:`id1`, :attr:`near2`, also what iterating gives) are
    made from these when asked for.
    """

    def __init__(self, pairs: np.ndarray, depths: np.ndarray):
        self.pairs = np.ascontiguousarray(pairs, dtype=np.int32)
        self.depths = np.ascontiguousarray(depths, dtype=np.float64)
        self.filled = []            # the boxes written into ``pairs`` (cleared on reuse)

    @property
    def near1(self) -> np.ndarray:
        """(H, W) float64 the depth of the nearest box over each pixel (inf where none)."""
        return self.depths[self.pairs & 0xFFFF]

    @property
    def id1(self) -> np.ndarray:
        """(H, W) int32 the index of the nearest box over each pixel (−1 where none)."""
        return (self.pairs & 0xFFFF) - 1

    @property
    def near2(self) -> np.ndarray:
        """(H, W) float64 the depth of the second-nearest box over each pixel (inf where fewer than two)."""
        return self.depths[self.pairs >> 16]

    def __iter__(self):
        return iter((self.near1, self.id1, self.near2))

    def depth_for(self, me, iv=slice(None), iu=slice(None)) -> np.ndarray:
        """The depth of the nearest box other than box ``me``'s over pixels ``(iv, iu)`` (inf where none).

        Default: over the whole image, (H, W). ``me`` an int, or an array of box indices that
        broadcasts against the pixel indices ``iv, iu`` (one per pixel read)."""
        p = self.pairs[iv, iu]
        first = p & 0xFFFF
        return self.depths[np.where(first - 1 == me, p >> 16, first)]


#: No occluders: reading by depth disabled.
NO_OCCLUDERS = Occluders(np.zeros((0, 0), dtype=np.int32), np.full(1, np.inf))


def column_heights(max_height: float, dz: float) -> np.ndarray:
    """The column's sample heights ``k·dz``, ``k = 0 … T`` with ``T = round(max_height / dz)``, metres."""
    T = int(round(max_height / dz))
    return np.arange(T + 1, dtype=float) * dz


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
    return boxes, _per_filter_int(me, len(boxes)), np.ascontiguousarray(which, dtype=np.int64)


_NO_BOX_TUPLE = tuple(NO_BOX.tolist())


def _per_object(v, k: int) -> np.ndarray:
    """(K,) float64 of one value for all ``k`` objects or one per object."""
    if isinstance(v, np.ndarray) and v.dtype == np.float64 and v.shape == (k,) and v.flags.c_contiguous:
        return v
    return np.ascontiguousarray(np.broadcast_to(np.asarray(v, dtype=np.float64), (k,)))


def _per_filter_int(v: int | Sequence[int], f: int) -> np.ndarray:
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


# ---------------------------------------------------------------------------- Numba kernels
#
# The kernels read the intrinsics and distortion once per call, as a tuple of scalars (:func:`_lens`),
# and the column kernel the rotation's entries too: read from the arrays inside the sample loop they
# are reloaded at every sample (the compiler cannot tell that the output arrays do not alias them),
# which cost the column kernel about a quarter of its time.

@njit(cache=True, inline="always")
def _lens(K, dist):
    """The intrinsics and distortion as scalars: ``(f_x, skew, c_x, f_y, c_y, k1, k2, p1, p2, k3)``."""
    return K[0, 0], K[0, 1], K[0, 2], K[1, 1], K[1, 2], dist[0], dist[1], dist[2], dist[3], dist[4]


@njit(cache=True, inline="always")
def _cam_to_uv(cx, cy, cz, lens, has_dist):
    """Camera-frame point → pixel coordinates (u, v) (no rounding, no image test); NaN behind the camera.

    ``lens`` from :func:`_lens`."""
    if not cz > 1e-9:
        return np.nan, np.nan
    x = cx / cz
    y = cy / cz
    if has_dist:
        k1, k2, p1, p2, k3 = lens[5], lens[6], lens[7], lens[8], lens[9]
        r2 = x * x + y * y
        radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
        xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
        yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
        x, y = xd, yd
    return lens[0] * x + lens[1] * y + lens[2], lens[3] * y + lens[4]


@njit(cache=True, inline="always")
def _nearest(c, n):
    """Nearest pixel index of coordinate ``c`` along an image axis of ``n`` pixels, −1 outside (or NaN)."""
    if not (c >= -0.5 and c < n - 0.5):
        return -1
    return int(math.floor(c + 0.5))


@njit(cache=True, inline="always")
def _to_pixel(px, py, pz, R, t, lens, has_dist, W, H):
    """World point → integer pixel (iu, iv), or (−1, −1) if behind the camera or outside the image.

    The arithmetic of :meth:`Camera.project`, then rounding to the nearest pixel centre."""
    cx = R[0, 0] * px + R[0, 1] * py + R[0, 2] * pz + t[0]
    cy = R[1, 0] * px + R[1, 1] * py + R[1, 2] * pz + t[1]
    cz = R[2, 0] * px + R[2, 1] * py + R[2, 2] * pz + t[2]
    u, v = _cam_to_uv(cx, cy, cz, lens, has_dist)
    iu, iv = _nearest(u, W), _nearest(v, H)
    if iu < 0 or iv < 0:
        return -1, -1
    return iu, iv


@njit(cache=True, inline="always")
def _box(boxes, f):
    """Row ``f`` of ``boxes`` (F, 4) as a tuple ``(u0, u1, v0, v1)``."""
    return boxes[f, 0], boxes[f, 1], boxes[f, 2], boxes[f, 3]


@njit(cache=True, inline="always")
def _others(n, box, iu, iv):
    """True if pixel (iu, iv), covered by ``n`` object boxes, lies in the box of an object other than
    ``box`` (the filter's own)."""
    if n == 0:
        return False
    own = 1 if (box[0] <= iu < box[1] and box[2] <= iv < box[3]) else 0
    return n > own


@njit(cache=True, inline="always")
def _occluded(pairs, depths, me, iu, iv, depth, margin):
    """True if the nearest other object's box over pixel (iu, iv) is nearer than ``depth − margin``."""
    if pairs.shape[0] == 0:
        return False
    p = pairs[iv, iu]
    first = p & 0xFFFF
    d = depths[p >> 16] if first - 1 == me else depths[first]
    return d < depth - margin


@njit(cache=True, inline="always")
def _read_line(codes, box, iu, iv, lab):
    """Read one line's pixel (iu, iv) of a column sample whose label so far is ``lab`` (not 1).

    Returns the new label — ``_OUT_OF_VIEW`` until a pixel in the image is read, then 1 if this
    pixel reads object, 2 if it reads no evidence, else unchanged (0 once in the image) — and
    whether the pixel lies in another object's box (then its label is not read)."""
    if iu < 0:
        return lab, False
    if lab == _OUT_OF_VIEW:
        lab = 0
    c = codes[iv, iu]
    if _others(c >> 2, box, iu, iv):
        return lab, True
    p = c & 3
    return (p if p == 1 or p == 2 else lab), False


@njit(cache=True)
def column_counts(xy: np.ndarray, heights: np.ndarray, R: np.ndarray, t: np.ndarray, K: np.ndarray,
                  dist: np.ndarray, has_dist: bool, radius: float, codes: np.ndarray, boxes: np.ndarray,
                  which: np.ndarray, pairs: np.ndarray, depths: np.ndarray, mes: np.ndarray, centre: np.ndarray,
                  margin: float, on: float, off: float, below: float, n_below: int, n_above: int, k_min: int,
                  tops: np.ndarray, top_sigma: float, px_scale: np.ndarray, outside_unknown: bool,
                  k_lo: np.ndarray, counts: np.ndarray, ratio: np.ndarray, top: np.ndarray, seen: np.ndarray,
                  hidden: np.ndarray) -> None:
    """Height-column likelihood of the particles of one or more filters for one camera, in place.

    Parameters
    ----------
    xy : (N, 2) float64, metres — particles' floor positions
    heights : (S,) float64, metres — ``n_below`` heights below the floor, then ``k·dz``, k = 0 … T,
        then ``n_above`` heights above ``T·dz``
    R, t, K, dist : the camera's rotation (3, 3), translation (3,), intrinsics (3, 3), distortion (5,)
    has_dist : bool — apply the distortion model
    radius : float, metres — 0: a line of points (the paper); > 0: a thin cylinder (module docstring)
    codes : (H, W) uint8 — per pixel the label in bits 0–1 (1 object, 0 background, 2 no evidence:
        :func:`hit_image`, :func:`hit_labels`) and in bits 2–7 how many object boxes cover it
        (:func:`owner_image`, up to 63): :func:`read_codes`, one byte read per pixel instead of two
    boxes : (F, 4) int64 — each filter's own object box ``(u0, u1, v0, v1)``, or :data:`NO_BOX`
    which : (N,) int64 — each particle's filter, a row of ``boxes`` and ``mes``
    pairs, depths : :class:`Occluders` ``pairs`` (H, W) int32 and ``depths`` (B + 1,) float64 of the
        same boxes (:func:`occluder_layers`), or those of :data:`NO_OCCLUDERS`. With them, a sample
        in another object's box whose object is nearer to the camera than the particle by more than
        ``margin`` is *occluded*: no evidence (label 2) instead of background
    mes : (F,) int64 — each filter's own index in the boxes of ``pairs, depths``
    centre : (2,) float64, metres — the camera centre's floor position (depths are floor distances)
    margin : float, metres
    on, off, below : float — log-ratio terms for a sample on / off the object, and for a ring sample
        (below the floor, or within ``n_above`` samples above the top) that reads object
    n_below, n_above : int — how many of ``heights`` (the first / the last ones) are ring samples
    k_min : int — the top is searched from index ``k_min`` of ``heights`` up to ``S − n_above − 1``
    tops, top_sigma : (N,) float64 and float, metres — with ``top_sigma > 0`` each particle's own
        object height: a top at height z adds the log prior ``−(z − tops[i])² / (2·top_sigma²)``
    px_scale : (F,) float64, 1 / pixels — per filter, 0: every sample weighs 1 (the paper's
        samples); > 0: each sample's terms are weighted by the image length it stands for times
        ``px_scale``, so that a column counts *pixels* of evidence and a far column, short in the
        image, does not gain from packing more samples into the same pixels
    outside_unknown : bool — a sample out of the image (none of its pixels in it) or behind the
        camera adds nothing to ``ratio`` (no evidence) instead of ``off`` (background, the paper)
    k_lo : (F,) int64 — per filter, the samples ``heights[:k_lo]`` read no evidence in ``ratio`` (not
        in ``counts``): the columns of a filter whose lower part is hidden (behind a nearer object,
        below the image's edge) are scored on the samples they all see
    counts : (N,) int32 — out: samples ``k·dz``, k = 0 … T, on ``F > γ`` (labels 1 and 2: π_i, eq. 11);
        a sample out of the image is never counted
    ratio : (N,) float64 — out: the best log-likelihood ratio
    top : (N,) int32 — out: the index into ``heights`` of the best top
    seen : (N,) bool — out: at least one sample projects into the image
    hidden : (N,) int32 — out: how many of the lowest samples, from ``heights[0]`` up, are hidden —
        occluded, or out of view with ``outside_unknown``
    """
    H, W = codes.shape
    S = heights.shape[0]
    last = S - n_above - 1
    k_min = max(k_min, n_below)
    lens = _lens(K, dist)
    fx = lens[0]
    r02, r12, r22 = R[0, 2], R[1, 2], R[2, 2]
    label = np.zeros(S, dtype=np.uint8)
    us = np.zeros(S)
    vs = np.zeros(S)
    wt = np.ones(S)
    weighted = False                                        # wt holds a weighted particle's lengths
    for i in range(xy.shape[0]):
        box = _box(boxes, which[i])
        me = mes[which[i]]
        ps = px_scale[which[i]]
        hb = 0                                              # hidden samples from the bottom up so far
        depth = math.hypot(xy[i, 0] - centre[0], xy[i, 1] - centre[1])
        # Camera-frame coordinates of the floor point; the column is linear in z.
        b0 = R[0, 0] * xy[i, 0] + R[0, 1] * xy[i, 1] + t[0]
        b1 = R[1, 0] * xy[i, 0] + R[1, 1] * xy[i, 1] + t[1]
        b2 = R[2, 0] * xy[i, 0] + R[2, 1] * xy[i, 1] + t[2]
        s = False
        for k in range(S):
            z = heights[k]
            cz = b2 + r22 * z
            u, v = _cam_to_uv(b0 + r02 * z, b1 + r12 * z, cz, lens, has_dist)
            us[k] = u
            vs[k] = v
            lab = _OUT_OF_VIEW                              # until a pixel in the image is read
            iv = _nearest(v, H)
            if iv >= 0:
                # The centre, then (cylinder) the pixels ``radius`` to the left and right at this
                # depth, until one reads object: object if any reads object, else no evidence if
                # any reads so — as a pixel in the box of a nearer object does (looked up last,
                # only if nothing else decides).
                iu0 = _nearest(u, W)
                lab, o0 = _read_line(codes, box, iu0, iv, lab)
                o1 = o2 = False
                iu1 = iu2 = -1
                if lab != 1 and radius > 0.0:
                    d = fx * radius / cz
                    if d > 0.0:
                        iu1 = _nearest(u - d, W)
                        lab, o1 = _read_line(codes, box, iu1, iv, lab)
                        if lab != 1:
                            iu2 = _nearest(u + d, W)
                            lab, o2 = _read_line(codes, box, iu2, iv, lab)
                if lab == 0 and (o0 or o1 or o2):
                    if ((o0 and _occluded(pairs, depths, me, iu0, iv, depth, margin))
                            or (o1 and _occluded(pairs, depths, me, iu1, iv, depth, margin))
                            or (o2 and _occluded(pairs, depths, me, iu2, iv, depth, margin))):
                        lab = _OCCLUDED
                if lab != _OUT_OF_VIEW:
                    s = True
            label[k] = lab
            # Hidden from the bottom up: occluded, or out of view when that is no evidence.
            if hb == k and (lab == _OCCLUDED or (lab == _OUT_OF_VIEW and outside_unknown)):
                hb = k + 1
        hidden[i] = hb
        if ps > 0.0:
            for k in range(S):
                wt[k] = _sample_length(us, vs, k) * ps
            weighted = True
        elif weighted:
            for k in range(S):
                wt[k] = 1.0
            weighted = False
        c = 0
        for k in range(n_below, last + 1):
            if label[k] == 1 or label[k] == 2 or label[k] == _OCCLUDED:
                c += 1
        # The samples below ``k_lo`` of the particle's filter read no evidence.
        for k in range(min(k_lo[which[i]], S)):
            label[k] = 2
        base = 0.0
        for k in range(n_below):
            if label[k] == 1:
                base += below * wt[k]
        # Ring above the top: the weight of the ``n_above`` samples above index k that read object.
        ring = 0.0
        for k in range(k_min + 1, min(k_min + n_above, S - 1) + 1):
            if label[k] == 1:
                ring += wt[k]
        run = base
        best = -1e300
        kbest = k_min
        for k in range(n_below, last + 1):
            lab = label[k]
            if lab == 1:
                run += on * wt[k]
            elif lab == 0 or (lab == _OUT_OF_VIEW and not outside_unknown):
                run += off * wt[k]
            if k >= k_min:
                if k > k_min and n_above > 0:
                    # Slide the ring up by one sample: k leaves it, k + n_above enters.
                    if label[k] == 1:
                        ring -= wt[k]
                    if k + n_above < S and label[k + n_above] == 1:
                        ring += wt[k + n_above]
                score = run + ring * below
                if top_sigma > 0.0:
                    e = (heights[k] - tops[i]) / top_sigma
                    score -= 0.5 * e * e
                if score > best:
                    best = score
                    kbest = k
        counts[i] = c
        ratio[i] = best
        top[i] = kbest
        seen[i] = s


@njit(cache=True, inline="always")
def _sample_length(us, vs, k):
    """Image length (pixels) a column sample stands for: half the distance between its neighbours'
    projections (one neighbour at the ends); 0 where a projection is undefined."""
    S = us.shape[0]
    lo = k - 1 if k > 0 else k
    hi = k + 1 if k < S - 1 else k
    if hi == lo:
        return 0.0
    du = us[hi] - us[lo]
    dv = vs[hi] - vs[lo]
    if not (du == du and dv == dv):
        return 0.0
    return math.sqrt(du * du + dv * dv) / (hi - lo)


@njit(cache=True)
def point_values(xyz: np.ndarray, R: np.ndarray, t: np.ndarray, K: np.ndarray, dist: np.ndarray,
                 has_dist: bool, F: np.ndarray, owner: np.ndarray, boxes: np.ndarray, which: np.ndarray,
                 values: np.ndarray, seen: np.ndarray) -> None:
    """Point likelihood π_i = F(u, v) at each particle's own projection (eq. 7), in place.

    Parameters
    ----------
    xyz : (N, 3) float64, metres
    F : (H, W) float32 — background difference with ``F ≤ γ`` set to 0 (:func:`thresholded_difference`)
    owner, boxes, which : as in :func:`column_counts`
    values : (N,) float64 — out: F at the particle, 0 outside the image or in another object's box
    seen : (N,) bool — out: the particle projects into the image
    """
    H, W = F.shape
    lens = _lens(K, dist)
    for i in range(xyz.shape[0]):
        iu, iv = _to_pixel(xyz[i, 0], xyz[i, 1], xyz[i, 2], R, t, lens, has_dist, W, H)
        values[i] = 0.0
        seen[i] = iu >= 0
        if iu >= 0 and not _others(owner[iv, iu], _box(boxes, which[i]), iu, iv):
            values[i] = F[iv, iu]


def top_edge_offsets(step: float, samples: int) -> np.ndarray:
    """(2·samples,) float64, metres: the top-edge sample heights relative to a particle's top,
    ``−step, −2·step, …`` (on the object) then ``step, 2·step, …`` (over it)."""
    steps = float(step) * np.arange(1, int(samples) + 1)
    return np.concatenate([-steps, steps])


@njit(cache=True)
def top_edge_terms(xy: np.ndarray, tops: np.ndarray, offsets: np.ndarray, weight: float, out: np.ndarray,
                   R: np.ndarray, t: np.ndarray, K: np.ndarray, dist: np.ndarray, has_dist: bool, codes: np.ndarray,
                   boxes: np.ndarray, which: np.ndarray, pairs: np.ndarray, depths: np.ndarray, mes: np.ndarray,
                   centre: np.ndarray, margin: float, on: float, off: float) -> None:
    """Log-ratio of the object's top edge at each particle's own height, added to ``out`` in place.

    The column reads its top on the ``dz`` grid (0.1 m: 5–10 pixels at 3–6 m); these samples read it
    at the particle's own height ``tops[i]``, which the particle carries from frame to frame. Where
    that height has settled on the object's, the top edge tells depth along the line of sight, and
    a walker's head, unlike the feet, does not move with the stride. Each sample is read as a
    column sample on the particle's axis is (:func:`column_counts`): in another object's box it
    reads background, or no evidence if that object is nearer by more than ``margin``.

    Parameters
    ----------
    xy : (N, ≥ 2) float64, metres — particles' floor positions (columns 0, 1)
    tops : (N,) float64, metres — the particles' object heights
    offsets : (E,) float64, metres — sample heights relative to the top: those below 0 are on the
        object (``on`` if they read object, ``off`` if background), those above it over it (``−on``
        if they read object, nothing if background); a sample out of view reads no evidence
    weight : float — multiplies the sum of the terms
    out : (N,) float64 — in/out: the terms are added
    R, t, K, dist, has_dist, codes, boxes, which, pairs, depths, mes, centre, margin, on, off :
        as in :func:`column_counts` (:meth:`CameraLikelihood.column_args` gives them)
    """
    H, W = codes.shape
    lens = _lens(K, dist)
    for i in range(xy.shape[0]):
        box = _box(boxes, which[i])
        me = mes[which[i]]
        depth = math.hypot(xy[i, 0] - centre[0], xy[i, 1] - centre[1])
        s = 0.0
        for j in range(offsets.shape[0]):
            iu, iv = _to_pixel(xy[i, 0], xy[i, 1], tops[i] + offsets[j], R, t, lens, has_dist, W, H)
            if iu < 0:
                continue                                    # out of view: no evidence
            lab, other = _read_line(codes, box, iu, iv, _OUT_OF_VIEW)
            if other and _occluded(pairs, depths, me, iu, iv, depth, margin):
                continue                                    # behind a nearer object: no evidence
            if offsets[j] < 0.0:
                if lab == 1:
                    s += on
                elif lab == 0:
                    s += off
            elif lab == 1:
                s -= on
        out[i] += weight * s


@njit(cache=True)
def box_pixels(xy: np.ndarray, widths: np.ndarray, heights: np.ndarray, margin: float, depth: float,
               R: np.ndarray, t: np.ndarray, K: np.ndarray, dist: np.ndarray, has_dist: bool, centre: np.ndarray,
               floor_direction: np.ndarray, W: int, H: int, out: np.ndarray) -> None:
    """Pixel boxes of objects standing at ``xy`` (K, 2), in place: the kernel of
    :func:`~worldtrack.trackers.particle.image_boxes` (see there; tested equal to it).

    Parameters
    ----------
    xy : (K, 2) float64, metres; widths, heights : (K,) float64, metres
    margin, depth : float, metres
    R, t, K, dist, has_dist : the camera, as in :func:`column_counts`
    centre : (2,) float64 — the camera's foot point; floor_direction : (2,) float64 — its
        :attr:`~worldtrack.geometry.camera.Camera.floor_direction`
    W, H : int — image size
    out : (K, 4) int64 — out: ``(u0, u1, v0, v1)``, all −1 where the box is empty (out of view)
    """
    lens = _lens(K, dist)
    shifts = (0.0, -depth, depth)
    for i in range(xy.shape[0]):
        # The line of sight on the floor (as Camera.floor_rays) and across it.
        ax, ay = _floor_unit(xy[i, 0], xy[i, 1], centre, floor_direction)
        hw = 0.5 * widths[i] + margin
        lo_u, lo_v, hi_u, hi_v = np.inf, np.inf, -np.inf, -np.inf
        for a in range(3 if depth > 0.0 else 1):
            for side in (-1.0, 1.0):
                px = xy[i, 0] + shifts[a] * ax + side * hw * -ay
                py = xy[i, 1] + shifts[a] * ay + side * hw * ax
                for pz in (-margin, heights[i] + margin):
                    u, v = _cam_to_uv(R[0, 0] * px + R[0, 1] * py + R[0, 2] * pz + t[0],
                                      R[1, 0] * px + R[1, 1] * py + R[1, 2] * pz + t[1],
                                      R[2, 0] * px + R[2, 1] * py + R[2, 2] * pz + t[2], lens, has_dist)
                    if math.isfinite(u) and math.isfinite(v):
                        lo_u, hi_u = min(lo_u, u), max(hi_u, u)
                        lo_v, hi_v = min(lo_v, v), max(hi_v, v)
        # Clipped to the image: a box wholly outside it (or with no corner in front of the
        # camera) ends up empty.
        u0 = min(max(np.floor(lo_u + 0.5), 0.0), W)
        v0 = min(max(np.floor(lo_v + 0.5), 0.0), H)
        u1 = min(max(np.floor(hi_u + 0.5) + 1.0, 0.0), W)
        v1 = min(max(np.floor(hi_v + 0.5) + 1.0, 0.0), H)
        if u0 < u1 and v0 < v1:
            out[i, 0], out[i, 1], out[i, 2], out[i, 3] = int(u0), int(u1), int(v0), int(v1)
        else:
            out[i, 0], out[i, 1], out[i, 2], out[i, 3] = -1, -1, -1, -1


@njit(cache=True, inline="always")
def _floor_unit(x, y, centre, floor_direction):
    """Unit floor vector (a_x, a_y) from the camera's foot point ``centre`` towards (x, y); the
    camera's ``floor_direction`` within 1e-9 m of it (:meth:`Camera.floor_rays`' ``along``)."""
    dx = x - centre[0]
    dy = y - centre[1]
    n = math.hypot(dx, dy)
    if n > 1e-9:
        return dx / n, dy / n
    return floor_direction[0], floor_direction[1]


@njit(cache=True)
def floor_along(xy: np.ndarray, centre: np.ndarray, floor_direction: np.ndarray, out: np.ndarray) -> None:
    """The camera's lines of sight on the floor through ``xy`` (N, 2), metres, in place: ``out``
    (N, 2) unit vectors from the foot point ``centre`` (2,) towards the points, ``floor_direction``
    (2,) within 1e-9 m of it — :meth:`Camera.floor_rays`' ``along``, the same arithmetic (tested
    equal)."""
    for i in range(xy.shape[0]):
        out[i, 0], out[i, 1] = _floor_unit(xy[i, 0], xy[i, 1], centre, floor_direction)


@njit(cache=True)
def floor_distances(xy: np.ndarray, centre: np.ndarray, out: np.ndarray) -> None:
    """``out`` (N,), in place: the floor distances of ``xy`` (N, 2) from ``centre`` (2,), metres —
    :meth:`Camera.floor_rays`' ``distance`` (``np.hypot``: the same C ``hypot``; tested equal)."""
    for i in range(xy.shape[0]):
        out[i] = math.hypot(xy[i, 0] - centre[0], xy[i, 1] - centre[1])


@njit(cache=True)
def toward_camera(xy: np.ndarray, offset: float, centre: np.ndarray, floor_direction: np.ndarray,
                  out: np.ndarray) -> None:
    """``xy − offset·along`` (N, 2), metres, in place: the floor points ``offset`` m nearer to the
    camera along its lines of sight (:func:`floor_along`); tested equal to the NumPy expression."""
    for i in range(xy.shape[0]):
        ax, ay = _floor_unit(xy[i, 0], xy[i, 1], centre, floor_direction)
        out[i, 0] = xy[i, 0] - offset * ax
        out[i, 1] = xy[i, 1] - offset * ay


@njit(cache=True)
def columns_beside(xy: np.ndarray, offset: float, spread: np.ndarray, centre: np.ndarray,
                   floor_direction: np.ndarray, out: np.ndarray) -> None:
    """``out`` (3K, 2), in place: per point of ``xy`` (K, 2), metres, ``c`` = the point moved ``offset``
    nearer to the camera (:func:`toward_camera`; the point itself for ``offset ≤ 0``), then
    ``c ± spread·(−a_y, a_x)`` with ``a`` the line of sight through ``c`` (:func:`floor_along`) —
    the arithmetic of :func:`columns_beside_reference`."""
    for i in range(xy.shape[0]):
        x, y = xy[i, 0], xy[i, 1]
        if offset > 0.0:
            ax, ay = _floor_unit(x, y, centre, floor_direction)
            x, y = x - offset * ax, y - offset * ay
        ax, ay = _floor_unit(x, y, centre, floor_direction)
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


@njit(cache=True)
def boxes_apart(boxes: np.ndarray) -> np.ndarray:
    """(K,) bool: which of ``boxes`` (K, 4) int ``(u0, u1, v0, v1)`` (rows with ``u0 < 0``: none) exist
    and overlap no other existing box (a positive intersection) — what ``_overlaps`` (above 0 off
    the diagonal) tells, with integers."""
    k = boxes.shape[0]
    out = np.zeros(k, dtype=np.bool_)
    for i in range(k):
        if boxes[i, 0] < 0:
            continue
        alone = True
        for j in range(k):
            if j != i and boxes[j, 0] >= 0:
                w = min(boxes[i, 1], boxes[j, 1]) - max(boxes[i, 0], boxes[j, 0])
                h = min(boxes[i, 3], boxes[j, 3]) - max(boxes[i, 2], boxes[j, 2])
                if w > 0 and h > 0:
                    alone = False
                    break
        out[i] = alone
    return out


@njit(cache=True)
def boxes_on_one_object(boxes: np.ndarray, min_overlap: float) -> np.ndarray:
    """(K, K) bool, True above the diagonal for pairs of objects whose boxes ``boxes`` (C, K, 4) int
    ``(u0, u1, v0, v1)`` (rows with ``u0 < 0``: none) in C cameras overlap by at least ``min_overlap``
    (intersection over the smaller box) in every camera that sees both, and some camera sees both —
    the arithmetic of :func:`boxes_on_one_object_reference`."""
    c, k = boxes.shape[0], boxes.shape[1]
    out = np.zeros((k, k), dtype=np.bool_)
    for i in range(k):
        for j in range(i + 1, k):
            both = False
            apart = False
            for cam in range(c):
                a, b = boxes[cam, i], boxes[cam, j]
                if a[0] < 0 or b[0] < 0:
                    continue
                both = True
                w = min(a[1], b[1]) - max(a[0], b[0])
                h = min(a[3], b[3]) - max(a[2], b[2])
                inter = float(w * h) if w > 0 and h > 0 else 0.0
                if not inter / float(min((a[1] - a[0]) * (a[3] - a[2]), (b[1] - b[0]) * (b[3] - b[2]))) >= min_overlap:
                    apart = True
            out[i, j] = both and not apart
    return out


def boxes_on_one_object_reference(boxes: Sequence[Sequence], min_overlap: float) -> np.ndarray:
    """:func:`boxes_on_one_object` of box lists (per camera, K boxes or None) by the tracker's former
    NumPy code (intersection over the smaller box of every pair, NaN where either is missing)."""
    ov = []
    for cam in boxes:
        b = np.array([(np.nan,) * 4 if x is None else x for x in cam], dtype=float).reshape(-1, 4)
        w = np.minimum(b[:, None, 1], b[None, :, 1]) - np.maximum(b[:, None, 0], b[None, :, 0])
        h = np.minimum(b[:, None, 3], b[None, :, 3]) - np.maximum(b[:, None, 2], b[None, :, 2])
        area = (b[:, 1] - b[:, 0]) * (b[:, 3] - b[:, 2])
        with np.errstate(invalid="ignore"):
            ov.append(np.where((w > 0) & (h > 0), w * h, 0.0) / np.minimum(area[:, None], area[None, :]))
    ov = np.array(ov)
    both = ~np.isnan(ov)
    apart = both & ~(ov >= min_overlap)
    return np.triu(both.any(axis=0) & ~apart.any(axis=0), 1)


@njit(cache=True)
def add_camera(seen: np.ndarray, lv: np.ndarray, penalty: np.ndarray, weight: float, col_h: np.ndarray,
               ok: np.ndarray, logpi: np.ndarray, likely: np.ndarray, n_seen: np.ndarray, col: np.ndarray) -> None:
    """One camera's share of a likelihood summed over cameras, in place (N particles):
    ``logpi += lv + weight·penalty`` where the camera sees the particle (``+ 0`` elsewhere; no
    penalty term when ``penalty`` is empty), ``likely &= ok | ~seen``, ``n_seen += seen``,
    ``col += col_h`` where seen. The arithmetic of :func:`add_camera_reference`, one pass."""
    pen = penalty.shape[0] > 0
    for i in range(seen.shape[0]):
        s = seen[i]
        v = lv[i]
        if pen:
            v = v + weight * penalty[i]
        logpi[i] = logpi[i] + (v if s else 0.0)
        col[i] = col[i] + (col_h[i] if s else 0.0)
        likely[i] = likely[i] and (ok[i] or not s)
        n_seen[i] += s


def add_camera_reference(seen, lv, penalty, weight, col_h, ok, logpi, likely, n_seen, col) -> None:
    """:func:`add_camera` as NumPy expressions (the tracker's former code), in place."""
    if len(penalty):
        lv = lv + weight * penalty
    logpi += np.where(seen, lv, 0.0)
    col += np.where(seen, col_h, 0.0)
    likely &= ok | ~seen
    n_seen += seen


# ---------------------------------------------------------------------------- NumPy references

def read_codes_reference(hit: np.ndarray, owner: np.ndarray) -> np.ndarray:
    """:func:`read_codes` in NumPy."""
    label = np.where(hit <= 2, hit, 0).astype(np.uint8)
    return label | (np.minimum(owner, 63).astype(np.uint8) << 2)


def occluder_layers_reference(shape: tuple[int, int], boxes, depths) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`occluder_layers` as plain layers ``(near1, id1, near2)``: the boxes taken nearest first
    (the earlier one first among equal depths; boxes of NaN or infinite depth never), each pixel keeps
    the first two that cover it."""
    near1, near2 = np.full(shape, np.inf), np.full(shape, np.inf)
    id1 = np.full(shape, -1, dtype=np.int32)
    given = [k for k, b in enumerate(boxes) if b is not None and float(depths[k]) < math.inf]
    for k in sorted(given, key=lambda k: float(depths[k])):      # sorted() is stable
        u0, u1, v0, v1 = boxes[k]
        first = np.zeros(shape, dtype=bool)
        first[v0:v1, u0:u1] = True
        second = first & (id1 >= 0) & np.isinf(near2)
        first &= id1 < 0
        near1[first], id1[first] = depths[k], k
        near2[second] = depths[k]
    return near1, id1, near2


def column_points(xy: np.ndarray, heights: np.ndarray) -> np.ndarray:
    """(N, S, 3) world points of vertical columns: floor positions ``xy`` (N, 2) at ``heights`` (S,), metres."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    heights = np.asarray(heights, dtype=float)
    pts = np.empty((len(xy), len(heights), 3))
    pts[:, :, :2] = xy[:, None, :]
    pts[:, :, 2] = heights[None, :]
    return pts


def _pixels(camera: Camera, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Nearest pixel (iu, iv) of world points (..., 3) and whether they fall in the image."""
    uv = camera.project(points)
    inside = camera.in_image(uv) & np.isfinite(uv).all(axis=-1)
    iu = np.where(inside, np.floor(np.nan_to_num(uv[..., 0]) + 0.5), 0).astype(np.int64)
    iv = np.where(inside, np.floor(np.nan_to_num(uv[..., 1]) + 0.5), 0).astype(np.int64)
    return iu, iv, inside


def _readable(owner: np.ndarray | None, boxes: np.ndarray, iu: np.ndarray, iv: np.ndarray) -> np.ndarray:
    """False where a pixel lies in another object's box; ``boxes`` (N, 4) is the own box of the
    particle each row of ``iu, iv`` (N, ...) belongs to."""
    if owner is None:
        return np.ones(iu.shape, dtype=bool)
    b = boxes.reshape((len(boxes),) + (1,) * (iu.ndim - 1) + (4,))
    own = (iu >= b[..., 0]) & (iu < b[..., 1]) & (iv >= b[..., 2]) & (iv < b[..., 3])
    return owner[iv, iu].astype(int) <= own


def column_counts_reference(camera: Camera, hit: np.ndarray, xy: np.ndarray, heights: np.ndarray,
                            on: float = 1.0, off: float = -1.0, k_min: int = 0, radius: float = 0.0,
                            below: float = 0.0, n_below: int = 0, n_above: int = 0,
                            owner: np.ndarray | None = None, box=None, tops: np.ndarray | None = None,
                            top_sigma: float = 0.0, px_scale: float | Sequence[float] = 0.0,
                            occluders: Occluders | None = None,
                            me: int | Sequence[int] = -1, margin: float = 0.0, which: np.ndarray | None = None,
                            outside_unknown: bool = False, k_lo: int | Sequence[int] = 0,
                            return_hidden: bool = False):
    """:func:`column_counts` written plainly: every (particle, height) point through :meth:`Camera.project`.

    ``box``, ``me``, ``which``, ``px_scale``, ``outside_unknown``, ``k_lo`` and ``return_hidden`` as in
    :meth:`CameraLikelihood.column`.

    Returns
    -------
    counts : (N,) int64 — samples ``k·dz``, k = 0 … T, on ``F > γ`` (eq. 11)
    ratio : (N,) float — the best log-likelihood ratio
    top : (N,) int64 — index into ``heights`` of the best top
    seen : (N,) bool — some sample projects into the image
    hidden : (N,) int64, with ``return_hidden`` — how many lowest samples are hidden
    """
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    n, s = len(xy), len(heights)
    boxes, mes, which = filter_rows(box, me, which, n)
    own_box, own_index = boxes[which], mes[which][:, None]
    scale = pixel_scales(px_scale, len(boxes))[which][:, None]
    uv, depth = camera.project(column_points(xy, heights), return_depth=True)
    hits = np.zeros((n, s), dtype=bool)
    unsure = np.zeros((n, s), dtype=bool)
    seen = np.zeros(n, dtype=bool)
    in_view = np.zeros((n, s), dtype=bool)               # some pixel of the sample is in the image
    occluded = np.zeros((n, s), dtype=bool)              # some pixel in a nearer object's box
    offsets = [0.0] if radius <= 0 else [0.0, -1.0, 1.0]
    with np.errstate(divide="ignore", invalid="ignore"):
        d = np.where(depth > 1e-9, camera.K[0, 0] * radius / depth, 0.0)
    for o in offsets:
        uo = uv.copy()
        uo[..., 0] += o * d
        inside = camera.in_image(uo) & np.isfinite(uo).all(axis=-1)
        iu = np.where(inside, np.floor(np.nan_to_num(uo[..., 0]) + 0.5), 0).astype(np.int64)
        iv = np.where(inside, np.floor(np.nan_to_num(uo[..., 1]) + 0.5), 0).astype(np.int64)
        readable = inside & _readable(owner, own_box, iu, iv)
        hits |= readable & (hit[iv, iu] == 1)
        unsure |= readable & (hit[iv, iu] == 2)
        if occluders is not None and occluders.pairs.size:
            # In a nearer object's box: occluded, no evidence.
            particle_depth = camera.floor_rays(xy)[1][:, None]
            occluded |= inside & ~readable & (occluders.depth_for(own_index, iv, iu) < particle_depth - margin)
        seen |= inside.any(axis=1)
        in_view |= inside
    occluded &= ~hits & ~unsure
    unsure |= occluded
    unsure &= ~hits
    hid = occluded | (~in_view if outside_unknown else False)
    hidden = np.where(hid.all(axis=1), s, np.argmin(hid, axis=1))
    if outside_unknown:
        unsure |= ~in_view
    counts = ((hits | unsure) & in_view)[:, n_below:s - n_above].sum(axis=1).astype(np.int64)
    # The samples below each filter's k_lo read no evidence.
    cut = np.arange(s)[None, :] < _per_filter_int(k_lo, len(boxes))[which][:, None]
    hits, unsure = hits & ~cut, unsure | cut
    # Each sample stands for half the image distance between its neighbours (one at the ends).
    lo = np.maximum(np.arange(s) - 1, 0)
    hi = np.minimum(np.arange(s) + 1, s - 1)
    with np.errstate(invalid="ignore"):
        length = np.nan_to_num(np.hypot(*(uv[:, hi] - uv[:, lo]).transpose(2, 0, 1)) / (hi - lo), nan=0.0)
    weight = np.where(scale > 0, length * scale, 1.0)
    last = s - n_above                                   # one past the highest possible top
    terms = np.where(hits, on, np.where(unsure, 0.0, off)) * weight
    terms[:, :n_below] = np.where(hits[:, :n_below], below, 0.0) * weight[:, :n_below]
    run = np.cumsum(terms[:, :last], axis=1)
    # The ring above a top at index k: samples k + 1 … k + n_above that read object.
    ring = np.zeros_like(run)
    hit_weight = np.where(hits, weight, 0.0)
    for j in range(1, n_above + 1):
        ring += np.pad(hit_weight[:, j:last + j], ((0, 0), (0, max(0, last + j - s))))[:, :last]
    run = run + below * ring
    if top_sigma > 0:
        z = np.asarray(heights, dtype=float)[None, :last]
        run = run - 0.5 * ((z - np.asarray(tops, dtype=float)[:, None]) / top_sigma) ** 2
    run[:, :max(k_min, n_below)] = -np.inf
    top = np.argmax(run, axis=1)
    out = counts, run[np.arange(n), top], top, seen
    return out + (hidden,) if return_hidden else out


def point_values_reference(camera: Camera, F: np.ndarray, xyz: np.ndarray, owner: np.ndarray | None = None,
                           box=None, which: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """:func:`point_values` written plainly: F at each particle's projection, and ``seen``."""
    xyz = np.asarray(xyz, dtype=float).reshape(-1, 3)
    boxes, _, which = filter_rows(box, -1, which, len(xyz))
    iu, iv, inside = _pixels(camera, xyz)
    ok = inside & _readable(owner, boxes[which], iu, iv)
    return np.where(ok, F[iv, iu], 0.0).astype(float), inside


def top_edge_terms_reference(camera: Camera, hit: np.ndarray, xy: np.ndarray, tops: np.ndarray,
                             offsets: Sequence[float], on: float, off: float, weight: float = 1.0,
                             owner: np.ndarray | None = None, box=None, occluders: Occluders | None = None,
                             me: int | Sequence[int] = -1, margin: float = 0.0,
                             which: np.ndarray | None = None) -> np.ndarray:
    """:func:`top_edge_terms` written plainly: (N,) the weighted top-edge terms of each particle;
    ``owner``, ``box``, ``occluders``, ``me``, ``margin`` and ``which`` as in :meth:`CameraLikelihood.column`."""
    tops = np.asarray(tops, dtype=float)
    xy = np.asarray(xy, dtype=float).reshape(len(tops), -1)[:, :2]
    offsets = np.asarray(offsets, dtype=float)
    boxes, mes, which = filter_rows(box, me, which, len(xy))
    points = np.concatenate([np.broadcast_to(xy[:, None, :], (len(xy), len(offsets), 2)),
                             (tops[:, None] + offsets)[..., None]], axis=-1)
    iu, iv, inside = _pixels(camera, points)
    readable = _readable(owner, boxes[which], iu, iv)
    lab = np.where(readable, hit[iv, iu], 0)               # in another object's box: background
    lab = np.where(inside, lab, 2)
    if occluders is not None and occluders.pairs.size:
        nearer = occluders.depth_for(mes[which][:, None], iv, iu) < camera.floor_rays(xy)[1][:, None] - margin
        lab = np.where(inside & ~readable & nearer, 2, lab)
    below = offsets < 0
    terms = np.where(below, np.where(lab == 1, on, np.where(lab == 0, off, 0.0)), np.where(lab == 1, -on, 0.0))
    return weight * terms.sum(axis=1)


# ---------------------------------------------------------------------------- camera wrapper

class CameraLikelihood:
    """One camera's constants for the kernels (contiguous float64 arrays), built once.

    Parameters
    ----------
    camera : Camera
    """

    def __init__(self, camera: Camera):
        self.camera = camera
        self.R = np.ascontiguousarray(camera.R, dtype=np.float64)
        self.t = np.ascontiguousarray(camera.t, dtype=np.float64)
        self.K = np.ascontiguousarray(camera.K, dtype=np.float64)
        self.dist = np.ascontiguousarray(camera.dist, dtype=np.float64)
        self.has_dist = bool(camera.has_distortion)
        self.no_owner = np.zeros((camera.height, camera.width), dtype=np.uint8)
        self._codes: np.ndarray | None = None     # read_codes' output, reused call to call
        self.work: dict = {}                      # work arrays of compiled calls, kept call to call
        self.centre = np.ascontiguousarray(camera.centre[:2], dtype=np.float64)
        self.floor_direction = np.ascontiguousarray(camera.floor_direction, dtype=np.float64)

    def along(self, xy: np.ndarray) -> np.ndarray:
        """(N, 2) the camera's lines of sight on the floor through ``xy`` (N, 2), metres: the
        ``along`` of :meth:`Camera.floor_rays`, by the kernel :func:`floor_along`."""
        xy = np.ascontiguousarray(np.asarray(xy, dtype=np.float64).reshape(-1, 2))
        out = np.empty_like(xy)
        floor_along(xy, self.centre, self.floor_direction, out)
        return out

    def near_surface(self, xy: np.ndarray, offset: float) -> np.ndarray:
        """(N, 2) floor points ``offset`` m nearer to the camera than ``xy`` (N, 2) (or the first two
        columns of (N, ≥ 2)), metres, along its lines of sight: ``xy − offset·along``
        (:func:`toward_camera`)."""
        xy = np.asarray(xy, dtype=np.float64)
        if xy.ndim != 2 or xy.shape[1] < 2:
            xy = xy.reshape(-1, 2)
        out = np.empty((len(xy), 2))
        toward_camera(xy, float(offset), self.centre, self.floor_direction, out)
        return out

    def boxes(self, xy: np.ndarray, widths: np.ndarray, heights: np.ndarray, margin: float,
              depth: float = 0.0) -> list[tuple[int, int, int, int] | None]:
        """:func:`~worldtrack.trackers.particle.image_boxes` of objects at ``xy`` (K, 2) with
        ``widths, heights`` (K,) — by the kernel :func:`box_pixels`."""
        return [tuple(b) if b[0] >= 0 else None for b in self.box_array(xy, widths, heights, margin, depth).tolist()]

    def box_array(self, xy: np.ndarray, widths: np.ndarray, heights: np.ndarray, margin: float,
                  depth: float = 0.0) -> np.ndarray:
        """:meth:`boxes` as (K, 4) int64 ``(u0, u1, v0, v1)``, rows of −1 for no box."""
        xy = np.ascontiguousarray(np.asarray(xy, dtype=np.float64).reshape(-1, 2))
        k = len(xy)
        out = np.empty((k, 4), dtype=np.int64)
        box_pixels(xy, _per_object(widths, k), _per_object(heights, k), float(margin), float(depth), self.R, self.t,
                   self.K, self.dist, self.has_dist, self.centre, self.floor_direction, self.camera.width,
                   self.camera.height, out)
        return out

    def distances(self, xy: np.ndarray) -> np.ndarray:
        """(N,) the floor distances (m) of ``xy`` (N, 2) from the camera's foot point: :meth:`Camera.floor_rays`'
        ``distance``, by a kernel."""
        xy = np.ascontiguousarray(np.asarray(xy, dtype=np.float64).reshape(-1, 2))
        out = np.empty(len(xy))
        floor_distances(xy, self.centre, out)
        return out

    def beside(self, xy: np.ndarray, offset: float, spread: np.ndarray) -> np.ndarray:
        """(3K, 2) metres: for each of ``xy`` (K, 2), its column ``offset`` m nearer to the camera
        (as :meth:`near_surface`; ``xy`` itself for ``offset ≤ 0``) and the two ``spread`` (K,) m to
        either side of it across the line of sight through it, in that order (:func:`columns_beside`)."""
        xy = np.ascontiguousarray(np.asarray(xy, dtype=np.float64).reshape(-1, 2))
        out = np.empty((3 * len(xy), 2))
        columns_beside(xy, float(offset), np.ascontiguousarray(spread, dtype=np.float64), self.centre,
                       self.floor_direction, out)
        return out

    def column(self, hit: np.ndarray, xy: np.ndarray, heights: np.ndarray, on: float = 1.0, off: float = -1.0,
               k_min: int = 0, radius: float = 0.0, below: float = 0.0, n_below: int = 0, n_above: int = 0,
               owner: np.ndarray | None = None, box=None, tops: np.ndarray | None = None,
               top_sigma: float = 0.0, px_scale: float | Sequence[float] = 0.0,
               occluders: "Occluders | None" = None, me: int | Sequence[int] = -1, margin: float = 0.0,
               which: np.ndarray | None = None, outside_unknown: bool = False,
               k_lo: int | Sequence[int] = 0, return_hidden: bool = False) -> tuple[np.ndarray, ...]:
        """(counts, ratio, top, seen) of the height columns at ``xy`` (N, 2); see :func:`column_counts`.

        ``box`` is the filter's own box among those behind ``owner``; ``occluders``
        (:func:`occluder_layers` of those boxes) with ``me`` (the filter's index among them) and
        ``margin`` (m): samples behind a nearer object read as no evidence. The particles of
        several filters in one call: ``which`` (N,) int, each particle's filter 0 … F − 1, with
        ``box`` and ``me`` sequences of F (:func:`filter_rows`). ``px_scale``: one pixel-weight
        scale (1 / pixels, 0 = unweighted) for all particles or one per filter. ``outside_unknown``:
        samples out of the image are no evidence rather than background
        (``ParticleConfig.out_of_view``). ``k_lo``: for all particles or per filter, the samples
        ``heights[:k_lo]`` read no evidence in ``ratio``. ``return_hidden``: also return
        :func:`column_counts`' ``hidden`` (N,) int32, the number of lowest samples hidden."""
        xy = np.ascontiguousarray(xy, dtype=np.float64)
        n = len(xy)
        counts = np.empty(n, dtype=np.int32)
        ratio = np.empty(n, dtype=np.float64)
        top = np.empty(n, dtype=np.int32)
        seen = np.empty(n, dtype=np.bool_)
        hidden = np.empty(n, dtype=np.int32)
        column_counts(xy, *self.column_args(hit, n, heights, on, off, k_min, radius, below, n_below, n_above, owner,
                                            box, tops, top_sigma, px_scale, occluders, me, margin, which,
                                            outside_unknown, k_lo),
                      counts, ratio, top, seen, hidden)
        return (counts, ratio, top, seen, hidden) if return_hidden else (counts, ratio, top, seen)

    def column_args(self, hit: np.ndarray, n: int, heights: np.ndarray, on: float = 1.0, off: float = -1.0,
                    k_min: int = 0, radius: float = 0.0, below: float = 0.0, n_below: int = 0, n_above: int = 0,
                    owner: np.ndarray | None = None, box=None, tops: np.ndarray | None = None,
                    top_sigma: float = 0.0, px_scale: float | Sequence[float] = 0.0,
                    occluders: "Occluders | None" = None, me: int | Sequence[int] = -1, margin: float = 0.0,
                    which: np.ndarray | None = None, outside_unknown: bool = False,
                    k_lo: int | Sequence[int] = 0) -> tuple:
        """The arguments of :func:`column_counts` between ``xy`` and its outputs, for ``n`` particles
        read as :meth:`column` reads them (its parameters)."""
        boxes, mes, which = filter_rows(box, me, which, n)
        if owner is None:
            codes = hit                             # labels 0, 1, 2 are the codes of pixels in no box
        else:
            if self._codes is None or self._codes.shape != hit.shape:
                self._codes = np.empty(hit.shape, dtype=np.uint8)
            codes = read_codes(hit, owner, self._codes)
        occ = NO_OCCLUDERS if occluders is None else occluders
        return (np.ascontiguousarray(heights, dtype=np.float64), self.R, self.t, self.K, self.dist, self.has_dist,
                float(radius), codes, boxes, which, occ.pairs, occ.depths, mes, self.centre, float(margin),
                float(on), float(off), float(below), int(n_below), int(n_above), int(k_min),
                np.zeros(n) if tops is None else np.ascontiguousarray(tops, dtype=np.float64),
                float(top_sigma) if tops is not None else 0.0, pixel_scales(px_scale, len(boxes)),
                bool(outside_unknown), _per_filter_int(k_lo, len(boxes)))

    def top_edge(self, column_args: tuple, xy: np.ndarray, tops: np.ndarray, offsets: np.ndarray, weight: float,
                 out: np.ndarray) -> None:
        """Add ``weight`` times the top-edge terms (:func:`top_edge_terms`) of the particles ``xy``
        (N, ≥ 2) at heights ``tops`` (N,), metres, at ``offsets`` (E,) metres from them, to ``out`` (N,)
        in place, read as :meth:`column_args` ``column_args`` (for the same N particles) reads."""
        a = column_args
        top_edge_terms(np.ascontiguousarray(xy, dtype=np.float64), np.ascontiguousarray(tops, dtype=np.float64),
                       np.ascontiguousarray(offsets, dtype=np.float64), float(weight), out, *a[1:6], *a[7:17])

    def point(self, F: np.ndarray, xyz: np.ndarray, owner: np.ndarray | None = None,
              box=None, which: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(F values (N,) float64, seen (N,) bool) at the points ``xyz`` (N, 3) — eq. 7; ``box``
        and ``which`` as in :meth:`column`."""
        xyz = np.ascontiguousarray(xyz, dtype=np.float64)
        boxes, _, which = filter_rows(box, -1, which, len(xyz))
        values = np.empty(len(xyz), dtype=np.float64)
        seen = np.empty(len(xyz), dtype=np.bool_)
        point_values(xyz, self.R, self.t, self.K, self.dist, self.has_dist, F,
                     self.no_owner if owner is None else owner, boxes, which, values, seen)
        return values, seen
