"""Whether one camera sees where each person stands: their feet in its image, in front of the
scene's obstacles and of everybody nearer to it.

One camera measures a person's depth by where their silhouette meets the floor. With the feet in
view and nobody in front of them (:mod:`.legs`, :mod:`.feet`), the matched ellipse's bottom sits on
them and its place along the line of sight is fixed; with the feet covered by somebody nearer
(a crowd seen from a corner) or by a table, only the head and the silhouette's size say how far the
person is, and the match slides along the ray inside the merged blob (:mod:`.prediction`). On PETS
2009 walkers in pairs share much of their outline (``own_share`` < 0.5) while their feet stay in
view; the test here is on the feet alone.

>>> from worldtrack.scene import scene_from_dict
>>> from worldtrack.trackers.ellipsoid.cameras import CameraView
>>> scene = scene_from_dict({
...     "cameras": [{"id": "c", "image_size": [160, 120], "position": [0, -4, 2.6], "look_at": [0, 0, 0.8],
...                  "hfov_deg": 60}],
...     "floor": {"walkable": [{"outer": [[-4, -3], [4, -3], [4, 5], [-4, 5]]}]}})
>>> from worldtrack.trackers.ellipsoid.config import EllipsoidConfig
>>> from worldtrack.trackers.ellipsoid.tracker import EllipsoidTracker
>>> from worldtrack.foreground import make_foregrounds
>>> import numpy as np
>>> view = EllipsoidTracker(scene, make_foregrounds(scene, {"c": np.zeros((120, 160, 3), np.uint8)}, "colour"),
...                         EllipsoidConfig()).views["c"]
>>> xy = np.array([[0.0, 0.0], [0.0, 1.0], [2.0, 0.0]])      # one behind the other, one beside
>>> feet_in_view(view, xy, np.full(3, 1.7), np.full(3, 0.45)).tolist()
[True, False, True]
"""

from __future__ import annotations

import numpy as np

from worldtrack.trackers.ellipsoid.cameras import CameraView

#: Height above the floor (m) of the point tested for each person: the ankles, inside their ellipse.
FEET_Z_M = 0.1


def feet_in_view(view: CameraView, xy: np.ndarray, heights: np.ndarray, widths: np.ndarray,
                 obstacles: bool = True) -> np.ndarray:
    """Whether ``view``'s camera sees each person's feet.

    Parameters
    ----------
    view : the camera's view (its ellipse drawing, undistortion grid and obstacle map)
    xy : (N, 2) float — everyone's floor positions, m (all the people who may cover each other)
    heights, widths : (N,) float — their body sizes, m
    obstacles : bool — the scene's obstacles hide feet (False: only the image's edge and people do)

    Returns
    -------
    (N,) bool — the point :data:`FEET_Z_M` above each person's floor place projects into the image,
    in front of the scene's obstacles, and outside the ellipse of every person nearer to the camera
    """
    xy = np.asarray(xy, float).reshape(-1, 2)
    n = len(xy)
    if n == 0:
        return np.zeros(0, dtype=bool)
    cam = view.camera
    inner, _, _, valid, dist = view.forms(xy, np.asarray(heights, float), np.asarray(widths, float))
    uv = cam.project(np.column_stack([xy, np.full(n, FEET_Z_M)]))
    u = np.clip(np.round(uv[:, 0]).astype(int), 0, cam.width - 1)
    v = np.clip(np.round(uv[:, 1]).astype(int), 0, cam.height - 1)
    ok = valid & cam.in_image(uv)
    if obstacles:
        ok &= view.occ[v, u] >= dist                   # no obstacle in front
    if view.args.has_dist:                             # the ellipses are drawn in ideal coordinates
        pu, pv = view.grid[v, u, 0].astype(float), view.grid[v, u, 1].astype(float)
    else:
        pu, pv = uv[:, 0], uv[:, 1]
    f = inner[valid]                                   # (M, 5): centre u, v and the normal form
    du, dv = pu[:, None] - f[None, :, 0], pv[:, None] - f[None, :, 1]
    within = f[None, :, 2] * du * du + 2.0 * f[None, :, 3] * du * dv + f[None, :, 4] * dv * dv < 1.0
    nearer = dist[valid][None, :] < dist[:, None]      # (N, M): the other person is nearer
    ok &= ~(within & nearer).any(axis=1)
    return ok


__all__ = ["FEET_Z_M", "feet_in_view"]
