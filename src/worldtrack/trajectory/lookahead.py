"""How far each state of a Levenberg–Marquardt step may go: a look-ahead along its move in the
distance field, instead of one length for the whole path.

With the barrier, a Gauss–Newton step cannot see an obstacle that its samples are not yet near (the
hinge's tail is flat there), so a long step can carry part of a path into a desk or through a
partition. The solver's older answer, a 0.25 m limit per state, shortens the steps state by state;
but states shortened on their own break the motion prior between neighbours (34i: on the speed walks
that step *raises* the model objective in every iteration of the first phase), so the solver falls
back to scaling the *whole* step until its largest move is 0.25 m. A path that must move metres in
one long gap then moves 5–10 % of its Gauss–Newton step everywhere, for ~10–20 iterations.

Here each state goes as far along its own Gauss–Newton move as the floor lets it. The move of every
barrier sample (the states and the points on the Hermite curves between them, where the hinge is
evaluated) is traced through the distance field: from a point at distance d it advances by
max(0.7·(d − floor), min(clearance, max(0.7·d, half a cell))) — every point within d − floor of it
keeps at least ``floor`` and every point within d is outside obstacles (the field is a distance,
~1-Lipschitz; bilinear slopes reach ~1.4, hence 0.7), so no partition is jumped — and stops at the
last point before the first one closer to an obstacle than floor = min(clearance, where the sample
starts). A move no longer than the first stride is whole without a lookup at its end (34j: most
moves, far from obstacles), and a trace starts from the distances the linearisation already has at
the samples. A state takes the least share α of the samples
on its two neighbouring curves. The shares are then made smooth in time, so that neighbouring
states move alike: the least α within ± ``window`` steps, averaged over the same window (neither
raises any state's α above its own look-ahead); the velocities get the derivative of α·δp (the step
stays a motion the prior can follow). Where the floor is clear, α = 1: the whole Gauss–Newton step.
A state never goes less far than the uniform scaling would take it.

The step is still judged by the solver's gain ratio ρ (actual against predicted decrease).
"""

from __future__ import annotations

import numpy as np
from numba import njit
from scipy.ndimage import minimum_filter1d, uniform_filter1d

from worldtrack.scene.floor import FloorGrid
from worldtrack.trajectory.environment import Barrier, hermite_weights, sample_field
from worldtrack.trajectory.kernels import field_value

_U, _UD, _V, _VD = 0, 1, 2, 3
#: A traced point advances by this share of its distance beyond the floor (bilinear: slopes up to ~1.4).
_STRIDE = 0.7


@njit(cache=True)
def _trace(values: np.ndarray, origin: np.ndarray, res: float, x: float, y: float, mx: float, my: float,
           clearance: float, d: float) -> float:  # pragma: no cover (compiled)
    """The share of the move (mx, my) from (x, y), where the field is d, that keeps min(clearance, d)
    (see the module notes)."""
    length = np.hypot(mx, my)
    floor = min(clearance, d)
    if length <= _STRIDE * (d - floor):      # the first stride covers the move: its end needs no lookup
        return 1.0
    done = 0.0
    while done < length:
        ahead = min(done + max(_STRIDE * (d - floor), min(clearance, max(_STRIDE * d, 0.5 * res))), length)
        d = field_value(values, origin, res, x + mx * ahead / length, y + my * ahead / length)
        if d < floor:
            return done / length
        done = ahead
    return 1.0


@njit(cache=True)
def _state_shares(X: np.ndarray, delta: np.ndarray, step: np.ndarray, H: np.ndarray, values: np.ndarray,
                  origin: np.ndarray, res: float, clearance: float,
                  start: np.ndarray) -> np.ndarray:  # pragma: no cover (compiled)
    """Every state's least share over the barrier samples (step t, Hermite weights H (M, 4)) it touches;
    ``start`` (M,): the field at the samples, or empty (then looked up)."""
    alpha = np.ones(X.shape[0])
    for m in range(step.shape[0]):
        t = step[m]
        h0, h1, h2, h3 = H[m, 0], H[m, 1], H[m, 2], H[m, 3]
        px = h0 * X[t, _U] + h1 * X[t, _UD] + h2 * X[t + 1, _U] + h3 * X[t + 1, _UD]
        py = h0 * X[t, _V] + h1 * X[t, _VD] + h2 * X[t + 1, _V] + h3 * X[t + 1, _VD]
        qx = h0 * delta[t, _U] + h1 * delta[t, _UD] + h2 * delta[t + 1, _U] + h3 * delta[t + 1, _UD]
        qy = h0 * delta[t, _V] + h1 * delta[t, _VD] + h2 * delta[t + 1, _V] + h3 * delta[t + 1, _VD]
        d = start[m] if start.shape[0] else field_value(values, origin, res, px, py)
        a = _trace(values, origin, res, px, py, qx, qy, clearance, d)
        alpha[t] = min(alpha[t], a)
        alpha[t + 1] = min(alpha[t + 1], a)
    return alpha


def state_shares(X: np.ndarray, delta: np.ndarray, barrier: Barrier, dt: float,
                 start: np.ndarray | None = None) -> np.ndarray:
    """(n,) each state's share α ∈ [0, 1] of the step δ (n, 6) from X (n, 6) before its samples come too
    close to an obstacle (the module notes), grid step ``dt`` (s). ``start``: the distance field at the
    barrier's samples (M,) in the order of :meth:`Barrier.samples`, if known (the linearisation at X has
    it: ``Linearisation.barrier_d``); else looked up.

    >>> from worldtrack.scene.floor import FloorGrid
    >>> x = np.arange(0.0, 5.01, 0.05); field = FloorGrid(np.zeros(2), 0.05, np.tile(3.0 - x, (len(x), 1)))
    >>> X = np.array([[1.0, 0, 1.0, 0, 1.7, 0], [1.5, 0, 1.0, 0, 1.7, 0]])      # 0.5 m apart, at rest
    >>> delta = np.array([[1.9, 0, 0, 0, 0, 0], [1.9, 0, 0, 0, 0, 0]])         # 1.9 m towards the wall at x = 3
    >>> state_shares(X, delta, Barrier(field, clearance=0.2), 0.5).round(3)    # 1.5 + 0.62·1.9 = 2.68 m: the
    array([0.623, 0.623])

    (the next traced point, 2.88 m, is within the clearance of the wall; both states move alike.)
    """
    step, frac = barrier.samples(len(X))
    f = barrier.field
    return _state_shares(np.ascontiguousarray(X, dtype=float), np.ascontiguousarray(delta, dtype=float), step,
                         hermite_weights(frac, dt), np.ascontiguousarray(f.values, dtype=float),
                         np.asarray(f.origin, dtype=float), float(f.resolution), float(barrier.clearance),
                         np.empty(0) if start is None else np.ascontiguousarray(start, dtype=float))


def trace_reference(field: FloorGrid, xy: np.ndarray, move: np.ndarray, clearance: float) -> np.ndarray:
    """NumPy reference of the compiled trace: the share (N,) of each move (N, 2) from xy (N, 2)."""
    out = np.ones(len(xy))
    for k, (p, m) in enumerate(zip(np.asarray(xy, float), np.asarray(move, float))):
        length = float(np.hypot(*m))
        d = float(sample_field(field, p[None])[0][0])
        floor, done = min(clearance, d), 0.0
        if length <= _STRIDE * (d - floor):
            continue                    # the first stride covers the move (out[k] stays 1)
        while done < length:
            ahead = min(done + max(_STRIDE * (d - floor), min(clearance, max(_STRIDE * d, 0.5 * field.resolution))),
                        length)
            d = float(sample_field(field, (p + m * ahead / length)[None])[0][0])
            if d < floor:
                out[k] = done / length
                break
            done = ahead
    return out


def shape_step(delta: np.ndarray, X: np.ndarray, barrier: Barrier, least: float, window: int,
               dt: float, start: np.ndarray | None = None) -> np.ndarray:
    """The step δ (n, 6) with each state's share α_t (:func:`state_shares`, ``start`` as there), at least
    ``least`` (the uniform scaling's fraction), smoothed over ± ``window`` steps; velocities corrected by
    α̇·δp (dt s)."""
    alpha = np.maximum(state_shares(X, delta, barrier, dt, start), least)
    if window > 0:
        alpha = uniform_filter1d(minimum_filter1d(alpha, 2 * window + 1, mode="nearest"), 2 * window + 1,
                                 mode="nearest")
    shaped = delta * alpha[:, None]
    rate = np.gradient(alpha, dt) if len(alpha) > 1 else np.zeros_like(alpha)
    shaped[:, _UD] += rate * delta[:, _U]
    shaped[:, _VD] += rate * delta[:, _V]
    return shaped
