"""Tracking the other people (worldtrack, beyond seed 001), so that a crossing cannot swap the target.

Every candidate that is not the target is followed by its own constant-velocity Kalman filter and
colour histogram (an average of its recent silhouettes). Each frame all candidates are assigned at
once — to the target, to one of the others or to nobody — by the smallest total dissimilarity
(Hungarian algorithm, ``scipy.optimize.linear_sum_assignment``): each person scores each candidate
with eq. 3 against its own template and its own prediction, and leaving a person unassigned costs
the decision threshold. A person who walks between the robot and the target is then explained by
their own track and cannot take the target's place, even in the same clothes.

Unassigned candidates start new tracks; a track unseen for ``others_max_coast`` seconds ends.

>>> import numpy as np
>>> cost = np.array([[0.1, 0.6], [0.2, 0.05]])            # target and one other, two candidates
>>> assign(cost, threshold=0.5).tolist()                  # target → 0, other → 1
[0, 1]
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

from worldtrack.follow import kalman

BIG = 1e6


def assign(cost: np.ndarray, threshold: float) -> np.ndarray:
    """(R,) candidate index for each row of ``cost`` (R, N), −1 for none; each candidate used once.

    Leaving row r unassigned costs ``threshold``; a pair costing ``threshold`` or more (or inf) is
    never made.
    """
    R, N = cost.shape
    if R == 0:
        return np.zeros(0, dtype=np.int64)
    c = np.where(np.isfinite(cost) & (cost < threshold), cost, BIG)
    dummy = np.full((R, R), BIG)
    np.fill_diagonal(dummy, threshold)
    rows, cols = linear_sum_assignment(np.hstack([c, dummy]))
    out = np.full(R, -1, dtype=np.int64)
    real = cols < N
    ok = real & (c[rows, np.minimum(cols, N - 1)] < BIG) if N else np.zeros(len(rows), bool)
    out[rows[ok]] = cols[ok]
    return out


class Others:
    """The other people's tracks: ids from 2 (1 is the target), states, histograms, last seen."""

    def __init__(self, n_bins: int, accel_sigma: float, measurement_sigma: float, max_coast: float):
        self.ids = np.zeros(0, dtype=np.int64)
        self.x = np.zeros((0, 4))
        self.P = np.zeros((0, 4, 4))
        self.hist = np.zeros((0, n_bins))
        self.last_seen = np.zeros(0)
        self.born = np.zeros(0)
        self.next_id = 2
        self.accel_sigma = accel_sigma
        self.measurement_sigma = measurement_sigma
        self.max_coast = max_coast

    def __len__(self) -> int:
        return len(self.ids)

    def predict(self, dt: float) -> None:
        if len(self) and dt > 0:
            self.x, self.P = kalman.predict(self.x, self.P, dt, self.accel_sigma)

    def update(self, rows: np.ndarray, xy: np.ndarray, hists: np.ndarray, t: float, dt: float,
               tau: float = 1.0) -> None:
        """Correct tracks ``rows`` with positions (K, 2) and blend in their histograms (K, B)."""
        if len(rows) == 0:
            return
        x, P = kalman.update(self.x[rows], self.P[rows], xy, self.measurement_sigma)
        self.x[rows], self.P[rows] = x, P
        w = 1.0 - np.exp(-max(dt, 1e-3) / tau)
        has = hists.sum(axis=1) > 0
        blended = (1 - w) * self.hist[rows] + w * hists
        self.hist[rows[has]] = blended[has] / np.maximum(blended[has].sum(axis=1, keepdims=True), 1e-12)
        self.last_seen[rows] = t

    def add(self, xy: np.ndarray, hists: np.ndarray, t: float) -> np.ndarray:
        """Start tracks at positions (K, 2) with histograms (K, B); returns their ids."""
        k = len(xy)
        if k == 0:
            return np.zeros(0, dtype=np.int64)
        new_ids = np.arange(self.next_id, self.next_id + k)
        self.next_id += k
        x, P = kalman.initial_state(xy, self.measurement_sigma)
        self.ids = np.concatenate([self.ids, new_ids])
        self.x = np.concatenate([self.x, x])
        self.P = np.concatenate([self.P, P])
        self.hist = np.concatenate([self.hist, hists.astype(np.float64)])
        self.last_seen = np.concatenate([self.last_seen, np.full(k, t)])
        self.born = np.concatenate([self.born, np.full(k, t)])
        return new_ids

    def remove(self, keep: np.ndarray) -> None:
        """Keep only the tracks where ``keep`` (bool) is True."""
        for name in ("ids", "x", "P", "hist", "last_seen", "born"):
            setattr(self, name, getattr(self, name)[keep])

    def expire(self, t: float) -> None:
        """End tracks unseen for longer than ``max_coast`` seconds."""
        if len(self):
            self.remove(t - self.last_seen <= self.max_coast + 1e-9)

    def gate(self, t: float, base: float, growth: float, max_gate: float) -> np.ndarray:
        """(K,) largest accepted distance (m) from each prediction: grows while a track is unseen."""
        return np.minimum(base + growth * (t - self.last_seen), max_gate)
