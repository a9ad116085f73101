"""Prediction (seed 004, eqs. 1–2 in real time): ``x_t = x_{t−1} + v·dt + w``, ``w ~ N(0, σ²·dt)``.

The compiled kernels of the prediction and their NumPy references:

* :func:`predict_state` — each particle's own velocity walks by ``noise_v·√dt`` (clipped to the
  largest speed), then moves it: the constant-velocity model (``particle.motion.model="state"``);
* :func:`jitter_reflect` — the random walk of the particles' object heights, folded into
  [min_height, max_height];
* :func:`predict_walk` — both in one call.

>>> reflect_reference(np.array([2.1, -0.2]), 0.0, 2.0).round(2).tolist()
[1.9, 0.2]
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit


class HeightWalk(NamedTuple):
    """The heights' random walk of :func:`predict_walk`: heights ``h`` (any shape, metres), standard
    normal ``draws`` of its shape (empty: no walk), ``scale`` (noise·√dt, metres), the limits ``lo``,
    ``hi`` (metres) and ``out`` (h's shape)."""

    h: np.ndarray
    draws: np.ndarray
    scale: float
    lo: float
    hi: float
    out: np.ndarray


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
def predict_walk(old, a, noise, v, walk, scale, max_speed, dt, out, heights):
    """:func:`predict_state` and, with ``heights.draws`` not empty, :func:`jitter_reflect` of the
    heights (:class:`HeightWalk`), in one call."""
    predict_state(old, a, noise, v, walk, scale, max_speed, dt, out)
    if heights.draws.size:
        jitter_reflect(heights.h, heights.draws, heights.scale, heights.lo, heights.hi, heights.out)


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


__all__ = ["HeightWalk", "jitter_reflect", "predict_state", "predict_state_reference", "predict_walk",
           "reflect_reference", "velocity_walk_reference"]
