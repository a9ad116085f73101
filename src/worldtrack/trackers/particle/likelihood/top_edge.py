"""The top edge (worldtrack's, with the column's ratio): the object's head read to a pixel at each
particle's own height.

The column reads its top on the ``dz`` grid (0.1 m: 5–10 pixels at 3–6 m). :func:`top_edge_terms`
reads a few samples just below and just above each particle's own object height, which the particle
carries from frame to frame: below it on the object (``on`` if they read object, ``off`` if
background), above it over it (``−on`` if they read object, nothing if background); a sample out of
view reads no evidence. One camera's column leaves a valley of (depth, height) pairs; with the height
held, the head's edge fixes depth along the line of sight where the feet, moving with the stride, do
not. :func:`top_edge_terms_reference` is the same written plainly (the tests check that they agree).

>>> top_edge_offsets(0.03, 2).round(2).tolist()
[-0.03, -0.06, 0.03, 0.06]
"""

from __future__ import annotations

import math
from typing import NamedTuple, Sequence

import numpy as np
from numba import njit

from worldtrack.geometry._kernels import lens
from worldtrack.geometry.camera import Camera
from worldtrack.trackers.particle.likelihood.column import pixels, readable
from worldtrack.trackers.particle.likelihood.reading import (OUT_OF_VIEW, ReadAs, box_of, filter_rows, occluded,
                                                                 pixel_of, read_line)


class EdgeSpec(NamedTuple):
    """The top-edge samples: ``offsets`` (E,) float64, metres, relative to the particle's height
    (:func:`top_edge_offsets`); ``weight`` multiplies the sum of the terms; ``on``, ``off`` the
    column's log-ratio terms."""

    offsets: np.ndarray
    weight: float
    on: float
    off: float


def top_edge_offsets(step: float, samples: int) -> np.ndarray:
    """(2·samples,) float64, metres: the top-edge sample heights relative to a particle's top,
    ``−step, −2·step, …`` (on the object) then ``step, 2·step, …`` (over it)."""
    steps = float(step) * np.arange(1, int(samples) + 1)
    return np.concatenate([-steps, steps])


def edge_spec(offsets: np.ndarray, weight: float, on: float, off: float) -> EdgeSpec:
    """An :class:`EdgeSpec` with the kernel's types."""
    return EdgeSpec(np.ascontiguousarray(offsets, dtype=np.float64), float(weight), float(on), float(off))


@njit(cache=True)
def top_edge_terms(xy, tops, edge, camera, reading, out):
    """Add the weighted top-edge terms at each particle's own height to ``out`` (N,), in place.

    Parameters
    ----------
    xy : (N, ≥ 2) float64, metres — particles' floor positions (columns 0, 1)
    tops : (N,) float64, metres — the particles' object heights
    edge : EdgeSpec
    camera : CameraArgs
    reading : Reading — each sample is read as a column sample on the particle's axis is: in another
        object's box it reads background, or no evidence if that object is nearer by more than the
        margin
    out : (N,) float64 — in/out
    """
    codes, boxes, which, pairs, depths, mes, margin = (reading.codes, reading.boxes, reading.which, reading.pairs,
                                                       reading.depths, reading.mes, reading.margin)
    offsets, weight, on, off = edge.offsets, edge.weight, edge.on, edge.off
    centre = camera.centre
    H, W = codes.shape
    lens_ = lens(camera.K, camera.dist)
    for i in range(xy.shape[0]):
        box = box_of(boxes, which[i])
        me = mes[which[i]]
        depth = math.hypot(xy[i, 0] - centre[0], xy[i, 1] - centre[1])
        s = 0.0
        for j in range(offsets.shape[0]):
            iu, iv = pixel_of(xy[i, 0], xy[i, 1], tops[i] + offsets[j], camera, lens_, W, H)
            if iu < 0:
                continue                                    # out of view: no evidence
            lab, other = read_line(codes, box, iu, iv, OUT_OF_VIEW)
            if other and occluded(pairs, depths, me, iu, iv, depth, margin):
                continue                                    # behind a nearer object: no evidence
            if offsets[j] < 0.0:
                if lab == 1:
                    s += on
                elif lab == 0:
                    s += off
            elif lab == 1:
                s -= on
        out[i] += weight * s


def top_edge_terms_reference(camera: Camera, hit: np.ndarray, xy: np.ndarray, tops: np.ndarray,
                             offsets: Sequence[float], on: float, off: float, weight: float = 1.0,
                             read: ReadAs | None = None) -> np.ndarray:
    """:func:`top_edge_terms` written plainly: (N,) the weighted top-edge terms of each particle,
    read as ``read`` says (its owner, box, occluders, me, margin and which)."""
    read = read or ReadAs()
    tops = np.asarray(tops, dtype=float)
    xy = np.asarray(xy, dtype=float).reshape(len(tops), -1)[:, :2]
    offsets = np.asarray(offsets, dtype=float)
    boxes, mes, which = filter_rows(read.box, read.me, read.which, len(xy))
    points = np.concatenate([np.broadcast_to(xy[:, None, :], (len(xy), len(offsets), 2)),
                             (tops[:, None] + offsets)[..., None]], axis=-1)
    iu, iv, inside = pixels(camera, points)
    ok = readable(read.owner, boxes[which], iu, iv)
    lab = np.where(ok, hit[iv, iu], 0)                    # in another object's box: background
    lab = np.where(inside, lab, 2)
    if read.occluders is not None and read.occluders.pairs.size:
        nearer = read.occluders.depth_for(mes[which][:, None], iv, iu) < camera.floor_rays(xy)[1][:, None] - read.margin
        lab = np.where(inside & ~ok & nearer, 2, lab)
    below = offsets < 0
    terms = np.where(below, np.where(lab == 1, on, np.where(lab == 0, off, 0.0)), np.where(lab == 1, -on, 0.0))
    return weight * terms.sum(axis=1)


__all__ = ["EdgeSpec", "edge_spec", "top_edge_offsets", "top_edge_terms", "top_edge_terms_reference"]
