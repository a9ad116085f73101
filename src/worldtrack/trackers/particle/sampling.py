"""Sampling pieces of the particle tracker: resampling, uniform floor regions and splitting a cloud in two.

* :func:`systematic_resample`, :func:`stratified_resample` — "selection with replacement with
  probability proportional to the weight" (seed 004 §2). Systematic is the default: see
  :class:`~worldtrack.trackers.particle.ParticleConfig`.
* :class:`FloorRegion` — a floor area rasterised once, for scattering detection particles uniformly
  over it (§3.2) and testing whether they are still inside.
* :func:`bimodal_split` — is a particle cloud two objects side by side? (the paper's open problem of
  objects that enter together and then part, §6.) :func:`splittable` — its cheap first test, for
  many clouds at once.
* :func:`polygon_distance` — how far floor points are from an entry region.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Callable

import numpy as np
from numba import njit
from numpy.typing import ArrayLike

from worldtrack.errors import InputError
from worldtrack.scene.floor import WalkableRaster, points_in_polygon

RESAMPLERS = ("systematic", "stratified")


# ---------------------------------------------------------------------------- resampling

def systematic_resample(weights: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    """Indices of ``n`` particles drawn in proportion to ``weights`` with one uniform number.

    The points ``(u + j) / n``, ``j = 0 … n−1``, ``u ~ U[0, 1)``, are looked up in the cumulative
    weights: a particle of normalised weight ``w`` is copied ``⌊n·w⌋`` or ``⌈n·w⌉`` times.

    Parameters
    ----------
    weights : (M,) or (F, M) float, ≥ 0, not all 0 in a row — one row per filter, each resampled
        on its own (with its own uniform number)
    n : int
    rng : numpy.random.Generator

    Returns
    -------
    (n,) or (F, n) int64, sorted — indices into each row
    """
    rows = _rows(weights)
    return _draw_rows(rows, resample_draws("systematic", len(rows), n, rng), n).reshape(np.shape(weights)[:-1] + (n,))


def stratified_resample(weights: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    """As :func:`systematic_resample` with an independent uniform number in each stratum ``[j/n, (j+1)/n)``."""
    rows = _rows(weights)
    return _draw_rows(rows, resample_draws("stratified", len(rows), n, rng), n).reshape(np.shape(weights)[:-1] + (n,))


def resample_draws(name: str, f: int, n: int, rng: np.random.Generator) -> np.ndarray:
    """The uniform numbers resampler ``name`` draws for F rows of ``n`` points: (F, 1) for
    ``systematic`` (one per row), (F, n) for ``stratified`` (one per stratum)."""
    return rng.random((f, 1) if name == "systematic" else (f, n))


def resample_reference(weights: np.ndarray, r: np.ndarray, n: int) -> np.ndarray:
    """(F, n) what :func:`systematic_resample` (``r`` (F, 1) its uniform numbers) or
    :func:`stratified_resample` (``r`` (F, n)) draw from ``weights`` (F, M), in NumPy: the points
    ``(r + j) / n`` looked up by :func:`_lookup`."""
    return _lookup(_rows(weights), (r + np.arange(n)) / n)


def _draw_rows(rows: np.ndarray, r: np.ndarray, n: int) -> np.ndarray:
    """:func:`resample_reference` in one kernel: the cumulative weights, their normalisation, the
    points and the merge, per row (tested equal)."""
    out = np.empty((len(rows), n), dtype=np.int64)
    _cumulative_lookup(np.ascontiguousarray(rows), np.ascontiguousarray(r), out)
    return out


@njit(cache=True)
def _cumulative_lookup(w, r, out):
    """Per row f: ``c = cumsum(w[f]) / sum``, then ``out[f, j]`` the number of ``c`` values ≤
    ``(r[f, 0 or j] + j) / n``, at most M − 1 — :func:`_lookup`'s arithmetic, in place."""
    m = w.shape[1]
    n = out.shape[1]
    c = np.empty(m)
    for f in range(w.shape[0]):
        if m == 0:
            out[f, :] = -1
            continue
        c[0] = w[f, 0]
        for j in range(1, m):
            c[j] = c[j - 1] + w[f, j]
        total = c[m - 1]
        for j in range(m):
            c[j] = c[j] / total
        j = 0
        for k in range(n):
            u = (r[f, 0 if r.shape[1] == 1 else k] + k) / n
            while j < m and c[j] <= u:
                j += 1
            out[f, k] = min(j, m - 1)


def _rows(weights: np.ndarray) -> np.ndarray:
    """``weights`` (M,) or (F, M) as (F, M) float."""
    w = np.asarray(weights, dtype=float)
    return w.reshape(-1, w.shape[-1])


def _lookup(weights: np.ndarray, u: np.ndarray) -> np.ndarray:
    """(F, n) the index in each row of ``weights`` (F, M) where its points ``u`` (F, n) in [0, 1)
    fall in the normalised cumulative weights: ``searchsorted(c, u, side="right")`` per row, capped
    at M − 1. Plain NumPy, one call per row: the reference that :func:`_cumulative_lookup`'s merge
    is tested against."""
    c = np.cumsum(weights, axis=1)
    c /= c[:, -1:]
    m = c.shape[1]
    return np.array([np.minimum(np.searchsorted(row, points, side="right"), m - 1) for row, points in zip(c, u)],
                    dtype=np.int64).reshape(u.shape)


def gather_particles(idx: np.ndarray, xyz: np.ndarray, v: np.ndarray, h: np.ndarray, logpi: np.ndarray,
                     likely: np.ndarray, col_h: np.ndarray, z: np.ndarray | None = None) -> tuple[np.ndarray, ...]:
    """:func:`take_rows` of the six per-particle arrays of F filters (``xyz, v`` (F, M, 3), the others
    (F, M)) in one kernel; with ``z`` (F, n) uniform draws, each picked particle's height is then
    ``z · col_h`` (the column likelihood's draw below the top its column sees)."""
    f, n = idx.shape
    out = (np.empty((f, n, 3)), np.empty((f, n, 3)), np.empty((f, n)), np.empty((f, n)),
           np.empty((f, n), dtype=np.bool_), np.empty((f, n)))
    _gather_particles(np.ascontiguousarray(idx, dtype=np.int64), xyz, v, h, logpi, likely, col_h,
                      _NO_DRAWS if z is None else z, *out)
    return out


_NO_DRAWS = np.zeros((0, 0))


@njit(cache=True)
def _gather_particles(idx, xyz, v, h, logpi, likely, col_h, z, oxyz, ov, oh, ologpi, olikely, ocol_h):
    draw = z.shape[0] > 0
    for f in range(idx.shape[0]):
        for j in range(idx.shape[1]):
            k = idx[f, j]
            for c in range(3):
                oxyz[f, j, c] = xyz[f, k, c]
                ov[f, j, c] = v[f, k, c]
            oh[f, j] = h[f, k]
            ologpi[f, j] = logpi[f, k]
            olikely[f, j] = likely[f, k]
            ocol_h[f, j] = col_h[f, k]
            if draw:
                oxyz[f, j, 2] = z[f, j] * ocol_h[f, j]


def particle_weights(logpi: np.ndarray, power: float) -> np.ndarray:
    """Eq. 8 up to its sum, along the last axis of ``logpi`` (M,) or (F, M): ``π^κ`` scaled by the
    row's largest, 1 throughout a row whose every π is 0 — :func:`weights_reference` with its max and
    exponent taken in one kernel pass (the ``np.exp`` stays NumPy's, so the weights are equal bit
    for bit; tested)."""
    shape = np.shape(logpi)
    rows = np.ascontiguousarray(logpi, dtype=np.float64).reshape(math.prod(shape[:-1]), shape[-1])
    arg = np.empty(rows.shape)
    finite = np.empty(len(rows), dtype=np.bool_)
    if rows.shape[1]:
        _weight_exponents(rows, float(power), arg, finite)
    else:
        finite[:] = False
    return np.where(finite[:, None], np.exp(arg), 1.0).reshape(shape)


@njit(cache=True)
def _weight_exponents(logpi, power, arg, finite):
    """Per row: ``arg = power·(logpi − max)`` and whether the max is finite (where it is not, the
    exponents are taken about 0 and then unused) — :func:`weights_reference` before its ``np.exp``."""
    for f in range(logpi.shape[0]):
        m = logpi[f, 0]
        for x in logpi[f]:
            if x != x:                          # NaN: np.max's result
                m = x
                break
            if x > m:
                m = x
        fin = math.isfinite(m)
        finite[f] = fin
        mm = m if fin else 0.0
        for j in range(logpi.shape[1]):
            arg[f, j] = power * (logpi[f, j] - mm)


def weights_reference(logpi: np.ndarray, power: float) -> np.ndarray:
    """:func:`particle_weights` in NumPy."""
    m = logpi.max(axis=-1, keepdims=True)
    finite = np.isfinite(m)
    return np.where(finite, np.exp(power * (logpi - np.where(finite, m, 0.0))), 1.0)


def take_rows(a: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """(F, n, ...) ``a[f, idx[f, j]]``: each of F filters' particles ``a`` (F, M, ...) picked by its own
    indices ``idx`` (F, n) — ``np.take_along_axis`` in one kernel (tested equal)."""
    f, m = a.shape[:2]
    c = math.prod(a.shape[2:])
    out = np.empty((f, idx.shape[1], c), dtype=a.dtype)
    _take_rows(np.ascontiguousarray(a).reshape(f, m, c), np.ascontiguousarray(idx, dtype=np.int64), out)
    return out.reshape(idx.shape + a.shape[2:])


@njit(cache=True)
def _take_rows(a, idx, out):
    for f in range(idx.shape[0]):
        for j in range(idx.shape[1]):
            k = idx[f, j]
            for c in range(a.shape[2]):
                out[f, j, c] = a[f, k, c]


def order_statistic(x: np.ndarray, rank: int) -> np.ndarray:
    """(F,) the value of rank ``rank`` (0-based, ascending) in each row of ``x`` (F, N) of small
    non-negative integers: ``np.partition(x, rank, axis=1)[:, rank]`` by counting (tested equal)."""
    x = np.ascontiguousarray(x)
    out = np.empty(len(x), dtype=x.dtype)
    if not 0 <= rank < x.shape[1] or not _order_statistic(x, int(rank), out):
        return np.partition(x, rank, axis=1)[:, rank]         # (other values, or rank out of range: its error)
    return out


@njit(cache=True)
def _order_statistic(x, rank, out):
    """False (``out`` not filled) if some value is negative or above 4096."""
    for f in range(x.shape[0]):
        top = 0
        for v in x[f]:
            if v < 0 or v > 4096:
                return False
            top = max(top, v)
        counts = np.zeros(top + 1, dtype=np.int64)
        for v in x[f]:
            counts[v] += 1
        seen = 0
        for v in range(top + 1):
            seen += counts[v]
            if seen > rank:
                out[f] = v
                break
    return True


def resampler(name: str) -> Callable[[np.ndarray, int, np.random.Generator], np.ndarray]:
    """The resampling function by name (``"systematic"`` or ``"stratified"``)."""
    if name == "systematic":
        return systematic_resample
    if name == "stratified":
        return stratified_resample
    raise InputError(f"resampling: expected one of {', '.join(RESAMPLERS)}, got {name!r}")


# ---------------------------------------------------------------------------- floor regions

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
                     np.ascontiguousarray(raster.inside, dtype=np.bool_), _NO_BLOCKS if blocks is None else blocks,
                     out)
    return out


#: Cells per side of a :func:`raster_blocks` block (a power of two).
RASTER_BLOCK = 32
_NO_BLOCKS = np.zeros((0, 0), dtype=np.bool_)


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
def _in_raster(x, y, x0, y0, resolution, inside, blocks):
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
        out[k] = _in_raster(xy[k, 0], xy[k, 1], x0, y0, resolution, inside, blocks)


def close_sums(n_seen: np.ndarray, xyz: np.ndarray, raster: WalkableRaster, logpi: np.ndarray, likely: np.ndarray,
               col: np.ndarray, blocks: np.ndarray | None = None) -> None:
    """The end of a likelihood summed over cameras, in place (:func:`close_sums_reference`): where no
    camera sees the particle (``n_seen`` 0) or it stands off the walkable ``raster`` (``xyz`` (N, ≥ 2);
    ``blocks`` as in :func:`raster_contains`), ``logpi`` is −inf and ``likely`` False; ``col`` is
    divided by ``max(n_seen, 1)``."""
    xyz = np.asarray(xyz, dtype=np.float64)
    _close_sums(n_seen, xyz, float(raster.origin[0]), float(raster.origin[1]), float(raster.resolution),
                np.ascontiguousarray(raster.inside, dtype=np.bool_), _NO_BLOCKS if blocks is None else blocks,
                logpi, likely, col)


@njit(cache=True)
def _close_sums(n_seen, xyz, x0, y0, resolution, inside, blocks, logpi, likely, col):
    for k in range(n_seen.shape[0]):
        valid = n_seen[k] > 0 and _in_raster(xyz[k, 0], xyz[k, 1], x0, y0, resolution, inside, blocks)
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


# ---------------------------------------------------------------------------- splitting a cloud

def bimodal_split(xy: np.ndarray, min_separation: float, max_dip: float, min_mass: float,
                  bin_m: float = 0.04, smooth_m: float = 0.05,
                  principal: tuple | None = None) -> np.ndarray | None:
    """Split a floor cloud of particles into two objects side by side, if it is two.

    The cloud is projected on its principal axis; the projection's histogram (``bin_m`` bins,
    Gaussian smoothing ``smooth_m``) must have two peaks at least ``min_separation`` apart whose
    valley is at most ``max_dip`` times the lower peak, and each side of the valley must hold at
    least ``min_mass`` of the particles.

    Parameters
    ----------
    xy : (N, 2) float, metres — equally weighted particles
    min_separation : float, metres
    max_dip : float in (0, 1)
    min_mass : float in (0, 0.5)
    principal : tuple, optional — this cloud's row of :func:`splittable`'s ``principal`` (the
        centred cloud and its covariance, computed for many clouds at once), not to compute it again

    Returns
    -------
    (N,) bool or None
        Which side of the valley each particle is on; ``None`` for a single object.
    """
    xy = np.asarray(xy, dtype=float)
    if len(xy) < 8:
        return None
    if principal is None:
        c, (sxx, syy, sxy, lam) = _principal(xy[None])
        principal = c[0], float(sxx[0]), float(syy[0]), float(sxy[0]), float(lam[0])
    c, sxx, syy, sxy, lam = principal
    # _wide_enough of one float: the same IEEE operations (max keeps NaN and −0.0 as np.maximum does).
    if not math.sqrt(max(lam, 0.0)) >= min_separation * math.sqrt(min_mass * (1 - min_mass)):
        return None
    # The principal axis: the eigenvector of the covariance's largest eigenvalue.
    axis = np.array([sxy, lam - sxx]) if abs(sxy) > 1e-15 else (np.array([1.0, 0.0]) if sxx >= syy
                                                                   else np.array([0.0, 1.0]))
    axis /= np.linalg.norm(axis)
    s = c @ axis
    side = np.empty(len(s), dtype=np.bool_)
    return side if _sides(s, s.min(), bin_m, smooth_m, min_separation, max_dip, min_mass, side) else None


@njit(cache=True)
def _sides(s, lo, bin_m, smooth_m, min_separation, max_dip, min_mass, side):
    """The end of :func:`bimodal_split` in one call: ``side = s > lo + (valley + 0.5)·bin_m`` (in
    place) and True if :func:`_valley` finds a valley and each side holds at least ``min_mass`` of the
    particles (``side.mean()``, as a count over N)."""
    valley = _valley(s, lo, bin_m, smooth_m, min_separation, max_dip)
    if valley < 0:
        return False
    cut = lo + (valley + 0.5) * bin_m
    n = 0
    for i in range(s.shape[0]):
        side[i] = s[i] > cut
        n += side[i]
    m = n / s.shape[0]
    return not min(m, 1 - m) < min_mass


@njit(cache=True)
def _valley(s: np.ndarray, lo: float, bin_m: float, smooth_m: float, min_separation: float,
            max_dip: float) -> int:
    """The valley bin between the two peaks of the smoothed histogram of ``s`` (N,) metres, from
    ``lo`` in ``bin_m`` bins; −1 if there are no two peaks ``min_separation`` apart with a valley at
    most ``max_dip`` times the lower. The compiled kernel of :func:`bimodal_split` (the NumPy calls
    on these ~20-bin arrays cost more than the work); :func:`_valley_reference` is the same in NumPy."""
    nb = int(math.ceil((s.max() - lo) / bin_m)) + 1
    h = np.zeros(nb)
    for v in s:
        h[min(int((v - lo) / bin_m), nb - 1)] += 1.0
    r = max(1, int(math.ceil(3 * smooth_m / bin_m)))
    kernel = np.empty(2 * r + 1)
    for k in range(2 * r + 1):
        kernel[k] = math.exp(-0.5 * (((k - r) * bin_m) / smooth_m) ** 2)
    hs = np.zeros(nb)
    for i in range(nb):                      # np.convolve(np.pad(h, r), kernel, "valid")
        acc = 0.0
        for k in range(2 * r + 1):
            j = i + r - k
            if 0 <= j < nb:
                acc += h[j] * kernel[k]
        hs[i] = acc
    peaks = np.empty(nb, np.int64)
    n_peaks, p1 = 0, -1
    for i in range(nb):
        left = hs[i - 1] if i > 0 else -1.0
        right = hs[i + 1] if i < nb - 1 else -1.0
        if hs[i] >= left and hs[i] > right and hs[i] > 0:
            peaks[n_peaks] = i
            n_peaks += 1
            if p1 < 0 or hs[i] > hs[p1]:
                p1 = i
    if n_peaks < 2:
        return -1
    p2 = -1
    for i in peaks[:n_peaks]:
        if abs(i - p1) * bin_m >= min_separation and (p2 < 0 or hs[i] > hs[p2]):
            p2 = i
    if p2 < 0:
        return -1
    a, b = min(p1, p2), max(p1, p2)
    valley = a
    for i in range(a, b + 1):
        if hs[i] < hs[valley]:
            valley = i
    if hs[valley] > max_dip * min(hs[p1], hs[p2]):
        return -1
    return valley


def _valley_reference(s: np.ndarray, lo: float, bin_m: float, smooth_m: float, min_separation: float,
                      max_dip: float) -> int:
    """:func:`_valley` in NumPy."""
    nb = int(np.ceil((s.max() - lo) / bin_m)) + 1
    h = np.bincount(np.minimum(((s - lo) / bin_m).astype(np.int64), nb - 1), minlength=nb).astype(float)
    r = max(1, int(np.ceil(3 * smooth_m / bin_m)))
    kx = np.arange(-r, r + 1) * bin_m
    kernel = np.exp(-0.5 * (kx / smooth_m) ** 2)
    hs = np.convolve(np.pad(h, r), kernel, mode="valid")
    left = np.concatenate([[-1.0], hs[:-1]])
    right = np.concatenate([hs[1:], [-1.0]])
    peaks = np.flatnonzero((hs >= left) & (hs > right) & (hs > 0))
    if len(peaks) < 2:
        return -1
    p1 = peaks[np.argmax(hs[peaks])]
    far = peaks[np.abs(peaks - p1) * bin_m >= min_separation]
    if len(far) == 0:
        return -1
    p2 = far[np.argmax(hs[far])]
    a, b = min(p1, p2), max(p1, p2)
    valley = a + int(np.argmin(hs[a:b + 1]))
    if hs[valley] > max_dip * min(hs[p1], hs[p2]):
        return -1
    return valley


def _sides_reference(s: np.ndarray, lo: float, bin_m: float, smooth_m: float, min_separation: float,
                     max_dip: float, min_mass: float) -> np.ndarray | None:
    """:func:`_sides` in NumPy (:func:`bimodal_split`'s former end): the sides, or None."""
    valley = _valley_reference(s, lo, bin_m, smooth_m, min_separation, max_dip)
    if valley < 0:
        return None
    side = s > lo + (valley + 0.5) * bin_m
    m = side.mean()
    if min(m, 1 - m) < min_mass:
        return None
    return side


def splittable(xy: np.ndarray, min_separation: float, min_mass: float, principal: bool = False):
    """Which of F clouds :func:`bimodal_split` could split at all: the cheap test it starts with
    (at least 8 particles, wide enough along the principal axis), for many clouds at once.

    Parameters
    ----------
    xy : (F, N, 2) float, metres
    min_separation, min_mass : as in :func:`bimodal_split`
    principal : bool — also return each cloud's centred particles and covariance, for
        :func:`bimodal_split` (the same values as it computes for one cloud: the matrix products
        run per cloud)

    Returns
    -------
    wide : (F,) bool — False: :func:`bimodal_split` returns None for that cloud
    principal : list of F tuples, with ``principal`` — each cloud's ``principal`` argument of
        :func:`bimodal_split` (None for clouds of fewer than 8 particles)
    """
    xy = np.asarray(xy, dtype=float)
    if xy.shape[1] < 8:
        wide, rows = np.zeros(len(xy), dtype=bool), [None] * len(xy)
    else:
        c = xy - cloud_mean(xy)[:, None, :]
        out = np.empty((4, len(xy)))
        wide = np.empty(len(xy), dtype=np.bool_)
        _covariance_axes(c.transpose(0, 2, 1) @ c, xy.shape[1], out, float(min_separation), float(min_mass), wide)
        rows = list(zip(c, *out.tolist())) if principal else None
    return (wide, rows) if principal else wide


# ---------------------------------------------------------------------------- motion

@njit(cache=True)
def predict_state(old: np.ndarray, a: np.ndarray, noise: np.ndarray, v: np.ndarray, walk: np.ndarray,
                  scale: np.ndarray, max_speed: float, dt: float, out: np.ndarray) -> None:
    """``velocity="state"``'s prediction of F filters in one pass (:func:`predict_state_reference`):
    ``out = old + a·noise + v·dt`` (``out`` (F, N, 3), metres) with each particle's velocity ``v``
    (F, N, 3), m/s, first walked in place as :func:`velocity_walk_reference` walks it (``walk`` (F, N, 2)
    standard normal draws, ``scale`` (F,) m/s); ``a`` (F, N, 3) standard normal draws, ``noise``
    (3,) metres (σ·√dt per axis)."""
    n0, n1, n2 = noise[0], noise[1], noise[2]
    # Below 0.99·max_speed by the squares (rounding errors ~1e-16) the speed is below max_speed:
    # the exact hypot, which decides, is needed only above that.
    slow = (0.99 * max_speed) ** 2 if max_speed > 0.0 else -1.0
    for f in range(v.shape[0]):
        sc = scale[f]
        for i in range(v.shape[1]):
            v0 = v[f, i, 0] + walk[f, i, 0] * sc
            v1 = v[f, i, 1] + walk[f, i, 1] * sc
            if not v0 * v0 + v1 * v1 < slow:
                s = math.hypot(v0, v1)
                if s > max_speed:
                    r = max_speed / s
                    v0 *= r
                    v1 *= r
            v[f, i, 0] = v0
            v[f, i, 1] = v1
            v[f, i, 2] = 0.0
            out[f, i, 0] = old[f, i, 0] + (a[f, i, 0] * n0 + v0 * dt)
            out[f, i, 1] = old[f, i, 1] + (a[f, i, 1] * n1 + v1 * dt)
            out[f, i, 2] = old[f, i, 2] + a[f, i, 2] * n2


def predict_state_reference(old: np.ndarray, a: np.ndarray, noise: np.ndarray, v: np.ndarray, walk: np.ndarray,
                            scale: np.ndarray, max_speed: float, dt: float, out: np.ndarray) -> None:
    """:func:`predict_state` as the tracker's former NumPy steps."""
    step = a * noise
    velocity_walk_reference(v, walk, scale, max_speed, dt, step)
    out[...] = old + step


@njit(cache=True, inline="always")
def _mod(x, y):
    """``x mod y`` with the sign of ``y``, as NumPy's ``np.mod`` (and Python's ``%``) computes it."""
    m = np.fmod(x, y)
    if m != 0.0:
        if (y < 0.0) != (m < 0.0):
            m += y
    else:
        m = math.copysign(0.0, y)
    return m


@njit(cache=True)
def jitter_reflect(h: np.ndarray, a: np.ndarray, scale: float, lo: float, hi: float, out: np.ndarray) -> None:
    """``out = reflect(h + a·scale)`` into [lo, hi] by reflection at the ends, elementwise (any
    shape, C order): the random walk of the particles' heights in one pass (tested equal to
    :func:`reflect_reference` of the NumPy sum)."""
    span = hi - lo
    hf, af, of = h.reshape(h.size), a.reshape(a.size), out.reshape(out.size)     # views of C-contiguous arrays
    for k in range(hf.shape[0]):
        r = _mod(hf[k] + af[k] * scale - lo, 2 * span)
        of[k] = lo + (2 * span - r if r > span else r)


@njit(cache=True)
def predict_walk(old: np.ndarray, a: np.ndarray, noise: np.ndarray, v: np.ndarray, walk: np.ndarray,
                 scale: np.ndarray, max_speed: float, dt: float, out: np.ndarray, h: np.ndarray, ha: np.ndarray,
                 h_scale: float, lo: float, hi: float, h_out: np.ndarray) -> None:
    """:func:`predict_state` and, with ``ha`` not empty, :func:`jitter_reflect` of the heights ``h``
    into ``h_out``, in one call."""
    predict_state(old, a, noise, v, walk, scale, max_speed, dt, out)
    if ha.size:
        jitter_reflect(h, ha, h_scale, lo, hi, h_out)


def reflect_reference(z: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Fold values into [lo, hi] by reflection at the ends (NumPy)."""
    span = hi - lo
    r = np.mod(z - lo, 2 * span)
    return lo + np.where(r > span, 2 * span - r, r)


def velocity_walk_reference(v: np.ndarray, a: np.ndarray, scale: np.ndarray, max_speed: float, dt: float,
                            step: np.ndarray) -> None:
    """The walk of each particle's velocity (``velocity="state"``), in place: ``v + a·scale`` on the
    floor axes (``a`` (F, N, 2) standard normal draws, ``scale`` (F,) m/s), 0 vertically, floor
    speeds above ``max_speed`` scaled down to it; ``step += v·dt`` with the new ``v``. NumPy, the
    reference of :func:`predict_state`."""
    v[..., :2] += a * np.asarray(scale)[:, None, None]
    v[..., 2] = 0.0
    s = np.hypot(v[..., 0], v[..., 1])
    over = s > max_speed
    if over.any():
        v[over, :2] *= (max_speed / s[over])[:, None]
    step += v * dt


def cloud_mean(x: np.ndarray) -> np.ndarray:
    """Mean over the particles of each cloud, ``x`` (F, N, C) → (F, C), as a matrix product
    (NumPy's reduction over the middle axis of an (F, N, 3) array is many times slower)."""
    return _mean_weights(x.shape[1]) @ x


@functools.lru_cache(maxsize=8)
def _mean_weights(n: int) -> np.ndarray:
    """(n,) all ``1/n``, read-only: :func:`cloud_mean`'s weights, made once per particle count."""
    w = np.full(n, 1.0 / n)
    w.setflags(write=False)
    return w


def _principal(xy: np.ndarray) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """The clouds ``xy`` (F, N, 2) centred, and per cloud the covariance ``sxx, syy, sxy`` and its
    largest eigenvalue (the variance along the principal axis), each (F,), m²."""
    c = xy - cloud_mean(xy)[:, None, :]
    out = np.empty((4, len(xy)))
    _covariance_axes(c.transpose(0, 2, 1) @ c, xy.shape[1], out, 0.0, 0.0, np.empty(0, dtype=np.bool_))
    return c, (out[0], out[1], out[2], out[3])


@njit(cache=True)
def _covariance_axes(products, n, out, min_separation, min_mass, wide):
    """``out`` (4, F), in place: ``sxx, syy, sxy`` of the (F, 2, 2) sums of products over ``n`` and the
    largest eigenvalue ``(sxx + syy)/2 + hypot((sxx − syy)/2, sxy)`` — :func:`_principal_reference`'s
    arithmetic; and, if ``wide`` is not empty, :func:`_wide_enough` of the eigenvalues into it."""
    limit = min_separation * math.sqrt(min_mass * (1 - min_mass))
    for f in range(products.shape[0]):
        sxx = products[f, 0, 0] / n
        syy = products[f, 1, 1] / n
        sxy = products[f, 0, 1] / n
        out[0, f], out[1, f], out[2, f] = sxx, syy, sxy
        lam = 0.5 * (sxx + syy) + math.hypot(0.5 * (sxx - syy), sxy)
        out[3, f] = lam
        if wide.shape[0]:
            wide[f] = math.sqrt(lam if not lam < 0.0 else 0.0) >= limit


def _principal_reference(xy: np.ndarray) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """:func:`_principal` in NumPy (its former code)."""
    c = xy - cloud_mean(xy)[:, None, :]
    cov = c.transpose(0, 2, 1) @ c / xy.shape[1]
    sxx, syy, sxy = cov[:, 0, 0], cov[:, 1, 1], cov[:, 0, 1]
    return c, (sxx, syy, sxy, 0.5 * (sxx + syy) + np.hypot(0.5 * (sxx - syy), sxy))


def _wide_enough(lam, min_separation: float, min_mass: float):
    """Two lumps d apart holding m and 1 − m of the particles have a std of at least d·sqrt(m(1 − m))
    along the axis joining them: a cloud of principal variance ``lam`` narrower than that cannot be
    split."""
    return np.sqrt(np.maximum(lam, 0.0)) >= min_separation * np.sqrt(min_mass * (1 - min_mass))


@njit(cache=True)
def inverse_lengths(uv: np.ndarray, steps: int, out: np.ndarray) -> None:
    """``out`` (F,), in place: 1 / (the image length from ``uv[0, f]`` to ``uv[1, f]`` (pixels) over
    ``steps``), 0 where that is not finite and positive — :func:`inverse_lengths_reference`'s
    arithmetic (the pixel scale of ``pixel_weights="filter"``)."""
    for f in range(uv.shape[1]):
        length = math.hypot(uv[1, f, 0] - uv[0, f, 0], uv[1, f, 1] - uv[0, f, 1]) / steps
        out[f] = 1.0 / length if math.isfinite(length) and length > 0 else 0.0


def inverse_lengths_reference(uv: np.ndarray, steps: int) -> np.ndarray:
    """:func:`inverse_lengths` in NumPy (the tracker's former code)."""
    length = np.hypot(*(uv[1] - uv[0]).T) / steps
    ok = np.isfinite(length) & (length > 0)
    return np.where(ok, 1.0 / np.where(ok, length, 1.0), 0.0)


@njit(cache=True)
def region_sizes(sd: np.ndarray, widths: np.ndarray, sigma: np.ndarray) -> None:
    """The object regions' sizes from the particles' standard deviations ``sd`` (F, 3), metres, in
    place: ``sigma`` (F,) ``= sqrt((sx² + sy²) / 2)``, then, with ``widths`` (F,) (not empty),
    ``sx, sy = hypot(sx, width/4), hypot(sy, width/4)`` — :func:`region_sizes_reference`'s arithmetic."""
    for f in range(sd.shape[0]):
        sigma[f] = math.sqrt(0.5 * (sd[f, 0] * sd[f, 0] + sd[f, 1] * sd[f, 1]))
        if widths.shape[0]:
            q = 0.25 * widths[f]
            sd[f, 0] = math.hypot(sd[f, 0], q)
            sd[f, 1] = math.hypot(sd[f, 1], q)


def region_sizes_reference(sd: np.ndarray, widths: np.ndarray, sigma: np.ndarray) -> None:
    """:func:`region_sizes` in NumPy (the tracker's former code), in place."""
    sigma[:] = np.sqrt(0.5 * (sd[:, 0] ** 2 + sd[:, 1] ** 2))
    if len(widths):
        sd[:, :2] = np.hypot(sd[:, :2], 0.25 * np.asarray(widths)[:, None])


def polygon_distance(xy: ArrayLike, ring: ArrayLike) -> np.ndarray:
    """(N,) distance (m) from floor points to a polygon: 0 inside, else to the nearest edge."""
    p = np.asarray(xy, dtype=float).reshape(-1, 2)
    a = np.asarray(ring, dtype=float)
    ab = np.roll(a, -1, axis=0) - a
    ap = p[:, None, :] - a[None, :, :]
    s = np.clip((ap * ab).sum(axis=2) / np.maximum((ab * ab).sum(axis=1), 1e-12), 0.0, 1.0)
    d = np.sqrt(((ap - s[:, :, None] * ab) ** 2).sum(axis=2)).min(axis=1)
    return np.where(points_in_polygon(p, a), 0.0, d)
