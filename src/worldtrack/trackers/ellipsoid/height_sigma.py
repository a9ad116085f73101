"""A person's height as an estimate with its own uncertainty: the standard error of the median
of their measurements.

The tracker keeps the median of a person's last height measurements (:mod:`.height`). Its
standard error, from the samples' robust spread (1.4826 · MAD, the σ of a normal sample),
is 1.2533 σ / √n. With ``ellipsoid.height.deadband_sigmas`` it decides when a measured height
replaces the scene's default (instead of a fixed 5 cm), and :mod:`.depth` uses it as the
height's σ when the top of the head places a person along the line of sight.

>>> round(median_sigma([1.70, 1.72, 1.74, 1.76, 1.78]), 4)      # MAD 0.02 m, 5 samples
0.0166
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


def replace_margin(samples: Sequence[float], config: HeightConfig) -> float:
    """How far (m) the median of ``samples`` must be from the default height to replace it:
    ``deadband_m``, or ``deadband_sigmas`` standard errors of the median."""
    return config.deadband_sigmas * median_sigma(samples) if config.deadband_sigmas > 0 else config.deadband_m


def height_sigma(p: Person, unmeasured_sigma_m: float, floor_m: float = 0.01) -> float:
    """σ of a person's height (m): the standard error of the median of their samples, at least
    ``floor_m`` (the samples share their biases: a shoe's front, hair, the mask's edge), from 3
    samples on; else ``unmeasured_sigma_m``."""
    return median_sigma(p.height_samples, floor_m) if len(p.height_samples) >= 3 else unmeasured_sigma_m


__all__ = ["height_sigma", "median_sigma", "replace_margin"]
