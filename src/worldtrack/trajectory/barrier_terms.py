"""The barrier's samples added into the normal equations in one compiled pass.

:func:`~worldtrack.trajectory.kernels.barrier_samples` returns every sample's residual and its Jacobian
row (M, 12), which :func:`~worldtrack.trajectory.kernels.add_pair_terms` then adds into the blocks. At
T = 10 000 that is ~20 000 samples and a 1.9 MB Jacobian written and read back once per linearisation
(34j profile: the two passes 1.7 ms of a 4.1 ms linearisation). Here each sample's row lives in a
12-entry buffer and goes into the blocks at once: the same arithmetic in the same order (the sample
by :func:`~worldtrack.trajectory.kernels.barrier_point`, the blocks by ``add_pair_row``, as ``add_pair_terms``), so the
same numbers bit for bit; the two passes stay as its reference, and the test compares them. The blocks take
only the row's 8 floor entries (:func:`add_floor_row`): the other 4 are always 0, and adding their 0.0 products
changed nothing but cost 1/3 of the scatter (34n: the kernel 1.36 → 1.11 ms at T = 10 000, ~20 000 samples).

The residuals r (M,) and distances d (M,) are still returned: the cost is ``r @ r`` as before, and d
at the samples is what the look-ahead starts its traces from (:mod:`.lookahead`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from worldtrack.trajectory.kernels import STATE, barrier_point


class Hinge(NamedTuple):
    """The hinge's constants: clearance c (m), softness w (m) and gain √(λ/m)/s_h (1/m); ``outward``: the
    curvature factor of a sample that moved away from the obstacles since ``d_before`` (0: off, see
    :func:`add_barrier_terms`)."""

    clearance: float
    softness: float
    gain: float
    outward: float = 0.0


#: A sample "moved away" when its distance grew by more than this (m) since the last linearisation.
OUTWARD_MOVE = 1e-4


class Normal(NamedTuple):
    """The Gauss–Newton system written in place: blocks D (n, 6, 6), B (n − 1, 6, 6), half-gradient g (n, 6)."""

    D: np.ndarray
    B: np.ndarray
    g: np.ndarray


@njit(cache=True)
def add_barrier_terms(X: np.ndarray, step: np.ndarray, alpha: np.ndarray, dt: float, values: np.ndarray,
                      origin: np.ndarray, res: float, hinge: Hinge, normal: Normal, r: np.ndarray, d: np.ndarray,
                      inside_steps: np.ndarray, d_before: np.ndarray) -> None:  # pragma: no cover (compiled)
    """In place: every sample (step t, fraction α) of the barrier added into ``normal`` as curvature·JᵀJ
    and Jᵀr; its residual into r (M,), its distance into d (M,); ``inside_steps[t]`` set where a sample
    is within the clearance. The same numbers as ``barrier_samples`` followed by ``add_pair_terms``.

    With ``hinge.outward`` > 0 and ``d_before`` (M,) the samples' distances at the last linearisation (else
    ``d_before`` may be empty), a sample whose distance grew by more than ``OUTWARD_MOVE`` takes the curvature
    factor ``hinge.outward`` instead of 1 + r·r″/r′² (≈ 2 in the hinge's exponential tail): Newton's curvature
    of e^(−2d/w) at the start of a move away from an obstacle is the largest along it, so Newton moves such a
    sample ~w/2 per iteration (34l), Gauss–Newton (1) ~w."""
    D, B, g = normal
    row = np.empty(2 * STATE)
    for m in range(step.shape[0]):
        t = step[m]
        rm, dm, w = barrier_point(X, t, alpha[m], dt, values, origin, res, hinge.clearance, hinge.softness,
                                  hinge.gain, row)
        r[m], d[m] = rm, dm
        if dm < hinge.clearance:
            inside_steps[t] = True
        if rm != 0.0:                  # r = 0: beyond the barrier's reach, nothing to add
            if hinge.outward > 0.0 and dm > d_before[m] + OUTWARD_MOVE:
                w = hinge.outward
            add_floor_row(D, B, g, t, row, rm, w)


@njit(cache=True, inline="always")
def add_floor_row(D: np.ndarray, B: np.ndarray, g: np.ndarray, t: int, row: np.ndarray, r: float,
                  w: float) -> None:  # pragma: no cover (compiled)
    """:func:`~worldtrack.trajectory.kernels.add_pair_row` for a row (12,) that is 0 but for its floor entries
    (u, u̇, v, v̇ of each state: 0–3 and 6–9; ``barrier_point`` writes 0 into w, ẇ): the same
    products in the same order, but none of the 0.0 ones (so the same numbers bit for bit)."""
    for a in range(8):
        i = a if a < 4 else a + 2
        ji = row[i]
        if ji == 0.0:
            continue
        if i < STATE:
            g[t, i] += ji * r
        else:
            g[t + 1, i - STATE] += ji * r
        for b in range(8):
            j = b if b < 4 else b + 2
            v = w * ji * row[j]
            if i < STATE and j < STATE:
                D[t, i, j] += v
            elif i >= STATE and j >= STATE:
                D[t + 1, i - STATE, j - STATE] += v
            elif i < STATE:
                B[t, i, j - STATE] += v
