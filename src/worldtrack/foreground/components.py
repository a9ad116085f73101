"""Connected components of a foreground mask, with their statistics."""

from __future__ import annotations

import cv2
import numpy as np
from numba import njit


def connected_components(mask: np.ndarray) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
    """8-connected components of a binary mask: ``cv2.connectedComponentsWithStats`` output.

    Uses Grana's block-based algorithm (``cv2.CCL_GRANA``) explicitly: with statistics it is
    about 2.5× faster than OpenCV's default choice on a 640×480 mask on one thread (0.7 vs
    1.9 ms, measured on this project's crowd frames) and gives identical labels and statistics.

    Parameters
    ----------
    mask : (H, W) uint8 — non-zero pixels are foreground

    Returns
    -------
    n : int — number of labels, background (label 0) included
    labels : (H, W) int32
    stats : (n, 5) int32 — x, y, width, height, area per label (``cv2.CC_STAT_*`` columns)
    centroids : (n, 2) float64 — (u, v) per label
    """
    return cv2.connectedComponentsWithStatsWithAlgorithm(mask, 8, cv2.CV_32S, cv2.CCL_GRANA)


def blobs(mask: np.ndarray, min_area: float, factor: int = 1) -> list[tuple[int, tuple[int, int, int, int], np.ndarray, np.ndarray]]:
    """The 8-connected blobs of ``mask`` with at least ``min_area`` pixels, each exact at full resolution.

    With ``factor`` > 1 the components are found on the mask shrunk ``factor`` times (a pixel of
    the small mask is set when any pixel of its block is), which is several
    times cheaper on a 640×480 frame; every blob's pixels, area, box and centroid are then read
    from the full-resolution mask. The only difference from ``factor = 1``: pieces closer than
    about ``factor`` pixels to each other are one blob.

    Parameters
    ----------
    mask : (H, W) uint8 — non-zero pixels are foreground
    min_area : float, pixels (full resolution)
    factor : int — 1 (exact labelling) or the shrink factor (at most 22: a block mean of one
        set pixel, 255 / factor², must still round to non-zero)

    Returns
    -------
    list of (area, (x0, y0, width, height), centroid (2,) (u, v) float64, blob (height, width) bool)
        — ``blob`` is the crop of the mask at the box holding the blob's own pixels
    """
    if factor <= 1:
        n, labels, stats, cent = connected_components(mask)
        out = []
        for j in range(1, n):
            x0, y0, w, h, area = (int(v) for v in stats[j])
            if area >= min_area:
                out.append((area, (x0, y0, w, h), cent[j], labels[y0:y0 + h, x0:x0 + w] == j))
        return out
    if factor > 22:
        raise ValueError(f"blobs: shrink factor must be at most 22, got {factor}")
    H, W = mask.shape
    # Zeros to a multiple of the factor (a partial block at the bottom or right is then a whole
    # one), and block means of 0/255: non-zero exactly when some pixel of the block is set.
    full = cv2.threshold(mask, 0, 255, cv2.THRESH_BINARY)[1]
    pad_v, pad_u = -H % factor, -W % factor
    if pad_v or pad_u:
        full = cv2.copyMakeBorder(full, 0, pad_v, 0, pad_u, cv2.BORDER_CONSTANT, value=0)
    small = cv2.resize(full, ((W + pad_u) // factor, (H + pad_v) // factor), interpolation=cv2.INTER_AREA)
    n, labels, stats, _ = connected_components(small)
    out = []
    for j in range(1, n):
        sx, sy, sw, sh, sarea = (int(v) for v in stats[j])
        if sarea * factor * factor < min_area:
            continue  # even every pixel of its blocks set would be too few
        x0, y0 = sx * factor, sy * factor
        own = np.repeat(np.repeat(labels[sy:sy + sh, sx:sx + sw] == j, factor, axis=0), factor, axis=1)
        own = own[:H - y0, :W - x0] & (mask[y0:y0 + sh * factor, x0:x0 + sw * factor] != 0)
        area = int(np.count_nonzero(own))
        if area < min_area:
            continue
        rows = np.flatnonzero(own.any(axis=1))
        cols = np.flatnonzero(own.any(axis=0))
        r0, r1, c0, c1 = rows[0], rows[-1] + 1, cols[0], cols[-1] + 1
        crop = own[r0:r1, c0:c1]
        vs, us = np.nonzero(crop)
        centroid = np.array([us.mean() + x0 + c0, vs.mean() + y0 + r0])
        out.append((area, (x0 + int(c0), y0 + int(r0), int(c1 - c0), int(r1 - r0)), centroid, crop))
    return out



@njit(cache=True)
def blob_extent(blob: np.ndarray, u0: int, v0: int, cu: float, cv: float, dx: float, dy: float,
                end_divisor: int) -> tuple[float, float, float, float, float, float]:
    """How far a blob reaches along a direction and across it, and where its two ends lie across.

    Parameters
    ----------
    blob : (h, w) bool — the blob's pixels, its top-left pixel at (u0, v0) of the image
    cu, cv : float — the reference point (the blob's centroid), pixels
    dx, dy : float — unit image direction "along"; "across" is (−dy, dx)
    end_divisor : int — each end is the ``max(1, n // end_divisor)`` pixels lowest / highest along
        the direction; ties at the cut are taken in row-major order (a stable sort's)

    Returns
    -------
    along_min, along_max, across_min, across_max : float — extremes of the pixels' coordinates
        relative to (cu, cv), pixels (NaN for an empty blob)
    across_first, across_last : float — mean across-coordinate of the pixels at the low and the
        high end along the direction
    """
    h, w = blob.shape
    n = 0
    for r in range(h):
        for c in range(w):
            if blob[r, c]:
                n += 1
    if n == 0:
        return np.nan, np.nan, np.nan, np.nan, np.nan, np.nan
    along = np.empty(n)
    across = np.empty(n)
    i = 0
    for r in range(h):
        for c in range(w):
            if blob[r, c]:
                du = (u0 + c) - cu
                dv = (v0 + r) - cv
                along[i] = du * dx + dv * dy
                across[i] = du * -dy + dv * dx
                i += 1
    n_end = max(1, n // end_divisor)
    means = np.zeros(2)
    for e in range(2):
        total = 0.0
        for i in extreme_indices(along, n_end, e == 0):
            total += across[i]
        means[e] = total / n_end
    return along.min(), along.max(), across.min(), across.max(), means[0], means[1]


@njit(cache=True)
def extreme_indices(values: np.ndarray, count: int, lowest: bool) -> np.ndarray:
    """Indices of the ``count`` lowest (or highest) of ``values`` (1 ≤ count ≤ len): those strictly
    beyond the cut in index order, then the ties at the cut in index order until ``count`` — the
    set a stable sort puts first (or, for the ties, last), found by one selection (O(n))."""
    n = values.shape[0]
    cut = np.partition(values, count - 1)[count - 1] if lowest else np.partition(values, n - count)[n - count]
    sign = 1.0 if lowest else -1.0
    out = np.empty(count, np.int64)
    taken = 0
    for i in range(n):
        if sign * values[i] < sign * cut:
            out[taken] = i
            taken += 1
    for i in range(n):
        if taken >= count:
            break
        if values[i] == cut:
            out[taken] = i
            taken += 1
    return out


def blob_extent_reference(blob: np.ndarray, u0: int, v0: int, cu: float, cv: float, dx: float, dy: float,
                          end_divisor: int) -> tuple[float, float, float, float, float, float]:
    """Plain NumPy version of :func:`blob_extent` (a stable sort instead of selection)."""
    vs, us = np.nonzero(blob)
    if len(us) == 0:
        return (np.nan,) * 6
    du, dv = us + u0 - cu, vs + v0 - cv
    along = du * dx + dv * dy
    across = du * -dy + dv * dx
    n = len(along)
    n_end = max(1, n // end_divisor)
    order = np.argsort(along, kind="stable")
    low = order[:n_end]
    cut = along[order[n - n_end]]
    above = np.flatnonzero(along > cut)
    high = np.concatenate([above, np.flatnonzero(along == cut)[:n_end - len(above)]])
    return (along.min(), along.max(), across.min(), across.max(), across[low].mean(), across[high].mean())
