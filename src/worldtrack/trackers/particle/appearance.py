"""Appearance of a tracked object: a colour histogram per camera, and the colour term of the likelihood.

Beyond seed 004, which has no appearance. When two people cross in one camera's image at different
depths the height column alone cannot tell whose pixels it reads, and a filter may go on with the
other person (a hand-over). So each tracking filter learns, per camera, the colour histogram of
the object pixels on its own column — only in frames where its image box overlaps no other track's
— as seed 003 learns its target's hue–saturation histogram. A particle then loses, for every
sample of its colour column that reads object in a colour its object rarely shows (another
person's shirt), ``log((B·p(c) + ε) / (1 + ε)) < 0`` — p(c) below the uniform 1/B over the B bins.

Penalty only: a reward for the object's own colours acts as a second count of object samples and
pulls the column to where it covers most of the body (measured in ``benchmarks/results/tuning_particle.md``).

This module reads colours along a filter's columns (:func:`column_bins`, :func:`column_penalties`)
and teaches each filter its colours (:func:`learn_columns`, :class:`ColourLearning`); the bins and
the histogram are in :mod:`~worldtrack.trackers.particle.colour`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Mapping, NamedTuple, Sequence

import numpy as np
from numba import njit

from worldtrack.geometry._kernels import lens
from worldtrack.geometry.camera import Camera
from worldtrack.trackers.particle.colour import (MIN_LEARN_SAMPLES, N_BINS, ColourModel, _blend_histogram,
                                                 colour_bins_reference, penalty_tables, pixel_bin)
from worldtrack.trackers.particle.likelihood.boxes import box_pixels, boxes_apart
from worldtrack.trackers.particle.likelihood.camera import CameraLikelihood, columns_beside
from worldtrack.trackers.particle.likelihood.column import column_points, pixels
from worldtrack.trackers.particle.likelihood.reading import pixel_of

if TYPE_CHECKING:
    from worldtrack.trackers.base import Person
    from worldtrack.trackers.particle.cloud import Cloud
    from worldtrack.trackers.particle.config import ParticleConfig

#: Heights (m) of the colour samples on a column: torso and legs, below a child's head.
COLOUR_HEIGHTS = np.array([0.3, 0.5, 0.7, 0.9, 1.1, 1.3])


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


class ColourLearning:
    """Teaches each tracking filter the colours on its column, in the cameras where its box overlaps
    no other's: the column at the particles' mean and two beside it (±width/4 across the line of
    sight), object samples only; filters with fewer than half their particles likely learn nothing."""

    def __init__(self, cfg: "ParticleConfig", cameras: Mapping[str, CameraLikelihood]):
        self.margin, self.offset = cfg.explain.box_margin_m, cfg.column.surface_offset_m
        self.rate = cfg.appearance.rate
        self.cameras = cameras

    def learn(self, clouds: Sequence["Cloud"], persons: Sequence["Person"], labels: Mapping[str, np.ndarray],
              frames: Mapping[str, np.ndarray]) -> None:
        """One frame's learning of ``clouds`` (of ``persons``) from the ``labels`` and BGR ``frames`` per camera."""
        # More than half likely (the mean of the booleans above 0.5, with integers).
        learners = np.array([c.likely is not None and 2 * np.count_nonzero(c.likely) > len(c.likely) for c in clouds],
                            dtype=bool)
        if not learners.any():
            return
        centres = np.array([c.centre for c in clouds], dtype=float).reshape(-1, 2)
        widths = np.array([p.width for p in persons], dtype=float)
        heights = np.array([p.height for p in persons], dtype=float)
        for cid, hit in labels.items():
            # The boxes, those overlapping no other, the three columns of each, their colour bins and the
            # histograms' blend: learn_columns, one compiled call.
            models = [c.colours.get(cid) for c in clouds]
            given = [m if m is not None else ColourModel() for m in models]
            chosen = learn_columns(self.cameras[cid], frames[cid], hit, centres, widths, heights, learners, self.margin,
                                   self.offset, given, self.rate)
            for c, m, new, taught in zip(clouds, models, given, chosen.tolist()):
                if taught and m is None:                # a filter taught for the first time keeps its model
                    c.colours[cid] = new



__all__ = ["COLOUR_HEIGHTS", "ColourArgs", "ColourLearning", "column_bins", "column_bins_reference",
           "column_penalties", "learn_columns"]
