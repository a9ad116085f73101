"""Whether the top of a silhouette is this person's head (opt-in ``feet.head_clear``).

Where the feet are not trusted, the feet anchor (:mod:`.feet`) places a person under the top of
their head at their height. From a high camera, the people farther along the line of sight stand
higher in the image: the image above a person's head is the next person's legs, and a silhouette
that runs on into them tops out at the other person's head or at the edge of the region searched.
That top, taken for this person's head, moved tracks by up to ``depth_offset_m`` + 3 σ along the
line of sight (PETS 2009 View_001, camera 7 m high, people 15-30 m away: the anchor with the head
cue MOTA 0.872, with feet alone 0.941; issue 37). The head is trusted here only when

- the silhouette's top lies inside the region searched (the tallest plausible person's ellipse and
  its ring), not on its upper edge with foreground going on above it; and
- no other person's ellipse covers a pixel within ``FEET_CLEARANCE`` × the region's height of it.

Measured with the best one-camera opt-in (evidence shadow test, ``feet.anchor``, re-measuring after
encounters, height prior 0.1 m), issue 37: PETS View_001 (3 start frames) MOTA 0.846 -> 0.883, ID
switches 23.7 -> 18 (the head cue off altogether: 0.889); line-of-sight 640x480, 0.5 m gate, dev seeds
400-419 0.773 -> 0.759 (-0.014 +- 0.012 s.e., 8 better / 6 worse; head cue off: 0.739), held-out
420-439 0.732 -> 0.771 (+0.039 +- 0.020, 13 / 7; longest run > 0.5 m along the ray 7.0 -> 3.2 s),
never-used 440-449 0.682 -> 0.754 (+0.072 +- 0.025, 7 / 1; 5.8 -> 2.6 s).
Off by default (the anchor itself is).
"""

from __future__ import annotations

import numpy as np

from worldtrack.trackers.ellipsoid.height import silhouette_ends


def head_is_clear(camera, labels: np.ndarray, look: tuple, k: int) -> bool:
    """Whether the top of person ``k``'s silhouette in ``look`` (region (h, w) bool, owner (h, w) int32,
    box (u0, u1, v0, v1) px, image down (2,)) is their own head: inside the region and clear of others."""
    from worldtrack.trackers.ellipsoid.feet import touches_other   # feet.py imports this module

    region, owner, box, down = look
    ends = silhouette_ends(camera, labels, region, tuple(box), down)
    if ends is None:
        return False
    top = ends[0]
    u, v = int(round(top[0] - 2 * down[0])), int(round(top[1] - 2 * down[1]))
    inside = 0 <= u < labels.shape[1] and 0 <= v < labels.shape[0]
    if top[1] <= box[2] + 2 and inside and labels[v, u] == 1:
        return False   # the silhouette goes on above the region: its top is the region's edge
    return not touches_other(owner, box, top, k)


__all__ = ["head_is_clear"]
