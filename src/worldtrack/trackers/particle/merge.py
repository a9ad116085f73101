"""Merging two filters on one object (worldtrack's): the younger of two tracking filters that stay on
one object ends, by the one duplicate rule of :func:`worldtrack.trackers.lifecycle.merge_duplicates`.

Two filters are on one object while their image boxes overlap by at least ``merge.overlap`` (of the
smaller box) in every camera that sees both, for ``merge.after_s`` seconds — or ``merge.far_after_s``
while their centres stand more than ``merge.distance_m`` apart on the floor: one camera's boxes also
overlap while two people pass one behind the other, which lasts a moment, and a filter stuck at the
wrong depth on its neighbour's object lasts longer. Beyond ``merge.depth_m`` from the nearest camera
that distance grows in proportion (one camera's depth error grows with distance).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Callable, Mapping, Sequence

import numpy as np
from scipy.spatial.distance import cdist

from worldtrack.trackers.base import Person, PositionMap
from worldtrack.trackers.lifecycle import frames_for, merge_duplicates
from worldtrack.trackers.particle.cloud import Cloud
from worldtrack.trackers.particle.likelihood.boxes import boxes_on_one_object
from worldtrack.trackers.particle.likelihood.camera import CameraLikelihood

if TYPE_CHECKING:
    from worldtrack.trackers.particle.config import ParticleConfig


class Merger:
    """Ends the younger of two tracking filters on one object.

    Parameters
    ----------
    cfg : ParticleConfig — its ``merge`` section
    cameras : {camera_id: CameraLikelihood}
    """

    def __init__(self, cfg: "ParticleConfig", cameras: Mapping[str, CameraLikelihood]):
        self.cfg, self.cameras = cfg.merge, cameras
        # (C, 2) metres: the cameras' floor positions, for the depth-scaled merge distance.
        self.camera_floor = np.array([cl.camera.centre[:2] for cl in cameras.values()], dtype=float).reshape(-1, 2)

    def merge(self, clouds: Sequence[Cloud], position_map: PositionMap, dt: float,
              end: Callable[[Person], None]) -> None:
        """Count the pairs of ``clouds`` on one object this frame (frame interval ``dt``, s) and end the
        younger of each pair that has been so long enough (``end(person)``)."""
        if len(clouds) < 2:
            merge_duplicates(position_map, {}, end)
            return
        persons = [position_map[c.person] for c in clouds]
        c = np.array([cl.centre for cl in clouds], dtype=float)
        widths, heights = [p.width for p in persons], [p.height for p in persons]
        close = boxes_on_one_object(np.stack([cam.box_array(c, widths, heights, 0.0) for cam in self.cameras.values()]),
                                    float(self.cfg.overlap))
        pairs = np.nonzero(close)
        if not len(pairs[0]):
            merge_duplicates(position_map, {}, end)
            return
        far = cdist(c, c) > self.distances(c)
        near_frames, far_frames = frames_for(self.cfg.after_s, dt), frames_for(self.cfg.far_after_s, dt)
        close_now, frames = set(), {}
        for i, j in zip(*pairs):
            a, b = persons[i].id, persons[j].id
            close_now.add((min(a, b), max(a, b)))
            # One behind the other on the floor: two people passing, unless it lasts.
            frames[(min(a, b), max(a, b))] = far_frames if far[i, j] else near_frames
        merge_duplicates(position_map, {pair: frames[pair] for pair in close_now}, end)

    def distances(self, centres: np.ndarray) -> np.ndarray:
        """(F, F) metres: how far apart on the floor two filters' centres (F, 2) may be and still count
        as one object: ``distance_m``, grown in proportion to the pair's floor distance from the nearest
        camera beyond ``depth_m``."""
        depth = cdist(centres, self.camera_floor).min(axis=1)
        pair = 0.5 * (depth[:, None] + depth[None, :])
        return self.cfg.distance_m * np.maximum(1.0, pair / self.cfg.depth_m)


__all__ = ["Merger"]
