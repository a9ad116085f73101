"""When the feet anchor must not fire: another person's feet, an obstacle's edge, a wrong height (opt-in).

The feet anchor (:mod:`.feet`) moves a person one camera alone shows along its line of sight to the
floor point under the lowest point of their silhouette. Three ways that point is not their feet:

- **another person on the same line of sight, just behind or in front** (``feet.ray_band_share``).
  :func:`~.feet.touches_other` looks only a few pixels round the feet. On PETS 2009 View_001 (people
  ~25 m out, a pixel 0.13 m on the floor) people cross on one line of sight: with the anchor and
  ``feet.footprint``, started on frame 3, the track on person 15 took the feet of 19, who walked in
  front of them 0.3 m to the side (frame 108: 24.76 -> 23.93 m), and followed 19 from then on. Here
  the feet are not used when another person's ellipse (its bounding box) reaches the rectangle at
  the feet: their columns (± a quarter of the person's ellipse's width) and the rows from
  ``ray_band_share`` of the person's ellipse's height above them (someone just behind stands a few
  rows higher) down to them (someone in front covers them);
- **an obstacle's edge** (``feet.obstacle_clear``): :func:`~.height.measure_feet` tests the one
  pixel below the silhouette's bottom for an obstacle. Walking round a desk's end (paper_kato Table 2
  (a), "feet hidden", through), the leg beside the desk ends where the desk begins, a pixel or two
  to the side: all 5 anchor moves at 160x120 were there, 3 with the feet hidden, and they cost the
  still frames after them 0.135 -> 0.260 m. Here the feet are not used where an obstacle nearer
  than them covers any pixel of a window at the feet (half the person's ellipse wide each side,
  ``FEET_ROWS_SHARE`` of its height up and down);
- **a near walker's feet under a far person's head** (``feet.height_sigmas``): the merged
  silhouette's bottom is the near person's feet and its top the far one's head, and the head's ray
  above those feet is a few centimetres off the far person's height, within the fixed
  ``feet.height_match_m`` (0.3 m; one-camera seed 410 frames 67-68: a 1 m jump towards the camera).
  Once a person's height is measured (3 samples), the feet count only where the height read above
  them is within ``height_sigmas`` × the scatter of one measurement (1.4826 × MAD of the samples, at
  least ``SCATTER_FLOOR_M``) of the person's height, and never beyond ``height_match_m``.

>>> import numpy as np
>>> boxes = np.array([[90, 110, 20, 100], [95, 105, 10, 80], [200, 220, 20, 100]], dtype=float)
>>> ray_shared(boxes, np.ones(3, bool), 0, np.array([100.0, 99.0]), 0.1)   # 1 ends 20 rows above the feet
False
>>> ray_shared(boxes, np.ones(3, bool), 0, np.array([100.0, 99.0]), 0.3)
True
>>> ellipse_boxes(np.array([[100.0, 50.0, 1 / 10 ** 2, 0.0, 1 / 40 ** 2]])).tolist()
[[90.0, 110.0, 10.0, 90.0]]
>>> round(height_gate_m([1.70, 1.71, 1.69, 1.72, 1.70], 0.3, 3.0), 3)     # MAD 0.01 m: the floor
0.06
>>> round(height_gate_m([1.70, 1.73, 1.67, 1.74, 1.70], 0.3, 3.0), 3)     # MAD 0.03 m
0.133
>>> round(height_gate_m([1.70, 1.71, 1.69, 1.72, 1.70], 0.3, 3.0, floor_m=0.04), 3)
0.12
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

#: Least scatter of one height measurement, m (a pixel or two of the head's top at a few metres).
SCATTER_FLOOR_M = 0.02
#: Rows above and below the feet searched for an obstacle, share of the person's ellipse's height.
FEET_ROWS_SHARE = 0.03
#: Half the width of the feet's columns, share of the person's box width.
FEET_HALF_WIDTH_SHARE = 0.25


def ellipse_boxes(inner: np.ndarray) -> np.ndarray:
    """(N, 4) float — ``u0, u1, v0, v1`` (ideal px) bounding the ellipses of normal forms ``inner`` (N, 5)
    ``(cx, cy, a11, a12, a22)`` (the points with ``a11·du² + 2·a12·du·dv + a22·dv² < 1``)."""
    f = np.asarray(inner, dtype=float).reshape(-1, 5)
    det = np.maximum(f[:, 2] * f[:, 4] - f[:, 3] ** 2, 1e-12)
    hu, hv = np.sqrt(np.maximum(f[:, 4], 0) / det), np.sqrt(np.maximum(f[:, 2], 0) / det)
    return np.stack([f[:, 0] - hu, f[:, 0] + hu, f[:, 1] - hv, f[:, 1] + hv], axis=1)


def ideal_pixel(grid: np.ndarray, has_dist: bool, uv: np.ndarray) -> np.ndarray:
    """The ideal (undistorted) coordinates (2,) of real pixel ``uv`` (2,): from ``grid`` (H, W, 2) at
    the nearest pixel under distortion, else ``uv`` itself; non-finite stays non-finite."""
    uv = np.asarray(uv, dtype=float)
    if not has_dist or not np.isfinite(uv).all():
        return uv
    v = min(max(int(round(uv[1])), 0), grid.shape[0] - 1)
    u = min(max(int(round(uv[0])), 0), grid.shape[1] - 1)
    return np.asarray(grid[v, u], dtype=float)


def ray_shared(boxes: np.ndarray, valid: np.ndarray, k: int, feet_uv: np.ndarray, band_share: float) -> bool:
    """Whether another person's ellipse reaches the rectangle at person ``k``'s feet in one camera.

    Parameters
    ----------
    boxes : (N, 4) float — ``u0, u1, v0, v1`` (px) bounding the people's ellipses (:func:`ellipse_boxes`)
    valid : (N,) bool — which ellipses are drawn
    k : index of the person whose feet are tested
    feet_uv : (2,) float — the feet's image point (u, v), px, in the boxes' coordinates
    band_share : rows above the feet that count, share of ``k``'s box height; 0 tests nothing

    Returns
    -------
    bool — True when the feet may be another person's (or a non-finite point)
    """
    if band_share <= 0:
        return False
    if not np.isfinite(feet_uv).all():
        return True
    u0, u1, v0, v1 = (float(b) for b in boxes[k])
    half = FEET_HALF_WIDTH_SHARE * (u1 - u0)
    top, bottom = feet_uv[1] - band_share * (v1 - v0), feet_uv[1]
    b = np.asarray(boxes, dtype=float)
    others = np.asarray(valid, bool) & (np.arange(len(b)) != k)
    meets = (b[:, 0] < feet_uv[0] + half) & (b[:, 1] > feet_uv[0] - half) & (b[:, 2] <= bottom) & (b[:, 3] > top)
    return bool(np.any(others & meets))


def obstacle_beside(occ: np.ndarray | None, feet_uv: np.ndarray, half_px: float, rows_px: int, distance_m: float) -> bool:
    """Whether an obstacle nearer than ``distance_m`` (m, the person's floor distance) covers a pixel of
    the window at the feet: columns ``feet_uv[0]`` ± ``half_px``, rows from ``rows_px`` above the feet
    to ``rows_px`` below them (``occ`` (H, W): each pixel's nearest obstacle's floor distance, m, inf
    where none; None: no obstacles). The bottom of a silhouette there may be the obstacle's edge."""
    if occ is None:
        return False
    if not np.isfinite(feet_uv).all():
        return True
    h, w = occ.shape
    u, v = int(round(feet_uv[0])), int(round(feet_uv[1]))
    r = int(np.ceil(half_px))
    win = occ[max(v - rows_px, 0):min(v + rows_px + 1, h), max(u - r, 0):min(u + r + 1, w)]
    return bool(np.any(win < distance_m))


def feet_doubted(view, current, k: int, pixel: np.ndarray, feet_xy: np.ndarray, config) -> bool:
    """Whether person ``k``'s feet found at floor point ``feet_xy`` (2,, m), real image point ``pixel`` (2,), in camera ``view``
    (:class:`~.cameras.CameraView`; ``current``: every person's :class:`~.args.Forms` there) may be
    another person's (``config.ray_band_share``, :func:`ray_shared`) or an obstacle's edge
    (``config.obstacle_clear``, :func:`obstacle_beside`, the window half the person's ellipse wide
    each side and ``FEET_ROWS_SHARE`` of its height up and down); ``config``: a FeetConfig."""
    if config.ray_band_share <= 0 and not config.obstacle_clear:
        return False
    boxes = ellipse_boxes(current.inner)
    ideal = ideal_pixel(view.grid, view.args.has_dist, pixel)
    if ray_shared(boxes, current.valid, k, ideal, config.ray_band_share):
        return True
    if not config.obstacle_clear:
        return False
    u0, u1, v0, v1 = boxes[k]
    rows = max(2, int(round(FEET_ROWS_SHARE * (v1 - v0))))
    distance = float(np.hypot(*(np.asarray(feet_xy, dtype=float)[:2] - view.camera.centre[:2])))
    return obstacle_beside(view.occ, pixel, 0.5 * (u1 - u0), rows, distance)


def height_gate_m(samples: Sequence[float], match_m: float, sigmas: float, floor_m: float = SCATTER_FLOOR_M,
                  min_samples: int = 3) -> float:
    """How far (m) the height read above the feet may be from the person's height: ``match_m``
    while fewer than ``min_samples`` (at least 3) samples are in or ``sigmas`` is 0, else ``sigmas`` ×
    the scatter of one measurement (1.4826 × MAD of ``samples``, m, at least ``floor_m``, m), at most
    ``match_m``."""
    if sigmas <= 0 or len(samples) < max(3, min_samples):
        return match_m
    s = np.asarray(samples, dtype=float)
    scatter = max(1.4826 * float(np.median(np.abs(s - np.median(s)))), floor_m)
    return min(match_m, sigmas * scatter)


__all__ = ["FEET_HALF_WIDTH_SHARE", "FEET_ROWS_SHARE", "SCATTER_FLOOR_M", "ellipse_boxes", "feet_doubted",
           "height_gate_m", "ideal_pixel", "obstacle_beside", "ray_shared"]
