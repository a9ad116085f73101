"""Connected components of a foreground mask, with their statistics."""

from __future__ import annotations

import cv2
import numpy as np


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

