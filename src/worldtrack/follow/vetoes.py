"""Who cannot be the lost target (worldtrack, beyond seed 001): evidence that vetoes a candidate when
the target is found again, whatever its D.

* **Height** (:class:`TargetHeight`) — the depth camera measures each candidate's highest point:
  somebody partly hidden, or cut off by the image's upper edge, measures lower than their height,
  never higher. So a candidate *taller* than the target by more than a margin is vetoed, and one
  *shorter* only if its head is seen (:func:`heads_seen`: a point ``HEAD_ROOM`` above the measured
  top projects inside the image, and no nearer candidate covers its image box); the target's
  height is learnt only from frames where its head is seen,
  as an upper envelope (rising with time constant ``RISE_TAU`` s, falling with ``FALL_TAU``: a
  head lower than the height is more likely than one higher), and used only once it has been
  learnt for ``CONFIRM_S`` seconds — a single frame with the head hidden must not set a height
  that would veto the target itself.
* **Somebody hiding it** (:func:`hiding_target`) — a person who appears just as the target vanishes,
  where it vanishes, nearer the camera and covering where it should stand, is in front of it.
* **Pieces of somebody else** (:func:`pieces_of_others`) — near the camera one body is often seen
  as two candidates. A candidate within ``FRAGMENT_RADIUS`` of one that another person's track holds
  in the same frame is a piece of that person, seen while the target was not.

>>> import numpy as np
>>> xy = np.array([[0.0, 0.0], [0.35, 0.0], [2.0, 0.0]])
>>> pieces_of_others(xy, np.array([True, False, False])).tolist()    # candidate 0 is another's
[False, True, False]
>>> h = TargetHeight()
>>> h.value, h.seen_s = 1.65, 3.0
>>> h.mismatch(np.array([1.70, 1.80, 1.40, 1.40]), np.array([True, False, False, True]), margin=0.1).tolist()
[False, True, False, True]
"""

from __future__ import annotations

import numpy as np

from worldtrack.follow.silhouette import covering, person_box
from worldtrack.geometry.camera import Camera

#: A person this much nearer the camera (m) covering this share of the target's expected image box
#: may be hiding it.
HIDE_MARGIN, HIDE_SHARE = 0.25, 0.3
#: ... unless it stands this close (m) to the target's way since it was last measured (the target, stopped).
STOPPED_RADIUS = 0.3
#: A candidate this near (m) one of another tracked person's is a piece of that person.
FRAGMENT_RADIUS = 0.5
#: The target's height is learnt only from frames where a point this far (m) above its top is in the
#: image (the head is not cut off by the image's upper edge).
HEAD_ROOM = 0.15
#: Time constants (s) of the learnt height moving up to a higher top and down to a lower one.
RISE_TAU, FALL_TAU = 0.3, 5.0
#: The height vetoes nobody until it has been learnt from this many seconds of frames.
CONFIRM_S = 2.0


def pieces_of_others(xy: np.ndarray, held: np.ndarray) -> np.ndarray:
    """(N,) candidates (positions (N, 2), m) within ``FRAGMENT_RADIUS`` of a candidate that another
    person's track holds (``held`` (N,) bool), themselves not held."""
    held = np.asarray(held, bool)
    if not held.any():
        return np.zeros(len(xy), dtype=bool)
    d = np.hypot(*(xy[:, None] - xy[held][None]).transpose(2, 0, 1))
    return (d <= FRAGMENT_RADIUS).any(axis=1) & ~held


def hiding_target(obs, predicted_xy: np.ndarray, last_xy: np.ndarray) -> np.ndarray:
    """(N,) candidates of ``obs`` (an :class:`~worldtrack.follow.observation.Observation`) that may be
    hiding the target: more than ``HIDE_MARGIN`` nearer the camera than its prediction
    ``predicted_xy`` (2,) m and covering at least ``HIDE_SHARE`` of the image box where it should
    stand; except one standing on the target's way from where it was last measured (``last_xy``) to
    its prediction (within ``STOPPED_RADIUS``): that is the target, stopped while its
    constant-velocity prediction walked on. None without a camera."""
    c, n = obs.candidates, len(obs.candidates)
    if obs.camera is None or n == 0:
        return np.zeros(n, dtype=bool)
    cover = covering(obs.silhouettes, n, person_box(obs.camera, predicted_xy))
    centre = obs.camera.centre[:2]
    nearer = np.hypot(*(c.xy - centre).T) < np.hypot(*(predicted_xy - centre)) - HIDE_MARGIN
    way = predicted_xy - last_xy
    along = np.clip((c.xy - last_xy) @ way / max(way @ way, 1e-12), 0.0, 1.0)
    stopped = np.hypot(*(c.xy - last_xy - along[:, None] * way).T) <= STOPPED_RADIUS
    return nearer & (cover >= HIDE_SHARE) & ~stopped


def head_in_view(camera: Camera | None, xy, top: float) -> bool:
    """Whether a candidate at floor position ``xy`` (2,) m whose highest measured point is ``top`` m shows
    its head: a point ``HEAD_ROOM`` above it projects into ``camera``'s image (NaN top: False)."""
    if camera is None or not np.isfinite(top):
        return False
    uv, z = camera.project(np.array([xy[0], xy[1], top + HEAD_ROOM]), return_depth=True)
    return bool(z > 0 and camera.in_image(uv, margin=1.0))


def heads_seen(candidates, silhouettes: np.ndarray, camera: Camera | None) -> np.ndarray:
    """(N,) candidates whose measured top is their height: the head is inside the image
    (:func:`head_in_view`) and no nearer candidate's silhouette covers more than 2 % of their image box."""
    n = len(candidates)
    out = np.zeros(n, dtype=bool)
    for i in range(n):
        if head_in_view(camera, candidates.xy[i], float(candidates.top[i])):
            nearer = candidates.depth < candidates.depth[i]
            cover = covering(silhouettes, n, person_box(camera, candidates.xy[i]))
            out[i] = not (cover[nearer] > 0.02).any()
    return out


class TargetHeight:
    """The target's height (m; NaN until a frame showed its head), learnt from its candidates' tops;
    ``seen_s`` : seconds of frames it was learnt from."""

    def __init__(self) -> None:
        self.value = np.nan
        self.seen_s = 0.0

    def learn(self, top: float, dt: float) -> None:
        """Move towards ``top`` (m), the top of a candidate whose head is seen — up with time constant
        ``RISE_TAU``, down with ``FALL_TAU`` (the first such frame sets it)."""
        self.seen_s += max(dt, 0.0)
        if not np.isfinite(self.value):
            self.value = float(top)
            return
        tau = RISE_TAU if top > self.value else FALL_TAU
        self.value += (1.0 - np.exp(-max(dt, 0.0) / tau)) * (float(top) - self.value)

    def mismatch(self, tops: np.ndarray, seen: np.ndarray, margin: float) -> np.ndarray:
        """(N,) candidates whose highest point (N,) m is more than ``margin`` m above the target's height,
        or below it with the head ``seen`` (N,) bool (none while the height is unknown, learnt from less
        than ``CONFIRM_S`` s, or ``margin`` ≤ 0)."""
        tops = np.asarray(tops, float)
        if not (margin > 0 and np.isfinite(self.value) and self.seen_s >= CONFIRM_S):
            return np.zeros(len(tops), dtype=bool)
        return (tops > self.value + margin) | (np.asarray(seen, bool) & (tops < self.value - margin))
