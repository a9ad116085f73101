"""Is the bottom of a silhouette a person's feet? Two tests on the foreground labels.

Legs in the floor's colour (or dark trousers in a shadow-like light) read as "unsure" (label 2)
rather than foreground, so the foreground silhouette may end at the waist. Its "feet" then put the
person metres too far along an oblique camera's line of sight, and the head's height above that
point is far too low (1.32 m for a 1.62 m person 6 m from a camera 2.6 m high: still a plausible
height). The bottom is the feet when the silhouette does not go on below it as unsure pixels
(:func:`unsure_below`: the bottom touches the floor) and when below the knees it is foreground
(:func:`legs_foreground_share`).

>>> labels = np.zeros((100, 40), np.uint8); labels[10:60, 15:25] = 1; labels[60:95, 15:25] = 2
>>> region = np.ones((100, 40), bool)
>>> top, bottom, down = np.array([20.0, 10.0]), np.array([20.0, 95.0]), np.array([0.0, 1.0])
>>> legs_foreground_share(labels, region, (0, 40, 0, 100), top, bottom, down)    # trousers unsure
0.0
>>> labels[60:95, 15:25] = 1
>>> legs_foreground_share(labels, region, (0, 40, 0, 100), top, bottom, down)
1.0
>>> labels[60:95] = 2                                       # the silhouette 1 ends at row 60 ...
>>> unsure_below(labels, top, np.array([20.0, 60.0]), down)  # ... and goes on below, unsure
1.0
>>> labels[60:95] = 0
>>> unsure_below(labels, top, np.array([20.0, 60.0]), down)
0.0
"""

from __future__ import annotations

import numpy as np

#: The band below the bottom that :func:`unsure_below` reads: this share of the silhouette's
#: length down, and a twentieth of it either side (about a leg's width).
BELOW_SHARE = 0.3
#: The knees are this share of the way up from the feet to the top of the head.
KNEE_SHARE = 0.28


def unsure_below(labels: np.ndarray, top: np.ndarray, bottom: np.ndarray, down: np.ndarray) -> float:
    """Share (0–1) of the pixels just below a silhouette's bottom that are unsure (label 2).

    Parameters
    ----------
    labels : (H, W) uint8 — foreground labels (0 background, 1 foreground, 2 unsure)
    top, bottom : (2,) — the silhouette's ends, pixels (u, v)
    down : (2,) — the image's world-down direction there (unit)
    """
    length = float((bottom - top) @ down)
    if length <= 0:
        return 0.0
    half = max(0.05 * length, 1.0)
    aa, bb = np.meshgrid(np.arange(1.0, max(BELOW_SHARE * length, 2.0)), np.arange(-half, half + 1.0))
    u = np.rint(bottom[0] + aa * down[0] - bb * down[1]).astype(int).ravel()
    v = np.rint(bottom[1] + aa * down[1] + bb * down[0]).astype(int).ravel()
    inside = (u >= 0) & (v >= 0) & (u < labels.shape[1]) & (v < labels.shape[0])
    if not inside.any():
        return 0.0
    return float(np.count_nonzero(labels[v[inside], u[inside]] == 2)) / float(np.count_nonzero(inside))


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


__all__ = ["BELOW_SHARE", "KNEE_SHARE", "legs_foreground_share", "unsure_below"]
