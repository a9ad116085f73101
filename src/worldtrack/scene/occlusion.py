"""Per-camera depth maps of the known obstacles (the paper's z-buffer of structures).

Built once per camera by casting one ray per pixel against every obstacle. Two depths are kept:

* ``floor_distance``: the paper's measure (seed 000, §3.3) — the distance in the Z = 0 plane from
  the camera's foot point to the obstacle surface seen at the pixel;
* ``depth``: the true 3-D depth along the optical axis (what a depth camera would measure).

A person pixel is hidden when the obstacle seen there is nearer than the person. Pixels that see
no obstacle hold ``inf``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from worldtrack.geometry.camera import Camera


@dataclass(frozen=True)
class OcclusionMap:
    """Obstacle depth per pixel of one camera.

    Attributes
    ----------
    camera : Camera
    floor_distance : (H, W) float32, metres — ``inf`` where no obstacle
    depth : (H, W) float32, metres along the optical axis — ``inf`` where no obstacle
    """

    camera: Camera
    floor_distance: np.ndarray
    depth: np.ndarray

    @classmethod
    def build(cls, camera: Camera, obstacles: Sequence, rows_per_chunk: int = 64) -> "OcclusionMap":
        """Ray-cast every pixel of ``camera`` against ``obstacles`` (Box or Patch objects)."""
        H, W = camera.height, camera.width
        floor = np.full((H, W), np.inf, dtype=np.float32)
        depth = np.full((H, W), np.inf, dtype=np.float32)
        if obstacles:
            u = np.arange(W, dtype=float)
            for v0 in range(0, H, rows_per_chunk):
                v1 = min(H, v0 + rows_per_chunk)
                vv, uu = np.meshgrid(np.arange(v0, v1, dtype=float), u, indexing="ij")
                origin, d = camera.rays(np.stack([uu.ravel(), vv.ravel()], axis=1))
                s = np.full(len(d), np.inf)
                for ob in obstacles:
                    s = np.minimum(s, ob.intersect(origin, d))
                hit = np.isfinite(s)
                pts = origin + s[hit, None] * d[hit]
                f = np.full(len(d), np.inf)
                z = np.full(len(d), np.inf)
                f[hit] = camera.floor_distance(pts)
                z[hit] = camera.depth(pts)
                floor[v0:v1] = f.reshape(v1 - v0, W)
                depth[v0:v1] = z.reshape(v1 - v0, W)
        floor.setflags(write=False)
        depth.setflags(write=False)
        return cls(camera, floor, depth)

    def hidden(self, uv: np.ndarray, distance: np.ndarray | float, true_depth: bool = False) -> np.ndarray:
        """Is a point at pixel ``uv`` and the given distance behind an obstacle?

        Parameters
        ----------
        uv : (N, 2) pixels (rounded to the nearest pixel; outside the image → not hidden)
        distance : (N,) or scalar, metres — floor distance, or depth with ``true_depth``
        true_depth : bool — compare optical-axis depths instead of the paper's floor distances

        Returns
        -------
        (N,) bool
        """
        uv = np.nan_to_num(np.asarray(uv, dtype=float).reshape(-1, 2), nan=-1.0, posinf=-1.0, neginf=-1.0)
        iu = np.round(uv[:, 0]).astype(np.int64)
        iv = np.round(uv[:, 1]).astype(np.int64)
        ok = (iu >= 0) & (iu < self.camera.width) & (iv >= 0) & (iv < self.camera.height)
        grid = self.depth if true_depth else self.floor_distance
        occ = np.full(len(uv), np.inf)
        occ[ok] = grid[iv[ok], iu[ok]]
        return occ < np.broadcast_to(np.asarray(distance, dtype=float), (len(uv),))
