"""Silhouettes (seed 001 §2.3, Fig. 6): each candidate's points back in the image, at full resolution.

The plan-view step labels every ``stride``-th pixel. Each label is spread over its pixel block,
the holes a stereo matcher leaves on plain clothing are closed (a morphological closing of about
two blocks), and pixels whose own depth puts them well in front of or behind the candidate (the
background seen past an arm, a nearer person) are removed. Nearer candidates are drawn last, so
they keep the pixels they hide.

>>> import numpy as np
>>> labels = np.zeros((3, 4), np.int32); labels[1, 1:3] = 1
>>> depth = np.full((6, 8), 2.0, np.float32)
>>> sil = silhouettes(labels, 2, depth, np.array([2.0]))
>>> int((sil == 1).sum())                                 # the two 2×2 blocks
8
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy import ndimage


def upsample_labels(labels: np.ndarray, stride: int, shape: tuple[int, int]) -> np.ndarray:
    """(H, W) int32: the label of every pixel's block (block (i, j) covers rows i·s…, columns j·s…)."""
    H, W = shape
    s = int(stride)
    if s == 1:
        return labels[:H, :W].astype(np.int32)
    h, w = labels.shape
    big = cv2.resize(labels.astype(np.int32), (w * s, h * s), interpolation=cv2.INTER_NEAREST)
    out = np.zeros((H, W), np.int32)
    hh, ww = min(H, h * s), min(W, w * s)
    out[:hh, :ww] = big[:hh, :ww]
    return out


def silhouettes(labels: np.ndarray, stride: int, depth: np.ndarray, cand_depth: np.ndarray,
                depth_tolerance: float = 0.5) -> np.ndarray:
    """Full-resolution silhouettes of the candidates.

    Parameters
    ----------
    labels : (h, w) int32 on the strided grid (``Candidates.labels``)
    stride : int
    depth : (H, W) float32, metres, 0 = no measurement
    cand_depth : (N,) each candidate's median depth, metres (nearest first)
    depth_tolerance : metres; a measured pixel further than this from its candidate's depth is not its

    Returns
    -------
    (H, W) int32 — 0 background, i + 1 a pixel of candidate i.
    """
    H, W = depth.shape
    n = len(cand_depth)
    out = np.zeros((H, W), np.int32)
    if n == 0:
        return out
    s = int(stride)
    k = 2 * s + 1
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k))
    full = upsample_labels(labels, s, (H, W))
    measured = depth > 0
    boxes = ndimage.find_objects(labels, max_label=n)
    for i in range(n - 1, -1, -1):                 # far to near: nearer ones overwrite
        if boxes[i] is None:
            continue
        rows, cols = boxes[i]
        y0, y1 = max(rows.start * s - k, 0), min(rows.stop * s + k, H)
        x0, x1 = max(cols.start * s - k, 0), min(cols.stop * s + k, W)
        mask = (full[y0:y1, x0:x1] == i + 1).astype(np.uint8)
        box = cv2.morphologyEx(mask, cv2.MORPH_CLOSE, kernel).astype(bool)
        d = depth[y0:y1, x0:x1]
        far = measured[y0:y1, x0:x1] & (np.abs(d - cand_depth[i]) > depth_tolerance)
        region = out[y0:y1, x0:x1]
        region[box & ~far] = i + 1
    return out


def box_silhouettes(shape: tuple[int, int], boxes: np.ndarray, width_share: float = 0.6,
                    rows: tuple[float, float] = (0.12, 0.95)) -> np.ndarray:
    """Silhouettes from image boxes, for candidates given by a detector or by ground truth.

    Each box ``(left, top, width, height)`` (pixels) gives its central ``width_share`` of columns
    between the fractions ``rows`` of its height (the head and the background beside the body
    left out). Boxes reaching lower in the image are nearer on a flat floor and drawn last, so a
    nearer person keeps the pixels they hide.

    >>> sil = box_silhouettes((10, 10), np.array([[0, 0, 10, 10], [5, 2, 4, 8]], float))
    >>> sorted(np.unique(sil).tolist())
    [0, 1, 2]
    """
    H, W = shape
    out = np.zeros((H, W), np.int32)
    b = np.asarray(boxes, dtype=float).reshape(-1, 4)
    for i in np.argsort(b[:, 1] + b[:, 3], kind="stable"):
        left, top, w, h = b[i]
        x0 = int(np.clip(round(left + w * (1 - width_share) / 2), 0, W))
        x1 = int(np.clip(round(left + w * (1 + width_share) / 2), 0, W))
        y0 = int(np.clip(round(top + h * rows[0]), 0, H))
        y1 = int(np.clip(round(top + h * rows[1]), 0, H))
        out[y0:y1, x0:x1] = i + 1
    return out


def person_box(camera, xy, height: float = 1.7, width: float = 0.45) -> tuple[int, int, int, int] | None:
    """Pixel box ``(u0, v0, u1, v1)`` (clipped to the image) of a person standing at ``xy`` (m), or None
    when they are behind the camera or out of view."""
    x, y = float(xy[0]), float(xy[1])
    ray = np.array([x, y]) - camera.centre[:2]
    side = np.array([-ray[1], ray[0]]) / max(np.linalg.norm(ray), 1e-9) * width / 2
    pts = np.array([[x + sx * side[0], y + sx * side[1], z] for sx in (-1, 1) for z in (0.0, height)])
    uv, depth = camera.project(pts, return_depth=True)
    if np.any(depth <= 0.05) or not np.all(np.isfinite(uv)):
        return None
    u0, v0 = np.floor(uv.min(axis=0)).astype(int)
    u1, v1 = np.ceil(uv.max(axis=0)).astype(int) + 1
    u0, u1 = max(u0, 0), min(u1, camera.width)
    v0, v1 = max(v0, 0), min(v1, camera.height)
    if u1 <= u0 or v1 <= v0:
        return None
    return int(u0), int(v0), int(u1), int(v1)


def covering(silhouettes_: np.ndarray, n: int, box: tuple[int, int, int, int] | None) -> np.ndarray:
    """(n,) share of ``box`` that each candidate's silhouette covers (zeros without a box).

    >>> sil = np.zeros((4, 4), np.int32); sil[:, :2] = 1
    >>> covering(sil, 1, (0, 0, 4, 4)).tolist()
    [0.5]
    """
    if box is None or n == 0:
        return np.zeros(n)
    u0, v0, u1, v1 = box
    patch = silhouettes_[v0:v1, u0:u1]
    return np.bincount(patch.ravel(), minlength=n + 1)[1:n + 1] / max(patch.size, 1)
