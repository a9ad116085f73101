"""Colours of a tracked object (worldtrack's, not in seed 004): colour bins and a running histogram.

Colours: hue × saturation bins for saturated pixels (hue means little on greys), value bins for
the unsaturated ones, so black trousers and a white shirt are told apart too (:func:`colour_bins`;
:func:`pixel_bin` is the same for one pixel in the compiled kernels). A :class:`ColourModel` is one
object's histogram in one camera, learnt with a running average; its penalty table gives a sample
of a colour the object rarely shows ``log((B·p(c) + ε) / (1 + ε)) < 0`` — p(c) below the uniform
1/B over the B bins — and one of its own colours nothing (penalty only: see
:mod:`~worldtrack.trackers.particle.appearance`).

>>> m = ColourModel()
>>> m.learn(np.array([3] * 10), 1.0)
True
>>> m.log_ratio(np.array([[3, 3], [7, -1]])).round(3).tolist()
[0.0, -1.609]
"""

from __future__ import annotations

from typing import Sequence

import cv2
import numpy as np
from numba import njit

HUE_BINS = 12
SAT_BINS = 3          # saturated pixels only: saturation ≥ GREY_SATURATION
GREY_BINS = 4         # value bins of the unsaturated pixels
GREY_SATURATION = 48  # OpenCV saturation (0–255) below which a pixel counts as grey
N_BINS = HUE_BINS * SAT_BINS + GREY_BINS
#: A colour absent from the histogram still scores log(ε / (1 + ε)), not −inf.
EPSILON = 0.25
#: Fewer object samples than this in a frame teach nothing.
MIN_LEARN_SAMPLES = 6


def colour_bins(image: np.ndarray) -> np.ndarray:
    """(H, W) uint8 colour bin of every pixel of a BGR image, in ``0 … N_BINS − 1``.

    Saturated pixels: ``hue_bin · SAT_BINS + saturation_bin`` (hue in 12 bins of 15°, saturation
    from ``GREY_SATURATION`` to 255 in 3); grey pixels: ``HUE_BINS · SAT_BINS + value_bin``.
    One HSV conversion and three table look-ups (``cv2.LUT``); :func:`colour_bins_reference`
    is the same arithmetic written out.
    """
    h, s, v = cv2.split(cv2.cvtColor(np.ascontiguousarray(image, dtype=np.uint8), cv2.COLOR_BGR2HSV))
    colour = cv2.add(cv2.LUT(h, _HUE_LUT), cv2.LUT(s, _SAT_LUT))
    grey = cv2.LUT(v, _GREY_LUT)
    return np.where(s < GREY_SATURATION, grey, colour)


def colour_bins_reference(image: np.ndarray) -> np.ndarray:
    """:func:`colour_bins` with integer arithmetic on every pixel."""
    hsv = cv2.cvtColor(np.ascontiguousarray(image, dtype=np.uint8), cv2.COLOR_BGR2HSV)
    h = hsv[..., 0].astype(np.int32)
    s = hsv[..., 1].astype(np.int32)
    v = hsv[..., 2].astype(np.int32)
    sat_bin = np.minimum((s - GREY_SATURATION) * SAT_BINS // (256 - GREY_SATURATION), SAT_BINS - 1)
    colour = (np.minimum(h * HUE_BINS // 180, HUE_BINS - 1)) * SAT_BINS + sat_bin
    grey = HUE_BINS * SAT_BINS + v * GREY_BINS // 256
    return np.where(s < GREY_SATURATION, grey, colour).astype(np.uint8)


_LEVELS = np.arange(256)
_HUE_LUT = (np.minimum(_LEVELS * HUE_BINS // 180, HUE_BINS - 1) * SAT_BINS).astype(np.uint8)
_SAT_LUT = np.clip((_LEVELS - GREY_SATURATION) * SAT_BINS // (256 - GREY_SATURATION), 0, SAT_BINS - 1).astype(np.uint8)
_GREY_LUT = (HUE_BINS * SAT_BINS + _LEVELS * GREY_BINS // 256).astype(np.uint8)

# OpenCV's 8-bit BGR → HSV in fixed point (``hsv_shift`` 12, its tables ``sdiv_table`` and
# ``hdiv_table180``), for the compiled kernels: :func:`pixel_bin` is :func:`colour_bins` of one pixel
# (tested equal over all 2^24 colours).
_HSV_SHIFT = 12
_SDIV = np.array([0] + [round((255 << _HSV_SHIFT) / i) for i in range(1, 256)], dtype=np.int64)
_HDIV = np.array([0] + [round((180 << _HSV_SHIFT) / (6.0 * i)) for i in range(1, 256)], dtype=np.int64)


@njit(cache=True, inline="always")
def pixel_bin(b, g, r):
    """The :func:`colour_bins` bin of one BGR pixel (uint8 values), computed as OpenCV's
    ``COLOR_BGR2HSV`` computes hue (0–179), saturation and value, then the same three tables."""
    b, g, r = np.int64(b), np.int64(g), np.int64(r)
    v = max(b, g, r)
    diff = v - min(b, g, r)
    s = (diff * _SDIV[v] + (1 << (_HSV_SHIFT - 1))) >> _HSV_SHIFT
    if s < GREY_SATURATION:
        return np.int64(_GREY_LUT[v])
    if v == r:
        h = g - b
    elif v == g:
        h = b - r + 2 * diff
    else:
        h = r - g + 4 * diff
    h = (h * _HDIV[diff] + (1 << (_HSV_SHIFT - 1))) >> _HSV_SHIFT
    if h < 0:
        h += 180
    return np.int64(_HUE_LUT[h]) + np.int64(_SAT_LUT[s])


@njit(cache=True)
def _pixel_bins(image, out):
    for v in range(image.shape[0]):
        for u in range(image.shape[1]):
            out[v, u] = pixel_bin(image[v, u, 0], image[v, u, 1], image[v, u, 2])


def colour_bins_compiled(image: np.ndarray) -> np.ndarray:
    """:func:`colour_bins` by the compiled :func:`pixel_bin` (what the column kernels use), (H, W) uint8."""
    image = np.ascontiguousarray(image, dtype=np.uint8)
    out = np.empty(image.shape[:2], dtype=np.uint8)
    _pixel_bins(image, out)
    return out


class ColourModel:
    """One object's colour histogram in one camera, learnt with a running average.

    Attributes
    ----------
    hist : (N_BINS,) float or None — sums to 1 once anything was learnt
    frames : int — frames that taught it
    """

    def __init__(self) -> None:
        self.hist: np.ndarray | None = None
        self.frames = 0
        self._table: tuple[np.ndarray | None, np.ndarray] = (None, np.zeros(N_BINS))   # (hist, its table)

    def learn(self, sample_bins: np.ndarray, rate: float) -> bool:
        """Blend the histogram of the valid (≥ 0) bins in ``sample_bins`` in with weight ``rate``
        (the first frame sets it); False, and nothing learnt, with fewer than MIN_LEARN_SAMPLES."""
        bins = np.ascontiguousarray(sample_bins, dtype=np.int64).reshape(-1)
        out = np.empty(N_BINS)
        done = _blend_histogram(bins, _NO_HIST if self.hist is None else self.hist, float(rate), MIN_LEARN_SAMPLES,
                                out)
        if done < 0:
            raise ValueError(f"ColourModel.learn: colour bins must be below {N_BINS}, got {int(bins.max())}")
        if not done:
            return False
        self._learnt(out)
        return True

    def _learnt(self, hist: np.ndarray) -> None:
        """Take ``hist`` (N_BINS,) as the histogram after one more frame of learning."""
        self.hist = hist
        self.frames += 1

    def learn_reference(self, sample_bins: np.ndarray, rate: float) -> bool:
        """:meth:`learn` in NumPy (its former code), the reference of :func:`_blend_histogram`."""
        valid = np.asarray(sample_bins).ravel()
        valid = valid[valid >= 0]
        if len(valid) < MIN_LEARN_SAMPLES:
            return False
        p = np.bincount(valid, minlength=N_BINS).astype(float) / len(valid)
        self.hist = p if self.hist is None else (1.0 - rate) * self.hist + rate * p
        self.frames += 1
        return True

    def penalty_table(self) -> np.ndarray:
        """(N_BINS,) the term of a sample of each colour: ``min(0, log((B·p(c) + ε) / (1 + ε)))``, ≤ 0;
        all 0 when nothing is learnt. Kept until ``hist`` is replaced (every :meth:`learn` does)."""
        if self._table[0] is not self.hist:
            self._table = (self.hist, np.minimum(np.log((N_BINS * self.hist + EPSILON) / (1.0 + EPSILON)), 0.0))
        return self._table[1]

    def log_ratio(self, sample_bins: np.ndarray) -> np.ndarray:
        """(N,) sum over each row's valid samples of :meth:`penalty_table`, ≤ 0; 0 when nothing is learnt."""
        sample_bins = np.asarray(sample_bins)
        return colour_log_ratio([self], sample_bins, np.zeros(len(sample_bins), dtype=np.int64))


_NO_HIST = np.zeros(0)


@njit(cache=True)
def _blend_histogram(bins, hist, rate, min_samples, out):
    """``out`` (N_BINS,): the histogram ``p`` of the valid (≥ 0) ``bins`` (counts over their number),
    or ``(1 − rate)·hist + rate·p`` when ``hist`` is not empty; 1 when done, 0 (``out`` unset) with
    fewer than ``min_samples`` valid bins, −1 for a bin beyond ``out``."""
    counts = np.zeros(out.shape[0], dtype=np.int64)
    n = 0
    for b in bins:
        if b >= out.shape[0]:
            return -1
        if b >= 0:
            counts[b] += 1
            n += 1
    if n < min_samples:
        return 0
    keep = 1.0 - rate
    for c in range(out.shape[0]):
        p = counts[c] / n
        out[c] = p if hist.shape[0] == 0 else keep * hist[c] + rate * p
    return 1


def colour_log_ratio(models: Sequence[ColourModel | None], sample_bins: np.ndarray, which: np.ndarray) -> np.ndarray:
    """:meth:`ColourModel.log_ratio` of the colour columns of several filters' particles at once.

    Parameters
    ----------
    models : F models (None: nothing learnt, 0)
    sample_bins : (N, S) int — :func:`column_bins` of N particles' columns, −1 where not object
    which : (N,) int — each particle's model, 0 … F − 1

    Returns
    -------
    (N,) float, ≤ 0
    """
    tables = np.array([m.penalty_table() if m is not None else np.zeros(N_BINS) for m in models]).reshape(-1, N_BINS)
    sample_bins = np.asarray(sample_bins)
    out = np.empty(len(sample_bins))
    _table_sums(tables, np.ascontiguousarray(sample_bins), np.ascontiguousarray(which, dtype=np.int64), out)
    return out


@njit(cache=True)
def _table_sums(tables, bins, which, out):
    """``out[i] = Σ_k tables[which[i], bins[i, k]]`` over the valid (≥ 0) bins, in place."""
    for i in range(bins.shape[0]):
        s = 0.0
        for k in range(bins.shape[1]):
            if bins[i, k] >= 0:
                s += tables[which[i], bins[i, k]]
        out[i] = s


def penalty_tables(models: Sequence["ColourModel | None"]) -> tuple[np.ndarray, np.ndarray]:
    """(F, N_BINS) each model's :meth:`ColourModel.penalty_table` (0 for None) and (F,) bool which
    models have learnt something."""
    tables = np.array([m.penalty_table() if m is not None else np.zeros(N_BINS) for m in models]).reshape(-1, N_BINS)
    return tables, np.array([m is not None and m.hist is not None for m in models], dtype=np.bool_)


__all__ = ["EPSILON", "GREY_BINS", "HUE_BINS", "MIN_LEARN_SAMPLES", "N_BINS", "SAT_BINS", "ColourModel",
           "colour_bins", "colour_bins_compiled", "colour_bins_reference", "colour_log_ratio", "penalty_tables",
           "pixel_bin"]
