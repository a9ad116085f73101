"""Who is the target? Colour evidence kept open after the decision (worldtrack, beyond seed 001).

The frame-by-frame decision (eq. 3 and the joint assignment) can take the wrong person at the worst
moment — the target reappearing from behind somebody while a neighbour steps out beside it — and
once the target itself is tracked as one of the *others*, nothing in a single frame brings it back.
So the identity stays an open hypothesis that evidence can overturn:

* every frame where colour means something (α < α_th), each person's candidate is scored against
  the target's templates (RBhat, eq. 1), and a running average per track is kept — the target's
  own and every other track's (time constant ``tau`` seconds);
* when another track has been seen long enough (``min_frames``) and its average is lower than the
  target's by at least ``margin``, the two tracks exchange roles: the target takes over that
  track's position and velocity, and the person followed so far becomes another person. The test
  is relative — who fits the templates better under the same light — because a change of light
  (front light to backlight while the target was hidden) raises every score alike.

While the identity is on probation — for ``probation`` seconds after the target is found again
after being unseen, or after an exchange — the templates do not learn, so a wrong person cannot
teach them their colours before the evidence has spoken.

>>> import numpy as np
>>> ev = IdentityEvidence(tau=0.5, min_frames=3)
>>> for _ in range(5):
...     ev.observe(0.1, 0.6, np.array([7]), np.array([0.15]))   # followed: 0.6; track 7: 0.15
>>> ev.better(margin=0.4)
7
"""

from __future__ import annotations

import numpy as np


class IdentityEvidence:
    """Running averages (time constant ``tau`` s) of RBhat against the target's templates.

    ``target`` : the followed track's average (NaN before any); ``ids``, ``mean``, ``frames`` : (K,)
    the other tracks', with how many frames went into each.
    """

    def __init__(self, tau: float = 0.5, min_frames: int = 3):
        self.tau = float(tau)
        self.min_frames = int(min_frames)
        self.target = np.nan
        self.target_frames = 0
        self.ids = np.zeros(0, dtype=np.int64)
        self.mean = np.zeros(0)
        self.frames = np.zeros(0, dtype=np.int64)

    @staticmethod
    def _blend(old: np.ndarray, new: np.ndarray, w: float) -> np.ndarray:
        return np.where(np.isfinite(old), (1 - w) * old + w * new, new)

    def observe(self, dt: float, target_rb: float | None, other_ids: np.ndarray, other_rb: np.ndarray) -> None:
        """One frame's scores: the target's candidate (None if unseen) and the seen other tracks' (K,)."""
        w = 1.0 - np.exp(-max(dt, 1e-3) / self.tau)
        if target_rb is not None and np.isfinite(target_rb):
            self.target = float(self._blend(np.array(self.target), np.array(target_rb), w))
            self.target_frames += 1
        other_ids = np.asarray(other_ids, dtype=np.int64)
        new = other_ids[~np.isin(other_ids, self.ids)]
        if len(new):
            self.ids = np.concatenate([self.ids, new])
            self.mean = np.concatenate([self.mean, np.full(len(new), np.nan)])
            self.frames = np.concatenate([self.frames, np.zeros(len(new), dtype=np.int64)])
        rows = np.array([np.flatnonzero(self.ids == i)[0] for i in other_ids], dtype=np.int64)
        self.mean[rows] = self._blend(self.mean[rows], np.asarray(other_rb, float), w)
        self.frames[rows] += 1

    def keep(self, alive_ids: np.ndarray) -> None:
        """Forget the tracks that ended."""
        k = np.isin(self.ids, alive_ids)
        self.ids, self.mean, self.frames = self.ids[k], self.mean[k], self.frames[k]

    def better(self, margin: float) -> int | None:
        """The id of another track that fits the target's templates clearly better than the
        followed one (see the module docstring), or None."""
        if not np.isfinite(self.target) or len(self.ids) == 0:
            return None
        ok = (self.frames >= self.min_frames) & (self.mean <= self.target - margin)
        if not ok.any():
            return None
        i = int(np.flatnonzero(ok)[np.argmin(self.mean[ok])])
        return int(self.ids[i])

    def exchange(self, other_id: int) -> None:
        """The followed track and ``other_id`` exchanged roles: exchange their evidence too."""
        i = int(np.flatnonzero(self.ids == other_id)[0])
        self.target, self.mean[i] = float(self.mean[i]), self.target
        self.target_frames, self.frames[i] = int(self.frames[i]), self.target_frames
