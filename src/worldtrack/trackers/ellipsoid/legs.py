"""Are a silhouette's legs foreground? The test that decides whether its bottom is the feet.

Legs in the floor's colour read as "unsure" (shadow-like, label 2) rather than foreground. Where
the silhouette's lowest part is unsure, its bottom may be a shoe below unsure trousers, or the
waist; the feet are trusted only where the legs below the knees are mostly foreground.

>>> labels = np.zeros((100, 40), np.uint8); labels[10:60, 15:25] = 1; labels[60:95, 15:25] = 2
>>> region = np.ones((100, 40), bool)
>>> top, bottom, down = np.array([20.0, 10.0]), np.array([20.0, 95.0]), np.array([0.0, 1.0])
>>> legs_foreground_share(labels, region, (0, 40, 0, 100), top, bottom, down)    # trousers unsure
0.0
>>> labels[60:95, 15:25] = 1
>>> legs_foreground_share(labels, region, (0, 40, 0, 100), top, bottom, down)
1.0
"""

from __future__ import annotations

import numpy as np

#: The knees are this share of the way up from the feet to the top of the head.
KNEE_SHARE = 0.28


def legs_foreground_share(labels: np.ndarray, region: np.ndarray, box: tuple[int, int, int, int],
                          top: np.ndarray, bottom: np.ndarray, down: np.ndarray) -> float:
    """Share (0–1) of the labelled pixels (1 or 2) of ``region`` (a crop at ``box`` = (u0, u1, v0,
    v1)) below the knees that are foreground (1); 0 with none."""
    u0, _, v0, _ = (int(x) for x in box)
    vs, us = np.nonzero(region)
    along = (us + u0 - bottom[0]) * down[0] + (vs + v0 - bottom[1]) * down[1]   # ≤ 0 above the feet
    legs = along >= -KNEE_SHARE * float((bottom - top) @ down)
    values = labels[vs[legs] + v0, us[legs] + u0]
    fg = np.count_nonzero(values == 1)
    marked = fg + np.count_nonzero(values == 2)
    return float(fg / marked) if marked else 0.0


__all__ = ["KNEE_SHARE", "legs_foreground_share"]
