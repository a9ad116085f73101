"""One camera's share of the column likelihood ratio in one compiled call (the tracker's hot path).

:func:`observe_column` does for one camera what the readable steps do one after the other: the
columns stand ``surface_offset`` nearer to the camera than the particles
(:func:`~.camera.toward_camera`), are read (:func:`~.column.column_counts`), lose the colour term
of the filter's appearance (:func:`~worldtrack.trackers.particle.appearance.column_penalties`) and
are added to the sums over cameras (:func:`~.sums.add_camera`). The tests check that it gives the
same values as those calls one by one.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
from numba import njit

from worldtrack.trackers.particle.appearance import COLOUR_HEIGHTS, ColourArgs, _column_penalties
from worldtrack.trackers.particle.colour import N_BINS, ColourModel, penalty_tables
from worldtrack.trackers.particle.likelihood.camera import CameraLikelihood, toward_camera
from worldtrack.trackers.particle.likelihood.column import ColumnOut, ColumnSpec, column_counts
from worldtrack.trackers.particle.likelihood.reading import Reading
from worldtrack.trackers.particle.likelihood.sums import Sums, add_camera

_NO_TABLES = np.zeros((0, N_BINS))
_NO_IMAGE = np.zeros((0, 0, 3), dtype=np.uint8)
_NO_LEARNT = np.zeros(0, dtype=np.bool_)


def observe_column(cl: CameraLikelihood, xy: np.ndarray, offset: float, column: ColumnSpec, reading: Reading,
                   hit: np.ndarray, image: np.ndarray | None, models: Sequence[ColourModel | None], weight: float, likely_count: int,
                   sums: Sums, hidden: np.ndarray) -> None:
    """One camera's share of the column likelihood ratio, added to ``sums`` in place.

    Parameters
    ----------
    cl : CameraLikelihood
    xy : (N, ≥ 2) float64, metres — the particles (floor positions in the first two columns)
    offset : float, metres — the columns stand this much nearer to the camera
    column : ColumnSpec; reading : Reading (:meth:`CameraLikelihood.reading`) — how they are read
    hit : (H, W) uint8 — the labels (1 = object) the colour term reads
    image : (H, W, 3) uint8 or None — the BGR frame, for the colour term (None: no colour term)
    models : per filter, its ColourModel in this camera or None
    weight : float — the colour term's weight
    likely_count : int — samples on the object for a particle to be likely in this camera
    sums : Sums — in/out: ``logpi += best ratio (+ weight · colour term)`` where the camera sees the
        particle, ``likely &= counts ≥ likely_count``, ``n_seen += seen``, ``col += top's height``
    hidden : (N,) int32 — out: how many of each column's lowest samples are hidden
    """
    n = len(xy)
    if image is None:
        tables, learnt, image = _NO_TABLES, _NO_LEARNT, _NO_IMAGE
    else:
        tables, learnt = penalty_tables(models)
    surface, counts, ratio, top, seen, penalty = _work_arrays(cl, n)
    colour = ColourArgs(hit, np.ascontiguousarray(image, dtype=np.uint8), COLOUR_HEIGHTS, tables, learnt)
    _observe_column(xy, float(offset), cl.args, column, reading, ColumnOut(counts, ratio, top, seen, hidden), colour,
                    float(weight), int(likely_count), sums, surface, penalty)


def _work_arrays(cl: CameraLikelihood, n: int) -> tuple[np.ndarray, ...]:
    """Work arrays of :func:`_observe_column` for ``n`` particles (surface, counts, ratio, top, seen,
    penalty), kept in the camera's ``cl.work`` between calls (the last few sizes): all are written
    before they are read, the penalty set to 0 here."""
    key = ("observe_column", n)
    out = cl.work.get(key)
    if out is None:
        if len(cl.work) > 8:
            cl.work.clear()
        out = cl.work[key] = (np.empty((n, 2)), np.empty(n, dtype=np.int32), np.empty(n),
                              np.empty(n, dtype=np.int32), np.empty(n, dtype=np.bool_), np.empty(n))
    out[5][:] = 0.0
    return out


@njit(cache=True)
def _observe_column(xy, offset, camera, column, reading, out, colour, weight, likely_count, sums, surface, penalty):
    if offset > 0.0:
        toward_camera(xy, offset, camera, surface)
    else:
        for i in range(xy.shape[0]):
            surface[i, 0], surface[i, 1] = xy[i, 0], xy[i, 1]
    column_counts(surface, camera, column, reading, out)
    with_colour = colour.image.shape[0] > 0
    if with_colour:
        any_learnt = False
        for f in range(colour.learnt.shape[0]):
            any_learnt = any_learnt or colour.learnt[f]
        if any_learnt:
            _column_penalties(surface, camera, colour, reading.which, penalty)
    # lv = the best ratio (+ weight · penalty), col_h = its top's height, ok = counts ≥ likely_count
    add_camera(out.seen, out.ratio, penalty if with_colour else penalty[:0], weight, column.heights[out.top],
               out.counts >= likely_count, sums.logpi, sums.likely, sums.n_seen, sums.col)


__all__ = ["observe_column"]
