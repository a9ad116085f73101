"""A person's step along one camera's line of sight is bounded by how fast people walk (opt-in).

With one camera, a frame's evidence about depth can be wrong by a metre at once: where a near
person walks in front of a far one, the merged silhouette's bottom is the near person's feet and
its top the far person's head, so the feet anchor reads a plausible height and moves the far
person's track ~1 m towards the camera in one frame (line-of-sight seed 410: 8.57 -> 7.60 -> 7.04 m);
the velocity learnt from that jump then carries the track on while the near person covers the far
one, until it sits on the near person (4.4 m, a duplicate) and the far one is born again 1.2 m too
far. A body cannot do that: people walk at ≤ 2 m/s and turn within a few frames. So, with
``depth.max_along_speed_mps`` > 0, after the matching, the feet anchor and the depth fusion, a
tracked person that one camera alone shows is kept within ``max_along_speed_mps`` × dt of their
last place along that camera's line of sight (across it the frame's place stands). Bounding the
step from the constant-velocity prediction instead bounds only the acceleration: the velocity
learnt from the bounded steps grew frame by frame and the track slid on at 3 m/s (seed 410). Evidence that is right but far off (a track that started at the wrong depth) still wins,
at walking speed, frame after frame. It did not help: the match's pull goes on at walking speed
(seed 410: the same slide at 2 m/s; 410 / 415 MOTA 0.616 / 0.471 -> 0.625 / 0.406). Kept, off, for
the record and as a building block.

>>> import numpy as np
>>> ray = np.array([0.0, 1.0])
>>> np.round(bounded_along(np.array([0.2, 7.0]), np.array([0.0, 8.0]), ray, 0.2), 2).tolist()  # 1 m nearer
[0.2, 7.8]
>>> np.round(bounded_along(np.array([0.2, 7.9]), np.array([0.0, 8.0]), ray, 0.2), 2).tolist()  # within reach
[0.2, 7.9]
"""

from __future__ import annotations

import numpy as np


def bounded_along(xy: np.ndarray, last: np.ndarray, ray: np.ndarray, reach_m: float) -> np.ndarray:
    """``xy`` (2,) m with its offset from ``last`` (2,) m along the unit floor direction ``ray``
    (2,) clipped to ±``reach_m`` (m); the offset across ``ray`` is kept."""
    off = np.asarray(xy, float) - np.asarray(last, float)
    along = float(off @ ray)
    clipped = float(np.clip(along, -reach_m, reach_m))
    return np.asarray(xy, float) + (clipped - along) * ray


def bound_steps(people, last: dict, lone_camera_centre, speed_mps: float, dt: float, walkable) -> int:
    """Keep each of ``people`` whose last place is in ``last`` (person -> (2,) m) within
    ``speed_mps`` × ``dt`` (m/s, s) of it along the line of sight of the one camera that shows them
    (``lone_camera_centre(index)`` -> that camera's centre (3,), or None when none or several do);
    a bounded place off the walkable floor (``walkable``: (M, 2) -> (M,) bool) is not taken.
    Returns how many people were moved."""
    if speed_mps <= 0 or dt <= 0:
        return 0
    moved = 0
    for k, p in enumerate(people):
        before = last.get(p)
        centre = lone_camera_centre(k) if before is not None else None
        if centre is None:
            continue
        xy = np.array([p.x, p.y], dtype=float)
        ray = xy - np.asarray(centre, float)[:2]
        norm = float(np.hypot(*ray))
        if norm < 1e-9:
            continue
        new = bounded_along(xy, before, ray / norm, speed_mps * dt)
        if np.allclose(new, xy) or not walkable(new[None])[0]:
            continue
        p.x, p.y = float(new[0]), float(new[1])
        moved += 1
    return moved


__all__ = ["bound_steps", "bounded_along"]
