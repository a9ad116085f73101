"""The floor: walkable area, point-in-area tests and the distance field of walls and obstacles.

All coordinates are floor (X, Y) in metres. Polygons are (M, 2) arrays of vertices in order,
not closed (the last vertex is not a copy of the first).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike
from scipy import ndimage


#: Point-edge pairs tested at once by :func:`points_in_polygon` (bounds its temporary arrays).
_PAIRS_PER_CHUNK = 2_000_000
#: Most cells of a floor raster or distance field; a finer grid over a large floor is coarsened.
MAX_GRID_CELLS = 16_000_000


def grid_resolution(bounds: tuple[float, float, float, float], resolution: float,
                    max_cells: int = MAX_GRID_CELLS) -> float:
    """``resolution`` (m), or the finest coarser one whose grid over ``bounds`` has at most ``max_cells``.

    >>> grid_resolution((0.0, 10.0, 0.0, 10.0), 0.01)
    0.01
    >>> round(grid_resolution((0.0, 1000.0, 0.0, 1000.0), 0.01), 4)
    0.25
    """
    x0, x1, y0, y1 = bounds
    cells = ((x1 - x0) / resolution + 2) * ((y1 - y0) / resolution + 2)
    if cells <= max_cells:
        return resolution
    return float(np.sqrt((x1 - x0 + 2 * resolution) * (y1 - y0 + 2 * resolution) / max_cells)) * 1.0001


def points_in_polygon(points: ArrayLike, ring: ArrayLike) -> np.ndarray:
    """Even-odd (crossing number) test of many points against one polygon ring.

    Parameters
    ----------
    points : (N, 2) array_like, metres
    ring : (M, 2) array_like, metres

    Returns
    -------
    (N,) bool ndarray
        True strictly inside; points exactly on an edge may go either way.
    """
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    a = np.asarray(ring, dtype=float)
    b = np.roll(a, -1, axis=0)
    out = np.empty(len(p), dtype=bool)
    chunk = max(1, _PAIRS_PER_CHUNK // max(len(a), 1))  # bounded memory: (chunk, M) temporaries
    for start in range(0, len(p), chunk):
        x, y = p[start:start + chunk, 0:1], p[start:start + chunk, 1:2]   # (n, 1) against (M,) edges
        straddles = (a[:, 1] > y) != (b[:, 1] > y)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            x_cross = a[:, 0] + (y - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
        out[start:start + chunk] = np.count_nonzero(straddles & (x < x_cross), axis=1) % 2 == 1
    return out


def polygon_area(ring: ArrayLike) -> float:
    """Unsigned area (m²) of a simple polygon by the shoelace formula."""
    a = np.asarray(ring, dtype=float)
    x, y = a[:, 0], a[:, 1]
    return float(abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))) / 2.0)


@dataclass(frozen=True)
class FloorPolygon:
    """One walkable polygon with optional holes (columns, pillars…)."""

    outer: np.ndarray
    holes: tuple[np.ndarray, ...] = ()

    def contains(self, xy: ArrayLike) -> np.ndarray:
        """(N,) bool: inside the outer ring and outside every hole."""
        inside = points_in_polygon(xy, self.outer)
        for hole in self.holes:
            inside &= ~points_in_polygon(xy, hole)
        return inside

    @property
    def area(self) -> float:
        return polygon_area(self.outer) - sum(polygon_area(h) for h in self.holes)


@dataclass(frozen=True)
class FloorGrid:
    """A scalar field sampled on a regular floor grid.

    ``values[j, i]`` is the value at ``(origin[0] + i·resolution, origin[1] + j·resolution)``.
    """

    origin: np.ndarray
    resolution: float
    values: np.ndarray

    def sample(self, xy: ArrayLike, outside: float = 0.0) -> np.ndarray:
        """Bilinear interpolation at floor points (N, 2) → (N,); ``outside`` beyond the grid."""
        p = np.asarray(xy, dtype=float).reshape(-1, 2)
        coords = np.vstack([(p[:, 1] - self.origin[1]) / self.resolution,
                            (p[:, 0] - self.origin[0]) / self.resolution])
        return ndimage.map_coordinates(self.values, coords, order=1, mode="constant", cval=outside)

    def gradient(self, xy: ArrayLike) -> np.ndarray:
        """Spatial gradient (N, 2) of the field at floor points, per metre (central differences)."""
        p = np.asarray(xy, dtype=float).reshape(-1, 2)
        h = self.resolution
        gx = (self.sample(p + [h, 0]) - self.sample(p - [h, 0])) / (2 * h)
        gy = (self.sample(p + [0, h]) - self.sample(p - [0, h])) / (2 * h)
        return np.column_stack([gx, gy])


@dataclass(frozen=True)
class WalkableArea:
    """Where people can stand: the floor polygons minus the footprints of blocking obstacles.

    Parameters
    ----------
    polygons : tuple of FloorPolygon
    blocked : tuple of (M, 2) ndarray
        Footprints of obstacles a person cannot stand in (desks, shelves).
    """

    polygons: tuple[FloorPolygon, ...]
    blocked: tuple[np.ndarray, ...] = field(default=())

    def on_floor(self, xy: ArrayLike) -> np.ndarray:
        """(N,) bool: inside some floor polygon (obstacles ignored)."""
        p = np.asarray(xy, dtype=float).reshape(-1, 2)
        inside = np.zeros(len(p), dtype=bool)
        for poly in self.polygons:
            inside |= poly.contains(p)
        return inside

    def contains(self, xy: ArrayLike) -> np.ndarray:
        """(N,) bool: on the floor and not inside a blocking obstacle's footprint."""
        p = np.asarray(xy, dtype=float).reshape(-1, 2)
        inside = self.on_floor(p)
        for ring in self.blocked:
            if len(ring) >= 3 and polygon_area(ring) > 1e-9:
                inside &= ~points_in_polygon(p, ring)
        return inside

    def raster(self, resolution: float = 0.01) -> "WalkableRaster":
        """The walkable area sampled on a grid, for O(1) look-ups in hot loops (cached).

        The grid has at most :data:`MAX_GRID_CELLS` cells: over a large floor it is coarser than
        ``resolution`` (read :attr:`WalkableRaster.resolution`)."""
        cache = self.__dict__.setdefault("_rasters", {})
        if resolution not in cache:
            asked, resolution = resolution, grid_resolution(self.bounds, resolution)
            x0, x1, y0, y1 = self.bounds
            xs = np.arange(x0, x1 + resolution, resolution)
            ys = np.arange(y0, y1 + resolution, resolution)
            gx, gy = np.meshgrid(xs + resolution / 2, ys + resolution / 2)
            inside = self.contains(np.column_stack([gx.ravel(), gy.ravel()])).reshape(gx.shape)
            cache[asked] = WalkableRaster(np.array([x0, y0]), resolution, inside)
            resolution = asked
        return cache[resolution]

    @property
    def area(self) -> float:
        """Floor area in m² (obstacle footprints not subtracted)."""
        return float(sum(p.area for p in self.polygons))

    @cached_property
    def bounds(self) -> tuple[float, float, float, float]:
        """(x_min, x_max, y_min, y_max) of the floor polygons, metres."""
        pts = np.vstack([p.outer for p in self.polygons])
        return (float(pts[:, 0].min()), float(pts[:, 0].max()),
                float(pts[:, 1].min()), float(pts[:, 1].max()))

    def distance_field(self, resolution: float = 0.05, margin: float = 0.5) -> FloorGrid:
        """Signed distance (m) to the nearest wall or obstacle on a floor grid.

        Positive inside the walkable area (distance to the nearest non-walkable cell), negative
        outside (minus the distance to the nearest walkable cell). Thin obstacles (vertical
        partitions, whose footprint is a segment) are rasterised as lines so they still count.
        Paper 002's environment model ``e_h(d_h)`` reads this field. Over a large floor the grid is
        coarser than ``resolution`` (at most :data:`MAX_GRID_CELLS` cells; read
        :attr:`FloorGrid.resolution`).
        """
        x0, x1, y0, y1 = self.bounds
        resolution = grid_resolution((x0 - margin, x1 + margin, y0 - margin, y1 + margin), resolution)
        xs = np.arange(x0 - margin, x1 + margin + resolution / 2, resolution)
        ys = np.arange(y0 - margin, y1 + margin + resolution / 2, resolution)
        gx, gy = np.meshgrid(xs, ys)
        walk = self.contains(np.column_stack([gx.ravel(), gy.ravel()])).reshape(gx.shape)
        for ring in self.blocked:
            _rasterise_segments(walk, ring, xs[0], ys[0], resolution)
        inside = ndimage.distance_transform_edt(walk) * resolution
        outside = ndimage.distance_transform_edt(~walk) * resolution
        # Cell centres: the boundary lies half a cell from the first cell on either side.
        values = np.where(walk, inside - resolution / 2, -(outside - resolution / 2))
        return FloorGrid(np.array([xs[0], ys[0]]), resolution, values)


@dataclass(frozen=True)
class WalkableRaster:
    """Walkable cells of a floor grid: cell (j, i) covers ``origin + (i, j)·resolution`` onwards."""

    origin: np.ndarray
    resolution: float
    inside: np.ndarray

    def contains(self, xy: ArrayLike) -> np.ndarray:
        """(N,) bool, exact to one cell (``resolution`` metres) at the boundary."""
        p = np.asarray(xy, dtype=float).reshape(-1, 2)
        with np.errstate(invalid="ignore"):
            fi = (p[:, 0] - self.origin[0]) / self.resolution
            fj = (p[:, 1] - self.origin[1]) / self.resolution
            ok = (fi >= 0) & (fi < self.inside.shape[1]) & (fj >= 0) & (fj < self.inside.shape[0])
        i = fi[ok].astype(np.int64)
        j = fj[ok].astype(np.int64)
        out = np.zeros(len(p), dtype=bool)
        out[ok] = self.inside[j, i]
        return out


def _rasterise_segments(walk: np.ndarray, ring: np.ndarray, x0: float, y0: float, res: float) -> None:
    """Mark grid cells along a footprint's edges as not walkable (in place)."""
    a = np.asarray(ring, dtype=float)
    b = np.roll(a, -1, axis=0)
    for p, q in zip(a, b):
        n = int(np.ceil(np.linalg.norm(q - p) / (res / 2))) + 1
        s = np.linspace(0.0, 1.0, n)[:, None]
        pts = p + s * (q - p)
        i = np.round((pts[:, 0] - x0) / res).astype(int)
        j = np.round((pts[:, 1] - y0) / res).astype(int)
        ok = (i >= 0) & (i < walk.shape[1]) & (j >= 0) & (j < walk.shape[0])
        walk[j[ok], i[ok]] = False


@dataclass(frozen=True)
class EntryRegion:
    """A named floor polygon where people appear and leave (a door, a corridor end)."""

    name: str
    polygon: np.ndarray

    def contains(self, xy: ArrayLike) -> np.ndarray:
        return points_in_polygon(xy, self.polygon)


def entry_region_index(regions: tuple[EntryRegion, ...] | list[EntryRegion], xy: ArrayLike) -> np.ndarray:
    """(N,) int: index of the first entry region containing each point, −1 if none."""
    p = np.asarray(xy, dtype=float).reshape(-1, 2)
    out = np.full(len(p), -1, dtype=int)
    for k in range(len(regions) - 1, -1, -1):
        out[regions[k].contains(p)] = k
    return out
