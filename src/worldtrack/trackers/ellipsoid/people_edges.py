"""Births in a crowd one camera sees: where a new person's blob ends on somebody already tracked.

A birth blob (:mod:`.births`) is the foreground the ellipses of the people already known do not
explain. Its ends tell where the new person stands: the end in the direction of world-down is the
feet, the other the top of the head — unless the blob ends there on the image border or an
obstacle, which hide the feet or the head. In a crowd seen from one corner the blob mostly ends on
*another person's ellipse*: somebody standing behind a tracked person shows only a band of head and
shoulders above them, somebody in front of one shows the legs below them. Read as feet, the lower
end of such a head band puts the person metres too far along the line of sight (often off the
floor); and the blob, a part of the person, is then too small for the size test, which expects
everything the obstacles leave of a person standing there (issue 37: on crowd 50's development seed
110, 65 % of the person-frames of people at least half visible with no track had either no blob
left by the others' ellipses or one too small to count).

With ``crowd.births_past_people`` the births read the others' ellipses as they read obstacles:

* :func:`ends_on_people` — an end whose pixels just beyond lie mostly inside the (dilated) ellipses
  of known people is hidden: feet hidden → the head places the person (at the default height);
  head hidden → the feet place them; either way the blob shows only part of the person;
* :func:`unexplained_pixels` — the size test's "pixels a person there would show" leaves out those
  the known people's ellipses already explain (they cannot be in the blob either).

>>> import numpy as np
>>> explained = np.zeros((40, 40), np.uint8); explained[20:, :] = 1        # a tracked person below row 20
>>> ends_on_people(explained, foot=np.array([10.0, 19.0]), head=np.array([10.0, 5.0]),
...                down=np.array([0.0, 1.0]), half=3.0)                     # a head band above them
(True, False)
"""

from __future__ import annotations

import numpy as np

from worldtrack.trackers.ellipsoid.cameras import CameraView
from worldtrack.trackers.ellipsoid.forms import ellipse_crop

#: Pixels beyond a blob's end that are tested (the births' mask is dilated 2 px round each ellipse).
BEYOND_PX = 3.0
#: Share of the tested pixels inside known people's ellipses that hides an end.
HIDDEN_SHARE = 0.5


def covered_share(mask: np.ndarray, points: np.ndarray) -> float:
    """Share of image points ``points`` (N, 2) px, rounded, that fall on nonzero pixels of ``mask``
    (H, W); points outside the image count as not covered.

    >>> m = np.zeros((4, 4), np.uint8); m[0, :2] = 1
    >>> covered_share(m, np.array([[0.0, 0.0], [1.2, 0.1], [3.0, 3.0], [9.0, 0.0]]))
    0.5
    """
    q = np.rint(np.asarray(points, float)).astype(int)
    inside = (q[:, 0] >= 0) & (q[:, 0] < mask.shape[1]) & (q[:, 1] >= 0) & (q[:, 1] < mask.shape[0])
    hit = np.zeros(len(q), dtype=bool)
    hit[inside] = mask[q[inside, 1], q[inside, 0]] != 0
    return float(hit.mean()) if len(q) else 0.0


def ends_on_people(explained: np.ndarray, foot: np.ndarray, head: np.ndarray, down: np.ndarray,
                   half: float) -> tuple[bool, bool]:
    """Whether a blob's lower end (feet) and upper end (head top) lie on known people.

    Parameters
    ----------
    explained : (H, W) uint8 — nonzero where the ellipses of the people already known lie
    foot, head : (2,) float — the blob's two ends along world-down, px
    down : (2,) float — unit image direction of world-down there
    half : float — half the blob's width tested across it, px

    Returns
    -------
    (feet hidden, head hidden) : bool — :data:`HIDDEN_SHARE` or more of 9 pixels
    :data:`BEYOND_PX` beyond the end, across ±``half``, are inside ``explained``
    """
    down = np.asarray(down, float)
    across = np.array([-down[1], down[0]])
    spread = np.linspace(-half, half, 9)[:, None] * across
    below = np.asarray(foot, float) + BEYOND_PX * down + spread
    above = np.asarray(head, float) - BEYOND_PX * down + spread
    return covered_share(explained, below) >= HIDDEN_SHARE, covered_share(explained, above) >= HIDDEN_SHARE


def unexplained_pixels(view: CameraView, xy: np.ndarray, height: float, width: float,
                       explained: np.ndarray) -> int:
    """Pixels of a person's ellipse at ``xy`` (2,) m that are in the image, in front of the scene's
    obstacles and outside ``explained`` ((H, W) uint8, the known people's ellipses): the most a
    birth blob of a person standing there can hold."""
    inner, _, box, valid, dist = view.forms(np.asarray(xy, float)[None], np.array([height]), np.array([width]))
    u0, u1, v0, v1 = box[0]
    if not valid[0] or u0 >= u1 or v0 >= v1:
        return 0
    inside = ellipse_crop(inner[0], box[0], view.grid, view.args.has_dist)
    free = (view.occ[v0:v1, u0:u1] >= dist[0]) & (explained[v0:v1, u0:u1] == 0)
    return int((inside & free).sum())


__all__ = ["BEYOND_PX", "HIDDEN_SHARE", "covered_share", "ends_on_people", "unexplained_pixels"]
