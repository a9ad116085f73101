"""The object region (seed 004, eqs. 9–10): centre ``O = mean`` of the particles and size
``σ_x, σ_y, σ_z``, the box ``O ± σ``.

With the sharp column ratio the particles gather on the object's axis, so the region adds the
object's own extent: in x and y a disc of the person's width, ``σ_x² = var(x) + (width/4)²``
(:func:`region_sizes`); in z the particles are drawn below the top each column sees.

>>> cloud_mean(np.arange(12.0).reshape(1, 4, 3)).tolist()
[[4.5, 5.5, 6.5]]
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numba import njit


def cloud_mean(x: np.ndarray) -> np.ndarray:
    """Mean over the particles of each cloud, ``x`` (F, N, C) → (F, C), as a matrix product
    (NumPy's reduction over the middle axis of an (F, N, 3) array is many times slower)."""
    return _mean_weights(x.shape[1]) @ x


@functools.lru_cache(maxsize=8)
def _mean_weights(n: int) -> np.ndarray:
    """(n,) all ``1/n``, read-only: :func:`cloud_mean`'s weights, made once per particle count."""
    w = np.full(n, 1.0 / n)
    w.setflags(write=False)
    return w


@njit(cache=True)
def region_sizes(sd: np.ndarray, widths: np.ndarray, sigma: np.ndarray) -> None:
    """The object regions' sizes from the particles' standard deviations ``sd`` (F, 3), metres, in
    place: ``sigma`` (F,) ``= sqrt((sx² + sy²) / 2)``, then, with ``widths`` (F,) (not empty),
    ``sx, sy = hypot(sx, width/4), hypot(sy, width/4)`` — :func:`region_sizes_reference`'s arithmetic."""
    for f in range(sd.shape[0]):
        sigma[f] = math.sqrt(0.5 * (sd[f, 0] * sd[f, 0] + sd[f, 1] * sd[f, 1]))
        if widths.shape[0]:
            q = 0.25 * widths[f]
            sd[f, 0] = math.hypot(sd[f, 0], q)
            sd[f, 1] = math.hypot(sd[f, 1], q)


def region_sizes_reference(sd: np.ndarray, widths: np.ndarray, sigma: np.ndarray) -> None:
    """:func:`region_sizes` in NumPy (the tracker's former code), in place."""
    sigma[:] = np.sqrt(0.5 * (sd[:, 0] ** 2 + sd[:, 1] ** 2))
    if len(widths):
        sd[:, :2] = np.hypot(sd[:, :2], 0.25 * np.asarray(widths)[:, None])


__all__ = ["cloud_mean", "region_sizes", "region_sizes_reference"]
