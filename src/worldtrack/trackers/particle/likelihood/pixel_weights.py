"""Pixel weights of column samples (``particle.likelihood.pixel_weights``, column-ratio only).

Samples are evenly spaced in height, not in the image: unweighted (the paper), a column farther along
the line of sight — shorter in the image — packs more samples into the same pixels of a body and wins
wherever the column's foot cannot tell it off (the lower body hidden behind a nearer person or below
the image's edge). Weighting each sample by the image length it stands for makes the ratio count
pixels of evidence. The variants, chosen by name:

* ``none`` — every sample weighs 1;
* ``depth`` — a sample's length over that of a sample 5 m from the camera (a per-camera scale, for
  all filters; the likelihood holds it as its default scale);
* ``filter`` (:class:`FilterScales`) — over the mean sample length of the column at each tracking
  filter's centre, so weights are ~1 round each object at any distance;
* ``hidden`` (:class:`HiddenScales`, the default) — ``filter``, only for filters whose columns had
  more than the foot samples hidden in that camera last frame.

:func:`inverse_lengths` is the compiled scale, :func:`inverse_lengths_reference` the NumPy one.
"""

from __future__ import annotations

import math
from typing import Callable, Iterable, Mapping, Protocol, Sequence

import numpy as np
from numba import njit

from worldtrack.registry import Registry
from worldtrack.trackers.particle.cloud import Cloud


class PixelWeights(Protocol):
    """Per camera, the pixel-weight scales (F,) of tracking filters, or None (the default scale)."""

    def scales(self, clouds: Sequence[Cloud], centres: Callable[[], np.ndarray],
               cameras: Iterable[str]) -> Mapping[str, np.ndarray] | None: ...


#: Pixel weights by the name ``particle.likelihood.pixel_weights`` gives.
PIXEL_WEIGHTS: Registry[type] = Registry("particle.likelihood.pixel_weights")


class Unweighted:
    """``none`` and ``depth``: no per-filter scales (the likelihood's default scale applies)."""

    def __init__(self, likelihood, foot_samples: int):
        pass

    def scales(self, clouds, centres, cameras):
        return None


PIXEL_WEIGHTS.register("none")(Unweighted)
PIXEL_WEIGHTS.register("depth")(Unweighted)


@PIXEL_WEIGHTS.register("filter")
class FilterScales:
    """Per camera, (F,) 1 / the mean image length (pixels) of a body sample of the column at each
    tracking filter's centre; 0 where it does not project."""

    def __init__(self, likelihood, foot_samples: int):
        self.likelihood, self.foot_samples = likelihood, foot_samples

    def scales(self, clouds, centres, cameras):
        return self._scales(centres(), cameras)

    def _scales(self, centres: np.ndarray, cameras: Iterable[str]) -> dict[str, np.ndarray]:
        lk = self.likelihood
        out = {}
        top = float(lk.heights[-1])
        for cid in cameras:
            cl = lk.cameras[cid]
            xy = lk.near_surface(centres, cl)
            ends = np.empty((2, len(xy), 3))            # the column's foot and top points, (2F, 3)
            ends[:, :, :2] = xy
            ends[0, :, 2], ends[1, :, 2] = 0.0, top
            uv = cl.camera.project(ends.reshape(-1, 3)).reshape(2, len(xy), 2)
            out[cid] = np.empty(len(xy))
            inverse_lengths(uv, len(lk.heights) - 1, out[cid])
        return out


@PIXEL_WEIGHTS.register("hidden")
class HiddenScales(FilterScales):
    """:class:`FilterScales` only for filters whose columns had more than the foot samples hidden in
    that camera last frame (where the foot cannot tell a far column off); 0 for the others."""

    def scales(self, clouds, centres, cameras):
        cameras = list(cameras)
        nb = self.foot_samples
        if not any(c.k_lo.get(cid, 0) > nb for c in clouds for cid in cameras):
            return {cid: np.zeros(len(clouds)) for cid in cameras}   # nobody hidden: no scales to compute
        use = {cid: np.array([c.k_lo.get(cid, 0) > nb for c in clouds]) for cid in cameras}
        return {cid: np.where(use[cid], s, 0.0) for cid, s in self._scales(centres(), cameras).items()}


@njit(cache=True)
def inverse_lengths(uv: np.ndarray, steps: int, out: np.ndarray) -> None:
    """``out`` (F,), in place: 1 / (the image length from ``uv[0, f]`` to ``uv[1, f]`` (pixels) over
    ``steps``), 0 where that is not finite and positive — :func:`inverse_lengths_reference`'s
    arithmetic (the pixel scale of ``pixel_weights="filter"``)."""
    for f in range(uv.shape[1]):
        length = math.hypot(uv[1, f, 0] - uv[0, f, 0], uv[1, f, 1] - uv[0, f, 1]) / steps
        out[f] = 1.0 / length if math.isfinite(length) and length > 0 else 0.0


def inverse_lengths_reference(uv: np.ndarray, steps: int) -> np.ndarray:
    """:func:`inverse_lengths` in NumPy (the tracker's former code)."""
    length = np.hypot(*(uv[1] - uv[0]).T) / steps
    ok = np.isfinite(length) & (length > 0)
    return np.where(ok, 1.0 / np.where(ok, length, 1.0), 0.0)


__all__ = ["PIXEL_WEIGHTS", "FilterScales", "HiddenScales", "PixelWeights", "Unweighted", "inverse_lengths",
           "inverse_lengths_reference"]
