"""The point likelihood (seed 004, eq. 7): the baseline the height column improves on.

The particle's own 3-D point is projected and ``π_i = F(u, v)`` read there, F the background
difference with ``F ≤ γ`` set to 0. A particle inside the person and one on the floor behind it on
the same line of sight read the same pixel: the point cannot tell depth (the paper's Fig. 5).
:func:`point_values` is the compiled kernel, :func:`point_values_reference` the same in NumPy.

>>> round(F_MAX, 3)
441.673
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from worldtrack.geometry._kernels import lens
from worldtrack.geometry.camera import Camera
from worldtrack.trackers.particle.likelihood.column import pixels, readable
from worldtrack.trackers.particle.likelihood.reading import box_of, filter_rows, in_other_box, pixel_of

#: Largest possible Euclidean RGB distance, ``sqrt(3)·255``: divides F so that point likelihoods of
#: several cameras multiply on a common scale.
F_MAX = float(math.sqrt(3.0) * 255.0)


@njit(cache=True)
def point_values(xyz, camera, F, owner, boxes, which, values, seen):
    """Point likelihood π_i = F(u, v) at each particle's own projection (eq. 7), in place.

    Parameters
    ----------
    xyz : (N, 3) float64, metres
    camera : CameraArgs
    F : (H, W) float32 — background difference with ``F ≤ γ`` set to 0
    owner : (H, W) uint8 — object boxes per pixel; boxes (F, 4) int64, which (N,) int64 — each
        particle's filter's own box (a pixel in another box reads 0)
    values : (N,) float64 — out: F at the particle, 0 outside the image or in another object's box
    seen : (N,) bool — out: the particle projects into the image
    """
    H, W = F.shape
    lens_ = lens(camera.K, camera.dist)
    for i in range(xyz.shape[0]):
        iu, iv = pixel_of(xyz[i, 0], xyz[i, 1], xyz[i, 2], camera, lens_, W, H)
        values[i] = 0.0
        seen[i] = iu >= 0
        if iu >= 0 and not in_other_box(owner[iv, iu], box_of(boxes, which[i]), iu, iv):
            values[i] = F[iv, iu]


def point_values_reference(camera: Camera, F: np.ndarray, xyz: np.ndarray, owner: np.ndarray | None = None,
                           box=None, which: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """:func:`point_values` written plainly: F at each particle's projection, and ``seen``."""
    xyz = np.asarray(xyz, dtype=float).reshape(-1, 3)
    boxes, _, which = filter_rows(box, -1, which, len(xyz))
    iu, iv, inside = pixels(camera, xyz)
    ok = inside & readable(owner, boxes[which], iu, iv)
    return np.where(ok, F[iv, iu], 0.0).astype(float), inside


__all__ = ["F_MAX", "point_values", "point_values_reference"]
