"""A person walking behind a pillar keeps a coasting track instead of ending as "left the view".

The life cycle ends a track that no camera shows for ``end.leave_after_s`` (0.2 s): a person who
walked out of the image. "Shows" counts the ellipse's pixels in the image and in front of the
scene's obstacles (:mod:`.support`), so a person who walks behind a pillar, a column or a tall
shelf ends the same way, two frames after disappearing, and comes back only as a new birth —
which, in a crowd, the foreground merged with the others' seldom gives. In the one-camera crowd of
50 (``benchmarks/crowd50.py``, dev seeds 0–2, started on everyone) 24 tracks ended so, behind the
hall's pillars and table, against 10 that walked out of the image.

With ``crowd.coast_behind_obstacles_s`` > 0, a track whose body (feet, middle and head points)
some camera has in its image but wholly behind obstacles, from the scene's occlusion maps, is not
ended for being unseen until it has been unseen that long; meanwhile the prediction carries it
(the matching cannot move a person no camera shows), and it is matched again once it steps out.

>>> from worldtrack.scene import scene_from_dict
>>> scene = scene_from_dict({
...     "cameras": [{"id": "c", "image_size": [160, 120], "position": [0, -4, 2.6], "look_at": [0, 0, 0.8],
...                  "hfov_deg": 60}],
...     "floor": {"walkable": [{"outer": [[-4, -3], [4, -3], [4, 5], [-4, 5]]}]},
...     "obstacles": [{"type": "box", "name": "pillar", "centre": [0, 0, 1.5], "size": [0.6, 0.6, 3.0]}]})
>>> behind_obstacles(np.array([[0.0, 1.5], [2.0, 1.5], [30.0, 0.0]]), np.full(3, 1.7),   # behind, beside, out
...                  list(scene.cameras.values()), scene.occlusion).tolist()
[True, False, False]
"""

from __future__ import annotations

from typing import Callable, Sequence

import numpy as np

from worldtrack.geometry.camera import Camera

#: Heights on the body, as shares of its height, whose pixels must all be hidden.
BODY_SHARES = (0.0, 0.5, 1.0)


def behind_obstacles(xy: np.ndarray, heights: np.ndarray, cameras: Sequence[Camera],
                     occlusion: Callable[[str], object]) -> np.ndarray:
    """Whether each person's body is in some camera's image but hidden there by obstacles.

    Parameters
    ----------
    xy : (N, 2) float — floor positions, m
    heights : (N,) float — body heights, m
    cameras : the tracker's cameras
    occlusion : camera id → the scene's occlusion map of that camera (``scene.occlusion``)

    Returns
    -------
    (N,) bool — some camera has at least one of the body's points (feet, middle, head) in its
    image and every such point behind an obstacle nearer than the person
    """
    xy = np.asarray(xy, float).reshape(-1, 2)
    n, k = len(xy), len(BODY_SHARES)
    z = np.asarray(heights, float)[:, None] * np.array(BODY_SHARES)[None]
    pts = np.concatenate([np.repeat(xy, k, axis=0), z.reshape(-1, 1)], axis=1)
    out = np.zeros(n, dtype=bool)
    for cam in cameras:
        uv = cam.project(pts)
        inside = cam.in_image(uv).reshape(n, k)
        hidden = occlusion(cam.id).hidden(uv, cam.floor_distance(pts) - 0.05).reshape(n, k)
        out |= inside.any(axis=1) & (hidden | ~inside).all(axis=1)
    return out


__all__ = ["BODY_SHARES", "behind_obstacles"]
