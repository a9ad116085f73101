"""A crowd gate on height measurement: no height from a view where the person stands in a crowd.

A person's height is read from the foreground silhouette (:mod:`.height`): the feet back-projected
to the floor and the top of the head's ray above them. The people already tracked are left out of
the silhouette (their ellipses own their pixels), the people *not yet tracked* are not: in a crowd
one camera sees from a corner, somebody untracked standing behind a tracked person on the same line
of sight makes one silhouette whose top is their head — a height that is wrong but plausible, and
the taller ellipse then explains the head behind, so that person is never born (issue 37: with
height measurement off, crowd 50's dev seeds 110–112 held 9.0 → 11.0 people, session 10).

The gate looks at the band beside the person's body in the image — the ellipse of the same person
``BAND_WIDTHS`` times as wide, less their own ellipse: a person standing alone has floor there, a
person in a crowd has other people's foreground. Where foreground covers more than
``crowd.height_max_beside`` of the band in every view that shows the person, they are not measured
this frame (they keep the height they have: the prior, or what clearer frames measured).

>>> import numpy as np
>>> band = np.zeros((4, 6), bool); band[:, :2] = band[:, 4:] = True
>>> labels = np.zeros((4, 6), np.uint8); labels[:, 2:4] = 1            # alone: only the body
>>> beside_share(labels, band)
0.0
>>> labels[:, :2] = 1                                                   # somebody on one side
>>> beside_share(labels, band)
0.5
"""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from worldtrack.trackers.base import Person
from worldtrack.trackers.ellipsoid.cameras import CameraView
from worldtrack.trackers.ellipsoid.forms import ellipse_crop
from worldtrack.trackers.ellipsoid.height import heights_due

#: The band beside a person is the ellipse of the same person this many times as wide, less theirs.
BAND_WIDTHS = 3.0


def beside_share(labels: np.ndarray, band: np.ndarray) -> float:
    """Share of the ``band`` pixels ((h, w) bool) that are foreground (``labels`` == 1, (h, w)
    uint8); 0 for an empty band."""
    n = int(np.count_nonzero(band))
    return float(np.count_nonzero((labels == 1) & band)) / n if n else 0.0


def crowd_shares(people: Sequence[Person], view: CameraView, labels: np.ndarray) -> np.ndarray:
    """(N,) share of the band beside each of ``people`` that is foreground in one view (NaN where
    the person is not in its image).

    Parameters
    ----------
    people : the people, with floor place ``x, y`` (m), ``height`` and ``width`` (m)
    view : the camera's view
    labels : (H, W) uint8 — its foreground labels (1 = foreground)
    """
    xy = np.array([[p.x, p.y] for p in people], float).reshape(-1, 2)
    hs = np.array([p.height for p in people], float)
    ws = np.array([p.width for p in people], float)
    inner, _, _, valid, _ = view.forms(xy, hs, ws)
    wide, _, box, wide_valid, _ = view.forms(xy, hs, BAND_WIDTHS * ws)
    out = np.full(len(people), np.nan)
    for k in range(len(people)):
        u0, u1, v0, v1 = (int(b) for b in box[k])
        if not (valid[k] and wide_valid[k]) or u0 >= u1 or v0 >= v1:
            continue
        band = ellipse_crop(wide[k], box[k], view.grid, view.args.has_dist) \
            & ~ellipse_crop(inner[k], box[k], view.grid, view.args.has_dist)
        out[k] = beside_share(labels[v0:v1, u0:u1], band)
    return out


def uncrowded(due: Sequence[int], people: Sequence[Person], views: Mapping[str, CameraView],
              labels: Mapping[str, np.ndarray], max_beside: float) -> list[int]:
    """The indices of ``due`` (into ``people``) that some view shows with at most ``max_beside``
    of the band beside them foreground (``crowd.height_max_beside``; 1 or more: all of ``due``)."""
    if max_beside >= 1 or not due:
        return list(due)
    chosen = [people[k] for k in due]
    clear = np.zeros(len(chosen), bool)
    for cid, image_labels in labels.items():
        clear |= crowd_shares(chosen, views[cid], image_labels) <= max_beside   # NaN: not in view
    return [k for k, ok in zip(due, clear) if ok]


def heights_due_clear(judged: Sequence[Person], present: Sequence[Person], config, frame: int,
                      views: Mapping[str, CameraView], labels: Mapping[str, np.ndarray]) -> list[int]:
    """:func:`~.height.heights_due` of ``judged`` (the first people of ``present``), less those no
    view shows out of a crowd (:func:`uncrowded`, ``config.crowd.height_max_beside``); ``config`` is
    the :class:`~.config.EllipsoidConfig`."""
    return uncrowded(heights_due(judged, config.height, frame), present, views, labels,
                     config.crowd.height_max_beside)


__all__ = ["BAND_WIDTHS", "beside_share", "crowd_shares", "heights_due_clear", "uncrowded"]
