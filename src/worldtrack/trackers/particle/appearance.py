"""Appearance of a tracked object: a colour histogram per camera, and the colour term of the likelihood.

Beyond seed 004, which has no appearance. When two people cross in one camera's image at different
depths the height column alone cannot tell whose pixels it reads, and a filter may go on with the
other person (a hand-over). So each tracking filter learns, per camera, the colour histogram of
the object pixels on its own column — only in frames where its image box overlaps no other track's
— as seed 003 learns its target's hue–saturation histogram. A particle then loses, for every
sample of its colour column that reads object in a colour its object rarely shows (another
person's shirt), ``log((B·p(c) + ε) / (1 + ε)) < 0`` — p(c) below the uniform 1/B over the B bins.

Penalty only: rewarding the object's own colours too (the same log-ratio, positive) acts as a
second count of object samples and pulls the column to where it covers most of the body, which
one camera places badly in depth. On the entry scenario (3 seeds, benchmarks/particle_entry.py)
the reward version gave 1.47 tracks per person but a mean error of 0.165 m; penalty only 1.73
tracks per person and 0.132 m (without appearance: 2.0 and 0.144 m).

Colours: hue × saturation bins for saturated pixels (hue means little on greys), value bins for
the unsaturated ones, so black trousers and a white shirt are told apart too.
"""


from __future__ import annotations

from typing import NamedTuple, Sequence

import cv2
import numpy as np
from numba import njit

from worldtrack.geometry._kernels import lens
from worldtrack.geometry.camera import Camera
from worldtrack.trackers.particle.likelihood.boxes import box_pixels, boxes_apart
from worldtrack.trackers.particle.likelihood.camera import CameraLikelihood, columns_beside
from worldtrack.trackers.particle.likelihood.column import column_points, pixels
from worldtrack.trackers.particle.likelihood.reading import pixel_of

HUE_BINS = 12
SAT_BINS = 3          # saturated pixels only: saturation ≥ GREY_SATURATION
GREY_BINS = 4         # value bins of the unsaturated pixels
GREY_SATURATION = 48  # OpenCV saturation (0–255) below which a pixel counts as grey
N_BINS = HUE_BINS * SAT_BINS + GREY_BINS
#: Heights (m) of the colour samples on a column: torso and legs, below a child's head.
COLOUR_HEIGHTS = np.array([0.3, 0.5, 0.7, 0.9, 1.1, 1.3])
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


class ColourArgs(NamedTuple):
    """What the colour kernels read of a frame: the labels ``hit`` (H, W) uint8 (1 = object), the BGR
    ``image`` (H, W, 3) uint8, the colour samples' ``heights`` (S,) float64 metres, and per filter its
    penalty ``tables`` (F, N_BINS) and whether it has ``learnt`` (F,) bool anything."""

    hit: np.ndarray
    image: np.ndarray
    heights: np.ndarray
    tables: np.ndarray
    learnt: np.ndarray


class Objects(NamedTuple):
    """Tracked objects for colour learning: ``centres`` (F, 2), ``widths``, ``heights`` (F,) float64
    metres, and which are ``learners`` (F,) bool."""

    centres: np.ndarray
    widths: np.ndarray
    heights: np.ndarray
    learners: np.ndarray


class Learning(NamedTuple):
    """The models being taught: ``hists`` (F, N_BINS), ``has_hist`` (F,) bool, the blend ``rate`` and
    the least number of object samples ``min_samples`` a frame needs to teach anything."""

    hists: np.ndarray
    has_hist: np.ndarray
    rate: float
    min_samples: int


class Taught(NamedTuple):
    """:func:`learn_columns`' kernel outputs: ``chosen`` (F,) bool, ``status`` (F,) int64 (1 learnt,
    0 too few samples, −1 a bin out of range) and the new ``hists`` (F, N_BINS)."""

    chosen: np.ndarray
    status: np.ndarray
    hists: np.ndarray


def column_bins(cl: CameraLikelihood, image: np.ndarray, hit: np.ndarray, xy: np.ndarray,
                heights: np.ndarray = COLOUR_HEIGHTS) -> np.ndarray:
    """Colour bins along columns standing at ``xy``, where they read object.

    A Numba kernel finds the samples' pixels and computes the bins of those that read object
    (:func:`pixel_bin`: a whole-frame HSV conversion costs ~1 ms at 640×480, and converting the
    gathered pixels with OpenCV cost more in calls than in work). Tested equal to
    :func:`column_bins_reference`.

    Parameters
    ----------
    cl : CameraLikelihood — the camera's constants, as the column kernel takes them
    image : (H, W, 3) uint8 — the BGR frame
    hit : (H, W) uint8 — the column likelihood's labels (1 = object)
    xy : (N, 2) float, metres — the columns' floor positions
    heights : (S,) float, metres

    Returns
    -------
    (N, S) int16 — the :func:`colour_bins` bin at each sample's pixel, −1 where the sample is
    outside the image or does not read object
    """
    xy = np.ascontiguousarray(np.asarray(xy, dtype=np.float64).reshape(-1, 2))
    out = np.empty((len(xy), len(heights)), dtype=np.int16)
    _column_bins(xy, np.ascontiguousarray(heights, dtype=np.float64), cl.args, hit,
                 np.ascontiguousarray(image, dtype=np.uint8), out)
    return out


@njit(cache=True)
def _column_bins(xy, heights, camera, hit, image, out):
    """``out`` (N, S), in place: each column sample's :func:`pixel_bin` where it reads object, else −1."""
    H, W = hit.shape
    lens_ = lens(camera.K, camera.dist)
    for i in range(xy.shape[0]):
        for k in range(heights.shape[0]):
            iu, iv = pixel_of(xy[i, 0], xy[i, 1], heights[k], camera, lens_, W, H)
            if iu >= 0 and hit[iv, iu] == 1:
                out[i, k] = pixel_bin(image[iv, iu, 0], image[iv, iu, 1], image[iv, iu, 2])
            else:
                out[i, k] = -1


def penalty_tables(models: Sequence["ColourModel | None"]) -> tuple[np.ndarray, np.ndarray]:
    """(F, N_BINS) each model's :meth:`ColourModel.penalty_table` (0 for None) and (F,) bool which
    models have learnt something."""
    tables = np.array([m.penalty_table() if m is not None else np.zeros(N_BINS) for m in models]).reshape(-1, N_BINS)
    return tables, np.array([m is not None and m.hist is not None for m in models], dtype=np.bool_)


def column_penalties(cl: CameraLikelihood, image: np.ndarray, hit: np.ndarray, xy: np.ndarray,
                     models: Sequence["ColourModel | None"], which: np.ndarray,
                     heights: np.ndarray = COLOUR_HEIGHTS) -> np.ndarray:
    """:func:`colour_log_ratio` of the :func:`column_bins` of columns at ``xy`` (N, 2), metres, in one
    kernel: (N,) float, ≤ 0 — 0 for the particles of models (``which`` (N,) int, 0 … F − 1 into
    ``models``) that are None or have learnt nothing. Tested equal to the two calls."""
    tables, learnt = penalty_tables(models)
    xy = np.ascontiguousarray(np.asarray(xy, dtype=np.float64).reshape(-1, 2))
    out = np.zeros(len(xy))
    if learnt.any():
        colour = ColourArgs(hit, np.ascontiguousarray(image, dtype=np.uint8),
                            np.ascontiguousarray(heights, dtype=np.float64), tables, learnt)
        _column_penalties(xy, cl.args, colour, np.ascontiguousarray(which, dtype=np.int64), out)
    return out


@njit(cache=True)
def _column_penalties(xy, camera, colour, which, out):
    """``out[i]``, in place: ``Σ_k tables[which[i], bin]`` over the samples of column i that read
    object, in sample order (as :func:`_table_sums`), for the particles of learnt models."""
    hit, image, heights, tables, learnt = colour.hit, colour.image, colour.heights, colour.tables, colour.learnt
    H, W = hit.shape
    lens_ = lens(camera.K, camera.dist)
    for i in range(xy.shape[0]):
        f = which[i]
        if not learnt[f]:
            continue
        s = 0.0
        for k in range(heights.shape[0]):
            iu, iv = pixel_of(xy[i, 0], xy[i, 1], heights[k], camera, lens_, W, H)
            if iu >= 0 and hit[iv, iu] == 1:
                s += tables[f, pixel_bin(image[iv, iu, 0], image[iv, iu, 1], image[iv, iu, 2])]
        out[i] = s


def learn_columns(cl: CameraLikelihood, image: np.ndarray, hit: np.ndarray, centres: np.ndarray, widths: np.ndarray,
                  heights: np.ndarray, learners: np.ndarray, margin: float, offset: float,
                  models: Sequence["ColourModel | None"], rate: float) -> np.ndarray:
    """What the tracker's colour learning does in one camera, in one compiled call: the objects'
    boxes (``margin`` m, :func:`~worldtrack.trackers.particle.likelihood.box_pixels`), which of the
    ``learners`` (F,) bool have a box overlapping no other
    (:func:`~worldtrack.trackers.particle.likelihood.boxes_apart`), and for those the
    :func:`column_bins` of the column ``offset`` m nearer the camera than ``centres`` (F, 2) and the two
    ``widths/4`` beside it (:func:`~worldtrack.trackers.particle.likelihood.columns_beside`), blended
    into ``models`` (F, None where a filter has none yet) as :meth:`ColourModel.learn` blends them.

    Returns (F,) bool, the filters that were taught (whether or not they had enough object samples to
    learn from); the models of those that learnt are updated in place. Tested equal to those calls.
    """
    f = len(centres)
    hists = np.zeros((f, N_BINS))
    has_hist = np.zeros(f, dtype=np.bool_)
    for i, m in enumerate(models):
        if m is not None and m.hist is not None:
            hists[i], has_hist[i] = m.hist, True
    out = Taught(np.empty(f, dtype=np.bool_), np.zeros(f, dtype=np.int64), np.empty((f, N_BINS)))
    objects = Objects(np.ascontiguousarray(centres, dtype=np.float64).reshape(-1, 2),
                      np.ascontiguousarray(widths, dtype=np.float64), np.ascontiguousarray(heights, dtype=np.float64),
                      np.ascontiguousarray(learners, dtype=np.bool_))
    _learn_columns(objects, float(margin), float(offset), cl.args, hit, np.ascontiguousarray(image, dtype=np.uint8),
                   COLOUR_HEIGHTS, Learning(hists, has_hist, float(rate), MIN_LEARN_SAMPLES), out)
    for i in np.flatnonzero(out.status).tolist():
        if out.status[i] < 0:
            raise ValueError(f"learn_columns: colour bins must be below {N_BINS}")
        models[i]._learnt(out.hists[i])
    return out.chosen


@njit(cache=True)
def _learn_columns(objects, margin, offset, camera, hit, image, colour_heights, learning, out):
    centres, widths, heights, learners = objects.centres, objects.widths, objects.heights, objects.learners
    hists, has_hist = learning.hists, learning.has_hist
    f = centres.shape[0]
    boxes = np.empty((f, 4), dtype=np.int64)
    box_pixels(centres, widths, heights, margin, 0.0, camera, boxes)
    apart = boxes_apart(boxes)
    spread = np.empty(1)
    columns = np.empty((3, 2))
    bins = np.empty((3, colour_heights.shape[0]), dtype=np.int16)
    for i in range(f):
        out.chosen[i] = learners[i] and apart[i]
        if not out.chosen[i]:
            continue
        spread[0] = 0.25 * widths[i]
        columns_beside(centres[i:i + 1], offset, spread, camera, columns)
        _column_bins(columns, colour_heights, camera, hit, image, bins)
        out.status[i] = _blend_histogram(bins.reshape(bins.size), hists[i] if has_hist[i] else hists[i, :0],
                                         learning.rate, learning.min_samples, out.hists[i])


def column_bins_reference(camera: Camera, image: np.ndarray, hit: np.ndarray, xy: np.ndarray,
                          heights: np.ndarray = COLOUR_HEIGHTS) -> np.ndarray:
    """:func:`column_bins` written plainly: the whole frame's bins, every sample through
    :meth:`Camera.project`."""
    bins = colour_bins_reference(image)
    iu, iv, inside = pixels(camera, column_points(xy, heights))
    on = inside & (hit[iv, iu] == 1)
    return np.where(on, bins[iv, iu].astype(np.int16), np.int16(-1))


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


__all__ = ["COLOUR_HEIGHTS", "N_BINS", "ColourArgs", "ColourModel", "colour_bins", "colour_bins_compiled",
           "colour_bins_reference", "colour_log_ratio", "column_bins", "column_bins_reference", "column_penalties",
           "learn_columns", "penalty_tables", "pixel_bin"]
