"""Who cannot be the lost target (worldtrack, beyond seed 001): evidence that vetoes a candidate when
the target is found again, whatever its D.

* **Height** (:class:`TargetHeight`) — the depth camera measures each candidate's highest point. For
  the target it is learnt (an exponential average, ``HEIGHT_TAU`` s) from frames where its head is
  in the image: a point ``HEAD_ROOM`` above the measured top projects inside it. Somebody partly
  hidden, or cut off by the image's upper edge, measures lower than their height, never higher, so
  only a candidate *taller* than the target by more than a margin is vetoed.
* **Pieces of somebody else** (:func:`pieces_of_others`) — near the camera one body is often seen
  as two candidates. A candidate within ``FRAGMENT_RADIUS`` of one that another person's track holds
  in the same frame is a piece of that person, seen while the target was not.

>>> import numpy as np
>>> xy = np.array([[0.0, 0.0], [0.35, 0.0], [2.0, 0.0]])
>>> pieces_of_others(xy, np.array([True, False, False])).tolist()    # candidate 0 is another's
[False, True, False]
>>> h = TargetHeight()
>>> h.value = 1.65
>>> h.too_tall(np.array([1.70, 1.80, 1.40]), margin=0.1).tolist()
[False, True, False]
"""

from __future__ import annotations

import numpy as np

from worldtrack.geometry.camera import Camera

#: A candidate this near (m) one of another tracked person's is a piece of that person.
FRAGMENT_RADIUS = 0.5
#: The target's height is learnt only from frames where a point this far (m) above its top is in the
#: image (the head is not cut off by the image's upper edge).
HEAD_ROOM = 0.15
#: Time constant (s) of the target's learnt height.
HEIGHT_TAU = 3.0


def pieces_of_others(xy: np.ndarray, held: np.ndarray) -> np.ndarray:
    """(N,) candidates (positions (N, 2), m) within ``FRAGMENT_RADIUS`` of a candidate that another
    person's track holds (``held`` (N,) bool), themselves not held."""
    held = np.asarray(held, bool)
    if not held.any():
        return np.zeros(len(xy), dtype=bool)
    d = np.hypot(*(xy[:, None] - xy[held][None]).transpose(2, 0, 1))
    return (d <= FRAGMENT_RADIUS).any(axis=1) & ~held


def head_in_view(camera: Camera | None, xy, top: float) -> bool:
    """Whether a candidate at floor position ``xy`` (2,) m whose highest measured point is ``top`` m shows
    its head: a point ``HEAD_ROOM`` above it projects into ``camera``'s image (NaN top: False)."""
    if camera is None or not np.isfinite(top):
        return False
    uv, z = camera.project(np.array([xy[0], xy[1], top + HEAD_ROOM]), return_depth=True)
    return bool(z > 0 and camera.in_image(uv, margin=1.0))


class TargetHeight:
    """The target's height (m; NaN until a frame showed its head), learnt from its candidates' tops."""

    def __init__(self) -> None:
        self.value = np.nan

    def learn(self, camera: Camera | None, xy, top: float, dt: float) -> None:
        """Blend ``top`` (m) in with weight ``1 − exp(−dt/HEIGHT_TAU)`` if the candidate at ``xy`` shows
        its head (the first such frame sets it)."""
        if not head_in_view(camera, xy, top):
            return
        if not np.isfinite(self.value):
            self.value = float(top)
            return
        w = 1.0 - np.exp(-max(dt, 0.0) / HEIGHT_TAU)
        self.value = (1 - w) * self.value + w * float(top)

    def too_tall(self, tops: np.ndarray, margin: float) -> np.ndarray:
        """(N,) candidates whose highest point (N,) m is more than ``margin`` m above the target's height
        (none while it is unknown or ``margin`` ≤ 0)."""
        tops = np.asarray(tops, float)
        if not (margin > 0 and np.isfinite(self.value)):
            return np.zeros(len(tops), dtype=bool)
        return tops > self.value + margin
