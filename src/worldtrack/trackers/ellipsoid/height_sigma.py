"""A person's height as an estimate with its own uncertainty: the standard error of the median
of their measurements.

The tracker keeps the median of a person's last height measurements (:mod:`.height`). Its
standard error, from the samples' robust spread (1.4826 · MAD, the σ of a normal sample),
is 1.2533 σ / √n. With ``ellipsoid.height.prior_sigma_m`` the person's height is the
precision-weighted mean of the scene's default (people's heights scatter by that much about it)
and that median, instead of the median once it is more than a fixed 5 cm from the default (a
1.73 m person stays 1.70 m under that rule however often measured); :mod:`.depth` uses it as the
height's σ when the top of the head places a person along the line of sight.

>>> round(median_sigma([1.70, 1.72, 1.74, 1.76, 1.78]), 4)      # MAD 0.02 m, 5 samples
0.0166
>>> from worldtrack.trackers.ellipsoid.config import HeightConfig
>>> round(height_estimate([1.73] * 9, 1.70, HeightConfig(prior_sigma_m=0.1)), 3)     # σ 5 mm
1.73
>>> height_estimate([1.73] * 9, 1.70, HeightConfig())                              # the deadband
1.7
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from worldtrack.trackers.base import Person
from worldtrack.trackers.ellipsoid.config import HeightConfig


def median_sigma(samples: Sequence[float], floor_m: float = 0.005) -> float:
    """Standard error (m) of the median of height ``samples`` (m): 1.2533 · 1.4826 · MAD / √n,
    at least ``floor_m``."""
    s = np.asarray(samples, dtype=float)
    return max(1.2533 * 1.4826 * float(np.median(np.abs(s - np.median(s)))) / float(np.sqrt(len(s))), floor_m)


def height_estimate(samples: Sequence[float], default: float, config: HeightConfig) -> float:
    """A person's height (m) from their measurements ``samples`` (m) and the scene's ``default``
    height (m): with ``prior_sigma_m`` > 0 the precision-weighted mean of the default (σ
    ``prior_sigma_m``) and the samples' median (σ :func:`median_sigma`); else the median where it
    is more than ``deadband_m`` from the default, and the default where not."""
    median = float(np.median(samples))
    if config.prior_sigma_m > 0:
        prior, own = config.prior_sigma_m ** 2, median_sigma(samples) ** 2
        return default + prior / (prior + own) * (median - default)
    return median if abs(median - default) > config.deadband_m else default


def height_sigma(p: Person, unmeasured_sigma_m: float, floor_m: float = 0.01) -> float:
    """σ of a person's height (m): the standard error of the median of their samples, at least
    ``floor_m`` (the samples share their biases: a shoe's front, hair, the mask's edge), from 3
    samples on; else ``unmeasured_sigma_m``."""
    return median_sigma(p.height_samples, floor_m) if len(p.height_samples) >= 3 else unmeasured_sigma_m


__all__ = ["height_estimate", "height_sigma", "median_sigma"]
