"""Who others cover in some camera: the encounters after which a person's height is measured afresh.

When two people cross on a camera's line of sight, a track may take the other person's place and
keep its measured height; a height is final once its samples are in, so the wrong height then
holds the track metres off along the line of sight for the rest of the video (a 1.89 m and a
1.66 m person swapped heights that way and sat 1.2–1.4 m off for 7 s). With
``depth.remeasure_after_encounter``, a person whose region others' ellipses cover is noted, and
once clear again their height samples are dropped (:meth:`DepthFusion.note_encounter`). With
``depth.fuse`` the fusion notes them as it goes; without it, :func:`covered_in_some_view` does.

"""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from worldtrack.trackers.base import Person
from worldtrack.trackers.ellipsoid.cameras import CameraView
from worldtrack.trackers.ellipsoid.forms import ellipse_crop, owner_crop
from worldtrack.trackers.ellipsoid.height import MAX_COVERED_FOR_HEIGHT


def covered_in_some_view(people: Sequence[Person], views: Mapping[str, CameraView], max_height_m: float) -> list[bool]:
    """Per person: in some camera, others' ellipses cover more than :data:`MAX_COVERED_FOR_HEIGHT`
    of their region (the ellipse of the tallest plausible person, ``max_height_m``, with its ring)
    — the views in which no height is measured. Only tracked people can be covered."""
    if not people:
        return []
    xy = np.array([[p.x, p.y] for p in people], dtype=float)
    hs = np.array([p.height for p in people], dtype=float)
    ws = np.array([p.width for p in people], dtype=float)
    covered = [False] * len(people)
    for view in views.values():
        cam = view.camera
        _, ring, box, valid, _ = view.forms(xy, np.full(len(xy), max_height_m), 1.25 * ws)
        current = view.forms(xy, hs, ws)
        for k, p in enumerate(people):
            u0, u1, v0, v1 = box[k]
            if covered[k] or not valid[k] or p.mode != "tracking" or u0 >= u1 or v0 >= v1:
                continue
            region = ellipse_crop(ring[k], box[k], view.grid, cam.has_distortion)
            owner = owner_crop(box[k], current, view.grid, cam.has_distortion)
            others = region & (owner != k) & (owner != -1)
            covered[k] = bool(np.count_nonzero(others) > MAX_COVERED_FOR_HEIGHT * np.count_nonzero(region))
    return covered


__all__ = ["covered_in_some_view"]
