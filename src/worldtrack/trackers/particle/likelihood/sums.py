"""The likelihood summed over cameras: each camera's share added, then the particles no camera sees.

The likelihood of a particle multiplies over the cameras that see it (worldtrack's several-camera
extension of seed 004): :func:`add_camera` adds one camera's log-likelihood where it sees the particle;
:func:`close_sums` then gives −inf (weight 0, not likely) to particles that no camera sees or that
stand off the walkable floor. Each has a NumPy reference (the tracker's former code; tested equal).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from worldtrack.scene.floor import WalkableRaster
from worldtrack.trackers.particle.floor import NO_BLOCKS, in_raster


class Sums(NamedTuple):
    """The likelihood of N particles summed over cameras so far: ``logpi`` (N,) float64, ``likely``
    (N,) bool, ``n_seen`` (N,) int32 cameras that see each, ``col`` (N,) float64 the sum of their
    column heights (metres)."""

    logpi: np.ndarray
    likely: np.ndarray
    n_seen: np.ndarray
    col: np.ndarray

    @staticmethod
    def start(n: int) -> "Sums":
        """No camera yet: log-likelihood 0, every particle likely."""
        return Sums(np.zeros(n), np.ones(n, dtype=bool), np.zeros(n, dtype=np.int32), np.zeros(n))


@njit(cache=True)
def add_camera(seen: np.ndarray, lv: np.ndarray, penalty: np.ndarray, weight: float, col_h: np.ndarray,
               ok: np.ndarray, logpi: np.ndarray, likely: np.ndarray, n_seen: np.ndarray, col: np.ndarray) -> None:
    """One camera's share of a likelihood summed over cameras, in place (N particles):
    ``logpi += lv + weight·penalty`` where the camera sees the particle (``+ 0`` elsewhere; no
    penalty term when ``penalty`` is empty), ``likely &= ok | ~seen``, ``n_seen += seen``,
    ``col += col_h`` where seen. The arithmetic of :func:`add_camera_reference`, one pass."""
    pen = penalty.shape[0] > 0
    for i in range(seen.shape[0]):
        s = seen[i]
        v = lv[i]
        if pen:
            v = v + weight * penalty[i]
        logpi[i] = logpi[i] + (v if s else 0.0)
        col[i] = col[i] + (col_h[i] if s else 0.0)
        likely[i] = likely[i] and (ok[i] or not s)
        n_seen[i] += s


def add_camera_reference(seen, lv, penalty, weight, col_h, ok, logpi, likely, n_seen, col) -> None:
    """:func:`add_camera` as NumPy expressions (the tracker's former code), in place."""
    if len(penalty):
        lv = lv + weight * penalty
    logpi += np.where(seen, lv, 0.0)
    col += np.where(seen, col_h, 0.0)
    likely &= ok | ~seen
    n_seen += seen


def close_sums(n_seen: np.ndarray, xyz: np.ndarray, raster: WalkableRaster, logpi: np.ndarray, likely: np.ndarray,
               col: np.ndarray, blocks: np.ndarray | None = None) -> None:
    """The end of a likelihood summed over cameras, in place (:func:`close_sums_reference`): where no
    camera sees the particle (``n_seen`` 0) or it stands off the walkable ``raster`` (``xyz`` (N, ≥ 2);
    ``blocks`` as in :func:`raster_contains`), ``logpi`` is −inf and ``likely`` False; ``col`` is
    divided by ``max(n_seen, 1)``."""
    xyz = np.asarray(xyz, dtype=np.float64)
    _close_sums(n_seen, xyz, float(raster.origin[0]), float(raster.origin[1]), float(raster.resolution),
                np.ascontiguousarray(raster.inside, dtype=np.bool_), NO_BLOCKS if blocks is None else blocks,
                logpi, likely, col)


@njit(cache=True)
def _close_sums(n_seen, xyz, x0, y0, resolution, inside, blocks, logpi, likely, col):
    for k in range(n_seen.shape[0]):
        valid = n_seen[k] > 0 and in_raster(xyz[k, 0], xyz[k, 1], x0, y0, resolution, inside, blocks)
        if not valid:
            logpi[k] = -np.inf
            likely[k] = False
        col[k] = col[k] / max(n_seen[k], 1)


def close_sums_reference(n_seen, xyz, raster, logpi, likely, col) -> None:
    """:func:`close_sums` in NumPy (the tracker's former code), in place."""
    valid = (n_seen > 0) & raster.contains(np.asarray(xyz)[:, :2])
    logpi[:] = np.where(valid, logpi, -np.inf)
    likely &= valid
    col[:] = col / np.maximum(n_seen, 1)


__all__ = ["Sums", "add_camera", "add_camera_reference", "close_sums", "close_sums_reference"]
