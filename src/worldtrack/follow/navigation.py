"""Where the robot can drive, and how far a goal is round the obstacles (worldtrack; seed 001 has no map).

The follower knows its room: the scene's walkable area, whose signed distance field says how far
each floor point is from the nearest wall, kiosk or desk. :class:`NavigationGrid` turns it into

* ``clearance(xy)`` — that distance (m), bilinear, ``-1`` off the map;
* ``line_of_sight(a, b)`` — whether the straight segment from each ``a`` to ``b`` stays clear of
  every obstacle (the camera sees over nothing the map calls blocked);
* ``geodesic(goal)`` — the length (m) of the shortest drivable path from every cell to ``goal``
  on a grid whose free cells keep the robot's radius from any obstacle (8-connected, Dijkstra:
  ``scipy.sparse.csgraph.dijkstra``), so a goal behind the kiosk is as far as the way round it.

>>> from worldtrack.synth import make_scenario
>>> sc = make_scenario("follow-target", size=(160, 120), frames=2, seed=0, others=0)
>>> nav = NavigationGrid(sc.scene)
>>> bool(nav.clearance([[8.0, 6.0]])[0] < 0), bool(nav.clearance([[8.0, 4.0]])[0] > 0.3)   # the bench; open floor
(True, True)
>>> g = nav.geodesic((8.0, 7.0))                          # just north of the bench (8 ± 0.9, 6 ± 0.25)
>>> way = float(g.sample([[8.0, 5.0]])[0])                # 2 m south as the crow flies
>>> bool(3.6 < way < 4.0)                                 # round the bench's end, 0.3 m clear: 3.66 m
True
"""

from __future__ import annotations

import numpy as np
from scipy import sparse
from scipy.sparse.csgraph import dijkstra

from worldtrack.scene.floor import FloorGrid

#: Path cost of leaving the map (m): larger than any way round.
FAR = 1e3


class NavigationGrid:
    """The scene's obstacles for a robot of ``radius`` m (see the module docstring).

    scene : the Scene (its walkable area); resolution : geodesic grid cell (m);
    radius : the robot's radius (m): a cell is drivable when its clearance exceeds it
    """

    def __init__(self, scene, resolution: float = 0.1, radius: float = 0.3):
        self.field = scene.distance_field(0.05)
        self.radius = float(radius)
        x0, y0 = self.field.origin
        h, w = self.field.values.shape
        span = (np.array([w, h]) - 1) * self.field.resolution
        nx, ny = int(span[0] / resolution) + 1, int(span[1] / resolution) + 1
        self.origin, self.resolution, self.shape = np.array([x0, y0]), float(resolution), (ny, nx)
        gx, gy = np.meshgrid(x0 + np.arange(nx) * resolution, y0 + np.arange(ny) * resolution)
        self.free = self.clearance(np.column_stack([gx.ravel(), gy.ravel()])).reshape(ny, nx) > self.radius
        self._graph = _grid_graph(self.free, resolution)

    def clearance(self, xy) -> np.ndarray:
        """(N,) distance (m) from floor points (N, 2) to the nearest wall or obstacle; −1 off the map."""
        return self.field.sample(np.asarray(xy, float).reshape(-1, 2), outside=-1.0)

    def line_of_sight(self, a, b, step: float = 0.1) -> np.ndarray:
        """(N,) bool: the segments from points ``a`` (N, 2) to ``b`` (2,) or (N, 2) cross no obstacle."""
        a = np.asarray(a, float).reshape(-1, 2)
        b = np.broadcast_to(np.asarray(b, float), a.shape)
        n = max(2, int(np.ceil(np.hypot(*(b - a).T).max(initial=0.0) / step)) + 1)
        s = np.linspace(0.0, 1.0, n)
        pts = a[:, None] + s[None, :, None] * (b - a)[:, None]
        return (self.clearance(pts.reshape(-1, 2)).reshape(len(a), n) > 0.0).all(axis=1)

    def geodesic(self, goal) -> FloorGrid:
        """Drivable path length (m) from every grid cell to ``goal`` (2,) (the nearest free cell to it
        when it stands in a blocked one); :data:`FAR` where no path leads."""
        ny, nx = self.shape
        cell = np.rint((np.asarray(goal, float) - self.origin) / self.resolution).astype(int)
        idx = np.clip(cell, 0, [nx - 1, ny - 1])
        start = idx[1] * nx + idx[0]
        if not self.free.ravel()[start]:
            fj, fi = np.nonzero(self.free)
            if len(fj) == 0:
                return FloorGrid(self.origin, self.resolution, np.full(self.shape, FAR))
            k = int(np.argmin((fi - idx[0]) ** 2 + (fj - idx[1]) ** 2))
            start = fj[k] * nx + fi[k]
        d = dijkstra(self._graph, indices=start, directed=False)
        d = np.where(np.isfinite(d), d, FAR).reshape(self.shape)
        return FloorGrid(self.origin, self.resolution, d)


def _grid_graph(free: np.ndarray, res: float) -> sparse.csr_matrix:
    """8-connected graph of the free cells of ``free`` (ny, nx), edge lengths in metres."""
    ny, nx = free.shape
    ids = np.arange(ny * nx).reshape(ny, nx)
    rows, cols, lengths = [], [], []
    for dj, di in ((0, 1), (1, 0), (1, 1), (1, -1)):
        r0, r1, c0, c1 = max(0, -dj), ny - max(0, dj), max(0, -di), nx - max(0, di)
        a, b = ids[r0:r1, c0:c1], ids[r0 + dj:r1 + dj, c0 + di:c1 + di]
        ok = free.ravel()[a.ravel()] & free.ravel()[b.ravel()]
        rows.append(a.ravel()[ok])
        cols.append(b.ravel()[ok])
        lengths.append(np.full(ok.sum(), res * np.hypot(dj, di)))
    return sparse.csr_matrix((np.concatenate(lengths), (np.concatenate(rows), np.concatenate(cols))),
                             shape=(ny * nx, ny * nx))
