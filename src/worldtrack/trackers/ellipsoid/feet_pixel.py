"""The feet's σ along the line of sight includes what one image pixel at the feet spans on the floor (opt-in).

The feet anchor (:mod:`.feet`) trusts the lowest point of a silhouette to ``feet.sigma_m`` (0.1 m, a
shoe's length) wherever it is found. That is the floor's share only. The silhouette's bottom edge
is itself uncertain by a pixel or two (blur, compression, a shadow's first pixels, the foreground's
threshold), and one pixel at the feet spans

    ``ds/dv ≈ (d² + H²) / (H · f)``   (m per pixel along the line of sight)

on the floor (``d`` the distance on the floor, ``H`` the camera's height, ``f`` the focal length,
px): about 0.04 m for a person 7 m from a camera 2.85 m high at f ≈ 500 px, 0.09 m at 20 m from a
camera 7 m high (PETS 2009 View_001, f ≈ 745 px at 480x360). With ``feet.pixel_sigma_px`` = n > 0 the
feet's σ becomes ``hypot(feet.sigma_m, n · ds/dv)``, measured at the feet's own pixel by
back-projecting it and the pixel one step further down the image; far, small feet then pull the
track less than near, large ones. 0 (the default) keeps the fixed σ.

Measured with the best one-camera opt-in on PETS View_001 (3 start frames, issue 37): MOTA 0.846 ->
0.869 (n = 1) and 0.867 (n = 2), but IDF1 0.762 -> 0.703 / 0.775 and ID switches 23.7 -> 26 / 17: within
the runs' spread, not the cause of the opt-in's cost there (that is the anchor's head cue, :mod:`.head_clear`).
Not measured on the line-of-sight seeds.

>>> round(pixel_sigma_m(0.1, 2.0, 0.0), 3), round(pixel_sigma_m(0.1, 2.0, 0.1), 3)
(0.1, 0.224)
"""

from __future__ import annotations

import numpy as np


def pixel_sigma_m(sigma_m: float, pixel_sigma_px: float, metres_per_px: float) -> float:
    """σ of the feet's place along the line of sight, m: ``hypot(sigma_m, pixel_sigma_px · metres_per_px)``."""
    return float(np.hypot(sigma_m, pixel_sigma_px * metres_per_px))


def metres_per_pixel(camera, pixel: np.ndarray, down: np.ndarray) -> float:
    """Floor distance (m) between the back-projections of image point ``pixel`` (2,) (u, v, px) and of
    the point one pixel further along the image's ``down`` direction (2,, unit); inf when either
    does not meet the floor (at or above the horizon)."""
    uv = np.asarray(pixel, dtype=float)
    pair = np.stack([uv, uv + np.asarray(down, dtype=float)])
    floor = camera.backproject(pair, 0.0)
    if not np.isfinite(floor).all():
        return float("inf")
    return float(np.hypot(*(floor[1, :2] - floor[0, :2])))


def feet_sigma_m(camera, feet_xy: np.ndarray, down: np.ndarray, sigma_m: float, pixel_sigma_px: float) -> float:
    """The feet's σ along the line of sight (m) for feet found at floor point ``feet_xy`` (2,) in
    ``camera``: ``sigma_m`` alone when ``pixel_sigma_px`` is 0, else with the pixel's span added."""
    if pixel_sigma_px <= 0:
        return sigma_m
    pixel = camera.project(np.array([feet_xy[0], feet_xy[1], 0.0])[None])[0]
    if not np.isfinite(pixel).all():
        return sigma_m
    return pixel_sigma_m(sigma_m, pixel_sigma_px, metres_per_pixel(camera, pixel, down))


__all__ = ["feet_sigma_m", "metres_per_pixel", "pixel_sigma_m"]
