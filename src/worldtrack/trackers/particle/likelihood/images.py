"""The per-frame layers every likelihood kernel reads beside the labels: who owns a pixel, who hides it.

Explaining away (worldtrack's, not in seed 004): a pixel inside another tracked object's image box
reads as background, so a filter cannot take over its neighbour's pixels and a detection filter sees
only what no track explains; where that object stands nearer to the camera the pixel reads as
occluded (no evidence). Per camera and frame:

* :func:`owner_image` — how many object boxes cover each pixel;
* :func:`read_codes` — the labels and the box counts packed into one byte per pixel (what the
  column kernel reads);
* :func:`occluder_layers` — the two nearest boxes over each pixel (:class:`Occluders`).

Each has a NumPy reference (``*_reference``) that the tests compare it with.

>>> owner_image((2, 3), [(0, 2, 0, 1), None, (1, 3, 0, 2)]).tolist()
[[1, 2, 1], [0, 1, 1]]
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

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


__all__ = ["NO_OCCLUDERS", "Occluders", "occluder_layers", "occluder_layers_reference", "owner_image",
           "owner_image_reference", "read_codes", "read_codes_reference"]
