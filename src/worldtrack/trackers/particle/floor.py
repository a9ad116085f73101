"""Floor areas of the particle tracker: where detection filters scatter (§3.2) and where people stand.

* :class:`FloorRegion` — a floor area rasterised once, for scattering detection particles uniformly
  over it and testing whether they are still inside;
* :func:`raster_contains` — the walkable-floor test of many particles in one kernel pass
  (:func:`raster_blocks` lets it skip reading cells of blocks that are walkable throughout);
* :func:`polygon_distance` — how far floor points are from an entry region.

>>> ring = np.array([[0, 0], [2, 0], [2, 1], [0, 1]], float)
>>> polygon_distance([[3, 0.5], [1, 0.5]], ring).tolist()
[1.0, 0.0]
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
from numba import njit
from numpy.typing import ArrayLike

from worldtrack.scene.floor import WalkableRaster, points_in_polygon


@dataclass(frozen=True)
class FloorRegion:
    """A named floor area as a grid of cells (a :class:`~worldtrack.scene.floor.WalkableRaster`), for
    uniform sampling and inside tests.

    Cell ``(j, i)`` covers ``origin + (i, j)·cell`` to ``origin + (i + 1, j + 1)·cell``.

    Attributes
    ----------
    name : str
    raster : WalkableRaster — the cells; ``origin`` (2,) float, metres, ``cell`` (its
        ``resolution``) float, metres, and ``inside`` (ny, nx) bool read through to it
    """

    name: str
    raster: WalkableRaster

    @classmethod
    def rasterise(cls, name: str, bounds: tuple[float, float, float, float], cell: float,
                  test: Callable[[np.ndarray], np.ndarray]) -> "FloorRegion":
        """Cells of ``bounds = (x0, x1, y0, y1)`` whose centre passes ``test((N, 2) xy) -> (N,) bool``."""
        x0, x1, y0, y1 = bounds
        nx = max(1, int(np.ceil((x1 - x0) / cell)))
        ny = max(1, int(np.ceil((y1 - y0) / cell)))
        gx, gy = np.meshgrid(x0 + (np.arange(nx) + 0.5) * cell, y0 + (np.arange(ny) + 0.5) * cell)
        inside = np.asarray(test(np.column_stack([gx.ravel(), gy.ravel()])), dtype=bool).reshape(ny, nx)
        return cls(name, WalkableRaster(np.array([x0, y0], dtype=float), float(cell), inside))

    @property
    def origin(self) -> np.ndarray:
        return self.raster.origin

    @property
    def cell(self) -> float:
        return self.raster.resolution

    @property
    def inside(self) -> np.ndarray:
        return self.raster.inside

    @property
    def area(self) -> float:
        """m²"""
        return float(self.inside.sum()) * self.cell ** 2

    @property
    def empty(self) -> bool:
        return not bool(self.inside.any())

    def sample(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """(n, 2) points uniformly distributed over the region's cells, metres."""
        flat = np.flatnonzero(self.inside)
        k = flat[rng.integers(0, len(flat), size=n)]
        j, i = np.divmod(k, self.inside.shape[1])
        offs = rng.random((n, 2))
        return self.origin + (np.column_stack([i, j]) + offs) * self.cell

    def contains(self, xy: ArrayLike) -> np.ndarray:
        """(N,) bool: the point's cell is in the region (False for NaN)."""
        return self.raster.contains(xy)


def raster_contains(raster: WalkableRaster, xy: np.ndarray, blocks: np.ndarray | None = None) -> np.ndarray:
    """:meth:`WalkableRaster.contains <worldtrack.scene.floor.WalkableRaster.contains>` of ``xy`` (N, 2),
    metres (or the first two columns of (N, ≥ 2)), by a kernel (one pass instead of a dozen NumPy
    calls; tested equal): (N,) bool. ``blocks``: :func:`raster_blocks` of ``raster``, to read few
    cells (a 1 cm raster is a megabyte, mostly out of cache)."""
    xy = np.asarray(xy, dtype=np.float64)
    if xy.ndim != 2 or xy.shape[1] < 2:
        xy = xy.reshape(-1, 2)
    out = np.empty(len(xy), dtype=np.bool_)
    _raster_contains(xy, float(raster.origin[0]), float(raster.origin[1]), float(raster.resolution),
                     np.ascontiguousarray(raster.inside, dtype=np.bool_), NO_BLOCKS if blocks is None else blocks,
                     out)
    return out


#: Cells per side of a :func:`raster_blocks` block (a power of two).
RASTER_BLOCK = 32
NO_BLOCKS = np.zeros((0, 0), dtype=np.bool_)


def raster_blocks(raster: WalkableRaster) -> np.ndarray:
    """(⌈ny/32⌉, ⌈nx/32⌉) bool: which blocks of 32 × 32 cells of ``raster`` (fewer at the far edges) are
    inside throughout — where :func:`raster_contains` need not read the cell."""
    inside = np.asarray(raster.inside, dtype=bool)
    ny, nx = inside.shape
    b = RASTER_BLOCK
    pad = np.ones((-(-ny // b) * b, -(-nx // b) * b), dtype=bool)
    pad[:ny, :nx] = inside
    return pad.reshape(pad.shape[0] // b, b, pad.shape[1] // b, b).all(axis=(1, 3))


@njit(cache=True, inline="always")
def in_raster(x, y, x0, y0, resolution, inside, blocks):
    """The cell test of :meth:`WalkableRaster.contains` for one point (a block inside throughout answers first)."""
    ny, nx = inside.shape
    fi = (x - x0) / resolution
    fj = (y - y0) / resolution
    if not (fi >= 0 and fi < nx and fj >= 0 and fj < ny):
        return False
    i, j = int(fi), int(fj)
    if blocks.shape[0] and blocks[j // RASTER_BLOCK, i // RASTER_BLOCK]:
        return True
    return inside[j, i]


@njit(cache=True)
def _raster_contains(xy, x0, y0, resolution, inside, blocks, out):
    for k in range(xy.shape[0]):
        out[k] = in_raster(xy[k, 0], xy[k, 1], x0, y0, resolution, inside, blocks)


def polygon_distance(xy: ArrayLike, ring: ArrayLike) -> np.ndarray:
    """(N,) distance (m) from floor points to a polygon: 0 inside, else to the nearest edge."""
    p = np.asarray(xy, dtype=float).reshape(-1, 2)
    a = np.asarray(ring, dtype=float)
    ab = np.roll(a, -1, axis=0) - a
    ap = p[:, None, :] - a[None, :, :]
    s = np.clip((ap * ab).sum(axis=2) / np.maximum((ab * ab).sum(axis=1), 1e-12), 0.0, 1.0)
    d = np.sqrt(((ap - s[:, :, None] * ab) ** 2).sum(axis=2)).min(axis=1)
    return np.where(points_in_polygon(p, a), 0.0, d)


__all__ = ["RASTER_BLOCK", "FloorRegion", "polygon_distance", "raster_blocks", "raster_contains"]
