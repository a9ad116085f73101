"""Prediction (seed 004, eqs. 1–2 in real time): ``x_t = x_{t−1} + v·dt + w``, ``w ~ N(0, σ²·dt)``.

The velocity ``v`` is a component chosen by name (``particle.motion.model``, :data:`MOTIONS`):

* ``state`` (:class:`StateVelocity`, worldtrack's default) — each particle carries its own velocity, a
  constant-velocity model whose velocity walks by ``noise_v·√dt``: the particles that move like the
  object survive resampling, so evidence adds up along its path; the walk stops (the particles coast)
  while the filter's columns are mostly hidden;
* ``particle`` (:class:`ParticleVelocity`, the paper's eq. 2) — each particle's own last step
  ``(x_{t−1} − x_{t−2}) / dt``;
* ``object`` (:class:`ObjectVelocity`) — the object centre's, from its last two positions, smoothed;
* ``none`` (:class:`NoVelocity`).

:class:`HeightState` walks the particles' object heights. The compiled kernels and their NumPy
references:

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
from typing import TYPE_CHECKING, NamedTuple, Protocol, Sequence

import numpy as np
from numba import njit

from worldtrack.registry import Registry
from worldtrack.trackers.base import Person
from worldtrack.trackers.particle.cloud import Cloud, CloudStack
from worldtrack.trackers.particle.region import cloud_mean

if TYPE_CHECKING:
    from worldtrack.trackers.particle.config import ParticleConfig

#: No random draws (an empty array for a kernel's optional draws).
_NO_DRAWS = np.zeros(0)


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


def clip_speed(v: np.ndarray, max_speed: float) -> None:
    """Scale the velocities in ``v`` (..., ≥ 2) whose floor speed exceeds ``max_speed`` (in place)."""
    s = np.hypot(v[..., 0], v[..., 1])
    over = s > max_speed
    if over.any():
        v[over, :2] *= (max_speed / s[over])[:, None]


# ---------------------------------------------------------------------------- the models

class HeightState:
    """The particles' object heights (m): drawn about a person's height, walked by ``noise·√dt``,
    folded into [min_height, max_height]. ``walks``: the heights are a state of the likelihood
    (column-ratio with a height prior) and walk; otherwise they stay as drawn."""

    def __init__(self, cfg: "ParticleConfig", person_height: float, walks: bool, rng: np.random.Generator):
        self.spread, self.noise = cfg.height.spread_m, cfg.height.noise
        self.lo, self.hi = float(cfg.column.min_height_m), float(cfg.column.max_height_m)
        self.person_height = person_height
        self.walks = walks and self.noise > 0
        self.rng = rng

    def draw(self, n: int, centre: float | None = None) -> np.ndarray:
        """(n,) heights ~ N(centre, spread²) in [lo, hi] (default centre: the scene's person height)."""
        c = self.person_height if centre is None else centre
        return reflect_reference(c + self.spread * self.rng.standard_normal(n), self.lo, self.hi)

    def walk(self, h: np.ndarray, dt: float) -> np.ndarray:
        """``h`` (any shape) after the random walk (a new array; ``h`` itself when there is none)."""
        if self.walks and dt > 0 and h.size:
            out = np.empty(h.shape)
            jitter_reflect(np.ascontiguousarray(h, dtype=np.float64), self.rng.standard_normal(h.shape),
                           self.noise * math.sqrt(dt), self.lo, self.hi, out)
            return out
        return h


class MotionModel(Protocol):
    """The velocity of eqs. 1–2: draws a new filter's velocities, predicts filters, reports their
    floor velocity."""

    def velocities(self, n: int) -> np.ndarray:
        """(n, 3) m/s: a new tracking filter's particle velocities."""
        ...

    def predict(self, clouds: Sequence[Cloud], persons: Sequence[Person], dt: float) -> None:
        """Move the tracking filters ``clouds`` (of ``persons``) on by ``dt`` seconds, in place."""
        ...

    def velocity(self, clouds: Sequence[Cloud], persons: Sequence[Person], centres: np.ndarray,
                 t: float) -> np.ndarray:
        """(F, 2) m/s: each filter's floor velocity, its new resampled centre ``centres`` (F, ≥ 2) at ``t``."""
        ...


#: Motion models by the name ``particle.motion.model`` gives.
MOTIONS: Registry[type] = Registry("particle.motion.model")


class _Motion:
    """The prediction every model shares: Gaussian noise ``σ·√dt`` per axis (the step of
    :meth:`_step`), z folded into [0, max_height] for the point likelihood, the heights' walk."""

    def __init__(self, cfg: "ParticleConfig", rng: np.random.Generator, stack: CloudStack, heights: HeightState,
                 reflect_z: bool, column_samples: int):
        m = cfg.motion
        self.noise = np.array([m.noise_xy, m.noise_xy, m.noise_z])
        self.max_speed, self.max_height = float(m.max_speed_mps), float(cfg.column.max_height_m)
        self.cfg, self.rng, self.stack, self.heights = m, rng, stack, heights
        self.reflect_z, self.column_samples = reflect_z, column_samples

    def velocities(self, n: int) -> np.ndarray:
        return np.zeros((n, 3))

    def predict(self, clouds: Sequence[Cloud], persons: Sequence[Person], dt: float) -> None:
        if dt <= 0:
            return
        old = self.stack.stacked(clouds, "xyz")
        a = self.rng.standard_normal(old.shape)
        xyz, h = self._step(clouds, persons, old, a, dt)
        if self.reflect_z:
            xyz[..., 2] = reflect_reference(xyz[..., 2], 0.0, self.max_height)
        self.stack.set_rows(clouds, "h", self.heights.walk(self.stack.stacked(clouds, "h"), dt) if h is None else h)
        self.stack.set_rows(clouds, "xyz", xyz)
        self._after(clouds, xyz, old, dt)

    def _step(self, clouds, persons, old, a, dt) -> tuple[np.ndarray, np.ndarray | None]:
        """(new positions, new heights or None to walk them after) from the noise draws ``a``."""
        return old + a * (self.noise * math.sqrt(dt)), None

    def _after(self, clouds, xyz, old, dt) -> None:
        return None

    def velocity(self, clouds, persons, centres, t) -> np.ndarray:
        return np.zeros((len(clouds), 2))


@MOTIONS.register("none")
class NoVelocity(_Motion):
    """``x_t = x_{t−1} + w``: no velocity."""


@MOTIONS.register("particle")
class ParticleVelocity(_Motion):
    """Eq. 2: each particle's own velocity ``v_t = (x_t − x_{t−1}) / dt`` from its last step."""

    def _step(self, clouds, persons, old, a, dt):
        step = a * (self.noise * math.sqrt(dt))
        step += self.stack.stacked(clouds, "v") * dt
        return old + step, None

    def _after(self, clouds, xyz, old, dt) -> None:
        # v_t = (x_t − x_{t−1}) / dt, each particle's velocity for the next frame (eq. 2).
        v = (xyz - old) / dt
        clip_speed(v, self.max_speed)
        self.stack.set_rows(clouds, "v", v)

    def velocity(self, clouds, persons, centres, t) -> np.ndarray:
        return cloud_mean(self.stack.stacked(clouds, "v")[..., :2])


@MOTIONS.register("object")
class ObjectVelocity(_Motion):
    """The object centre's velocity, from its last two resampled centres, smoothed
    (``smoothing``: the newest measurement's weight); the person's ``vx, vy``."""

    def _step(self, clouds, persons, old, a, dt):
        step = a * (self.noise * math.sqrt(dt))
        step[..., :2] += np.array([[p.vx, p.vy] for p in persons])[:, None, :] * dt
        return old + step, None

    def velocity(self, clouds, persons, centres, t) -> np.ndarray:
        V = np.array([[p.vx, p.vy] for p in persons], dtype=float).reshape(-1, 2)
        prev = np.array([(np.nan, np.nan) if c.centre is None else c.centre for c in clouds], dtype=float)
        since = np.array([np.nan if c.t_update is None else t - c.t_update for c in clouds])
        moved = np.isfinite(prev[:, 0]) & (since > 0)
        if moved.any():
            w = self.cfg.smoothing
            V[moved] = (1 - w) * V[moved] + w * (centres[moved, :2] - prev[moved]) / since[moved, None]
            clip_speed(V, self.max_speed)
        return V


@MOTIONS.register("state")
class StateVelocity(_Motion):
    """Constant velocity: each particle's own velocity walks by ``noise_v·√dt`` (less while the filter's
    columns are hidden: it coasts), then moves it; the heights walk in the same compiled call."""

    def velocities(self, n: int) -> np.ndarray:
        v = np.zeros((n, 3))
        if self.cfg.velocity_spread_mps > 0:
            v[:, :2] = self.cfg.velocity_spread_mps * self.rng.standard_normal((n, 2))
            clip_speed(v, self.max_speed)
        return v

    def _step(self, clouds, persons, old, a, dt):
        # Constant velocity: each particle's own velocity walks by noise_v·√dt, then moves it; and
        # the heights' walk (HeightState.walk), all in one call with the draws in their order.
        v = self.stack.stacked(clouds, "v")                      # walked in place
        scale = self.cfg.noise_v * math.sqrt(dt) * self._coasting(clouds)
        xyz = np.empty_like(old)
        walk = self.rng.standard_normal(v.shape[:2] + (2,))
        hs = self.heights
        h = np.ascontiguousarray(self.stack.stacked(clouds, "h"), dtype=np.float64)
        walks = hs.walks and h.size
        h_out = np.empty(h.shape) if walks else h
        heights = HeightWalk(h, self.rng.standard_normal(h.shape) if walks else _NO_DRAWS, hs.noise * math.sqrt(dt),
                             hs.lo, hs.hi, h_out)
        predict_walk(old, a, self.noise * math.sqrt(dt), v, walk, scale, self.max_speed, float(dt), xyz, heights)
        self.stack.set_rows(clouds, "v", v)
        return xyz, h_out

    def _coasting(self, clouds: Sequence[Cloud]) -> np.ndarray:
        """(F,) factor of the velocity walk: ``1 − hidden / coast_hidden`` clipped to [0, 1], ``hidden``
        the share of column samples hidden (``k_lo``) in the camera that sees most of the object;
        1 with ``coast_hidden = 0``."""
        coast = self.cfg.coast_hidden
        if coast <= 0:
            return np.ones(len(clouds))
        n = self.column_samples
        return np.array([min(max(1.0 - (min(c.k_lo.values(), default=0) / n) / coast, 0.0), 1.0) for c in clouds])

    def velocity(self, clouds, persons, centres, t) -> np.ndarray:
        return cloud_mean(self.stack.stacked(clouds, "v")[..., :2])


__all__ = ["MOTIONS", "HeightState", "HeightWalk", "MotionModel", "NoVelocity", "ObjectVelocity", "ParticleVelocity",
           "StateVelocity", "clip_speed", "jitter_reflect", "predict_state", "predict_state_reference", "predict_walk",
           "reflect_reference", "velocity_walk_reference"]
