"""People behind a person do not hide them: the feet anchor's cover test counts only people in front (opt-in).

The feet anchor (:mod:`.feet`) reads a person's feet and head only where others' ellipses cover
at most :data:`~.height.MAX_COVERED_FOR_HEIGHT` of the region their pixels may be in. With one
camera, a person walking in front of somebody farther away shares a silhouette with them, and the
farther person's ellipse covers much of the near person's region: no cue is read, the matched
ellipse alone places the near person, and it slides away along the line of sight (a merged
silhouette is fitted better by a larger, farther ellipse). On the line-of-sight development seeds
20-39 that was the most common case of a track displaced along the ray with its height right
(seed 27: a 1.52 m person 5 m away, in clear view, pulled 0.9 m back onto the person behind).

Somebody farther along the line of sight cannot hide any of this person's pixels, and their feet
are higher in the image: the lowest foreground in the region is still this person's feet. So with
``behind_margin_m`` > 0 only people nearer than ``d_k + margin`` (and pixels several ellipses
front share) count as cover (:func:`in_front`), and the pixels of people behind are read as this person's: their
head may then top the silhouette, so a height read too *tall* above the feet does not reject them
(:func:`overlaps_behind`); too short still does (legs the floor's colour).

>>> import numpy as np
>>> farther(np.zeros(2), np.array([[0.0, 5.0], [0.0, 6.0], [0.0, 5.3]]), 0, 0.5).tolist()
[False, True, False]
"""

from __future__ import annotations

import numpy as np

from worldtrack.trackers.ellipsoid.args import Forms


def farther(camera_xy: np.ndarray, xy: np.ndarray, k: int, margin_m: float) -> np.ndarray:
    """(N,) bool: the people at floor points ``xy`` (N, 2) more than ``margin_m`` (m) farther from the camera
    (its floor point ``camera_xy`` (2,)) than person ``k``."""
    d = np.hypot(*(np.asarray(xy, dtype=float) - camera_xy).T)
    return d > d[k] + margin_m


def in_front(forms: Forms, k: int, behind: np.ndarray) -> Forms:
    """The ellipses ``forms`` of the people who may hide person ``k``: all but ``k`` and those ``behind`` (N,) bool."""
    keep = forms.valid & ~behind
    keep[k] = False
    return forms._replace(valid=keep)


def overlaps_behind(boxes: np.ndarray, box: np.ndarray, behind: np.ndarray) -> bool:
    """Whether the image box of any of the people ``behind`` (N,) bool (``boxes`` (N, 4): u0, u1, v0, v1, end
    exclusive) meets ``box`` (4,)."""
    b = np.asarray(boxes)[np.asarray(behind, bool)]
    return bool(np.any((b[:, 0] < box[1]) & (box[0] < b[:, 1]) & (b[:, 2] < box[3]) & (box[2] < b[:, 3])))


__all__ = ["farther", "in_front", "overlaps_behind"]
