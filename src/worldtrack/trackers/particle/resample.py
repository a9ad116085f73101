"""Weights and resampling (seed 004, eq. 8): ``g_i = π_i / Σ π``, then selection with replacement.

* :func:`particle_weights` — eq. 8 up to its sum, ``π^κ`` scaled by each row's largest;
* resamplers by name (:data:`RESAMPLERS`, the setting ``particle.weights.resampler``):
  :func:`systematic_resample` (the default: one uniform number places all N pointers, so each
  particle is copied ⌊N·g⌋ or ⌈N·g⌉ times) and :func:`stratified_resample` (one number per stratum);
  the paper's "selection with replacement in proportion to the weight" is multinomial;
* :func:`gather_particles`, :func:`take_rows` — the picked particles of F filters in one kernel.

Each kernel has a NumPy reference (``*_reference``) that the tests compare it with.

>>> idx = systematic_resample(np.array([0.0, 1.0, 3.0]), 4, np.random.default_rng(0))
>>> idx.tolist()
[1, 2, 2, 2]
"""

from __future__ import annotations

import math
from typing import Callable, NamedTuple, Protocol

import numpy as np
from numba import njit

from worldtrack.registry import Registry
from worldtrack.trackers.particle.cloud import PARTICLE_FIELDS, Cloud


class Resampler(Protocol):
    """Draws ``n`` indices per row of ``weights`` (M,) or (F, M) in proportion to the weights."""

    def __call__(self, weights: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray: ...


#: Resamplers by the name ``particle.weights.resampler`` gives.
RESAMPLERS: Registry[Resampler] = Registry("particle.weights.resampler")


class Particles(NamedTuple):
    """The per-particle arrays of F filters of M particles each, all indexed alike: ``xyz`` (F, M, 3)
    metres, ``v`` (F, M, 3) m/s, ``h`` (F, M) object heights (m), and this frame's observation
    ``logpi`` (F, M), ``likely`` (F, M) bool, ``col_h`` (F, M) metres."""

    xyz: np.ndarray
    v: np.ndarray
    h: np.ndarray
    logpi: np.ndarray
    likely: np.ndarray
    col_h: np.ndarray


@RESAMPLERS.register("systematic")
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
    r = rng.random((len(rows), 1))                              # one uniform number per row
    return _draw_rows(rows, r, n).reshape(np.shape(weights)[:-1] + (n,))


@RESAMPLERS.register("stratified")
def stratified_resample(weights: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    """As :func:`systematic_resample` with an independent uniform number in each stratum ``[j/n, (j+1)/n)``."""
    rows = _rows(weights)
    r = rng.random((len(rows), n))                              # one uniform number per stratum
    return _draw_rows(rows, r, n).reshape(np.shape(weights)[:-1] + (n,))


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


def gather_particles(idx: np.ndarray, parts: Particles, z: np.ndarray | None = None) -> Particles:
    """:func:`take_rows` of the six per-particle arrays of F filters in one kernel; with ``z`` (F, n)
    uniform draws, each picked particle's height is then ``z · col_h`` (the column likelihood's draw
    below the top its column sees)."""
    f, n = idx.shape
    out = Particles(np.empty((f, n, 3)), np.empty((f, n, 3)), np.empty((f, n)), np.empty((f, n)),
                    np.empty((f, n), dtype=np.bool_), np.empty((f, n)))
    _gather_particles(np.ascontiguousarray(idx, dtype=np.int64), parts, _NO_DRAWS if z is None else z, out)
    return out


_NO_DRAWS = np.zeros((0, 0))


@njit(cache=True)
def _gather_particles(idx, parts, z, out):
    xyz, v, h, logpi, likely, col_h = parts
    oxyz, ov, oh, ologpi, olikely, ocol_h = out
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


def resampler(name: str) -> Callable[[np.ndarray, int, np.random.Generator], np.ndarray]:
    """The resampling function by name (``"systematic"`` or ``"stratified"``); an unknown name is
    an :class:`~worldtrack.errors.InputError` naming the setting."""
    return RESAMPLERS[name]



class Resampling:
    """Eq. 8 and the selection with replacement, for the clouds of one tracker.

    Parameters
    ----------
    resample : Resampler — chosen by ``weights.resampler``
    power : float — weights ∝ π^power
    rng : numpy.random.Generator — the tracker's
    draw_z : bool — the column likelihoods: after resampling, each particle's z is drawn uniformly
        below the top its column sees (the column does not depend on z), so the particles fill the
        object's height
    """

    def __init__(self, resample: Resampler, power: float, rng: np.random.Generator, draw_z: bool):
        self.resample, self.power, self.rng, self.draw_z = resample, power, rng, draw_z

    def weights(self, logpi: np.ndarray) -> np.ndarray:
        """Eq. 8 up to its sum (the resampler normalises), along the last axis of ``logpi`` (one row
        per filter): ``g ∝ π^κ``; uniform in a row whose every π is 0."""
        return particle_weights(logpi, self.power)

    def parts(self, parts: dict[str, np.ndarray], weights: np.ndarray, n: int) -> dict[str, np.ndarray]:
        """The particles of F filters resampled to ``n`` each in proportion to ``weights`` (F, M):
        ``parts`` maps each per-particle field to its (F, M, ...) array; returns them (F, n, ...)."""
        idx = self.resample(weights, n, self.rng)
        if tuple(parts) == PARTICLE_FIELDS and parts["likely"].dtype == np.bool_:
            # All six fields (as tracking filters hold them): one kernel, heights drawn in it.
            arrays = gather_particles(idx, Particles(*parts.values()),
                                      z=self.rng.random(idx.shape) if self.draw_z else None)
            return dict(zip(PARTICLE_FIELDS, arrays))
        out = {name: take_rows(a, idx) for name, a in parts.items()}
        if self.draw_z:
            out["xyz"][..., 2] = self.rng.random(idx.shape) * out["col_h"]
        return out

    def cloud(self, c: Cloud, weights: np.ndarray, n: int) -> None:
        """:meth:`parts` of one cloud, in place."""
        parts = {name: getattr(c, name)[None] for name in PARTICLE_FIELDS if getattr(c, name) is not None}
        for name, a in self.parts(parts, weights[None], n).items():
            setattr(c, name, a[0])


__all__ = ["RESAMPLERS", "Particles", "Resampler", "Resampling", "gather_particles", "particle_weights", "resample_reference",
           "resampler", "stratified_resample", "systematic_resample", "take_rows", "weights_reference"]
