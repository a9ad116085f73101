"""Seed 003's error measures (eq. 21) and the failure rule the paper leaves out.

* :func:`rotation_error_deg` — ``arccos((tr(R0·Rᵀ) − 1) / 2)`` in degrees (eq. 21).
* :func:`axis_angle_deg` — angle between an estimated and a true limb axis (§5.2.1).
* :class:`FailureRule` — an error above ``limit_deg`` (10° for a face or object, 15° for a limb)
  for ``frames`` (5) consecutive frames is a failure; the tracker is then re-initialised at the
  true pose and the re-initialisation counted.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from worldtrack.geometry.rotation import rotation_angle_deg


def rotation_error_deg(R_true: np.ndarray, R_est: np.ndarray) -> np.ndarray:
    """Eq. 21: ``arccos((tr(R0·Rᵀ) − 1) / 2)`` in degrees, for (3, 3) or stacks (..., 3, 3).

    >>> float(rotation_error_deg(np.eye(3), np.diag([1.0, -1.0, -1.0])))
    180.0
    """
    return rotation_angle_deg(R_true, R_est)


def axis_angle_deg(a_true: np.ndarray, a_est: np.ndarray) -> np.ndarray:
    """Angle (degrees) between axes (..., 3) (need not be unit length).

    >>> round(float(axis_angle_deg(np.array([1.0, 0, 0]), np.array([1.0, 1.0, 0]))), 9)
    45.0
    """
    a, b = np.asarray(a_true, float), np.asarray(a_est, float)
    c = (a * b).sum(-1) / (np.linalg.norm(a, axis=-1) * np.linalg.norm(b, axis=-1))
    return np.degrees(np.arccos(np.clip(c, -1.0, 1.0)))


@dataclass
class FailureRule:
    """Counts failures: error > ``limit_deg`` for ``frames`` consecutive frames.

    ``update(error)`` returns True on the frame a failure is declared (the caller re-initialises);
    the run of bad frames then starts again from zero.

    >>> rule = FailureRule(10.0, 2)
    >>> [rule.update(e) for e in (11, 3, 12, 12, 12)], rule.failures
    ([False, False, False, True, False], 1)
    """

    limit_deg: float = 10.0
    frames: int = 5
    failures: int = 0
    _run: int = 0

    def update(self, error_deg: float) -> bool:
        self._run = self._run + 1 if error_deg > self.limit_deg else 0
        if self._run >= self.frames:
            self.failures += 1
            self._run = 0
            return True
        return False
