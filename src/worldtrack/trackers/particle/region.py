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
from typing import TYPE_CHECKING, Sequence

import numpy as np
from numba import njit

if TYPE_CHECKING:
    from worldtrack.trackers.base import Person
    from worldtrack.trackers.particle.cloud import Cloud, CloudStack
    from worldtrack.trackers.particle.motion import MotionModel

#: No widths (region_sizes leaves the floor sizes as the particles' spread).
_NO_WIDTHS = np.zeros(0)


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



def mean_rows(a: np.ndarray) -> np.ndarray:
    """(F,) the mean of each row of ``a`` (F, N): ``a.mean(axis=1)``, which is this sum over N."""
    return np.add.reduce(a, axis=1) / a.shape[1]


def mean_sd(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`cloud_mean` and the standard deviation over the particles of each cloud, two (F, C)."""
    mean = cloud_mean(x)
    d = x - mean[:, None, :]
    return mean, np.sqrt(cloud_mean(d * d))


class Regions:
    """Writes each tracking filter's object region on its person: centre (eq. 9) and size (eq. 10),
    velocity, height, and the box ``(x, y, z) ± (sx, sy, sz)`` as the output columns ``z, sx, sy, sz``.

    Parameters
    ----------
    stack : CloudStack; motion : MotionModel — the filters' floor velocity
    height_from : {"h", "col_h", None} — the per-particle field whose mean is the person's height: the
        particles' object heights, their columns' tops (once observed), or none (the point likelihood)
    widen : bool — the particles are the object's axis (the column ratio): the floor sizes add a disc
        of the person's width, ``σ_x² = var(x) + (width/4)²``
    """

    def __init__(self, stack: "CloudStack", motion: "MotionModel", height_from: str | None, widen: bool):
        self.stack, self.motion, self.height_from, self.widen = stack, motion, height_from, widen

    def update(self, clouds: Sequence["Cloud"], persons: Sequence["Person"], t: float) -> None:
        """The regions of ``clouds`` (of ``persons``, equal particle counts) at time ``t`` (s), from
        their resampled particles."""
        centre, sd = mean_sd(self.stack.stacked(clouds, "xyz"))
        V = self.motion.velocity(clouds, persons, centre, t)
        heights, field = None, self.height_from
        if field is not None and all(getattr(c, field) is not None for c in clouds):
            heights = mean_rows(self.stack.stacked(clouds, field))
        # sigma = sqrt((sx² + sy²) / 2); widened, sx, sy = hypot(sx, width/4).
        widths = np.array([p.width for p in persons], dtype=float) if self.widen else _NO_WIDTHS
        sigma = np.empty(len(clouds))
        region_sizes(sd, widths, sigma)
        floor_centre = centre[:, :2].copy()
        rows = zip(clouds, persons, floor_centre, centre.tolist(), V.tolist(), sd.tolist(), sigma.tolist(),
                   heights.tolist() if heights is not None else [None] * len(clouds))
        for c, p, fc, (x, y, z), (vx, vy), (sx, sy, sz), s, height in rows:
            c.centre, c.t_update = fc, t
            p.x, p.y, p.vx, p.vy, p.sigma = x, y, vx, vy, s
            if height is not None:
                p.height = height
            p.extra.update(z=z, sx=sx, sy=sy, sz=sz)


__all__ = ["Regions", "cloud_mean", "mean_rows", "mean_sd", "region_sizes", "region_sizes_reference"]
