"""Depth of a person others cover: their own head, where it is clear of the others (opt-in).

With one camera, the feet anchor (:mod:`.feet`) is silent for a person whose region others'
ellipses cover by more than :data:`~.height.MAX_COVERED_FOR_HEIGHT`: a near person walking in front
of a far one. Nothing then holds the far person's distance: the match slides their ellipse along
the line of sight towards the near person's silhouette (line-of-sight seed 410: a 1.97 m person
standing 9.1 m away slid to 4.4 m in 2 s behind a 1.6 m walker, became the walker's duplicate, and
was born again 1.2 m too far). Yet the far person's head often stays in view above the near one,
and a measured height puts it at one distance: the top of the head's ray at that height
(σ along the ray ``σ_h · d / (H − h)``, 0.3 m for σ_h 3 cm at 9 m from a camera 2.9 m high).

So, with ``depth.head_when_covered``, a tracked person one camera alone shows, covered there by
others, with a measured height (3 samples or more), is moved along that camera's line of sight
towards the point under their head by the share the uncertainties give, as the anchor does with
the feet, when the top of the pixels nobody else's ellipse owns is their head: inside the region
searched and clear of the others' ellipses (:func:`~.head_clear.head_is_clear`), and when the
point lies within ``GATE_SIGMAS`` of its σ of the track along the ray: the cue holds a person where
they were, it does not move them far (without the gate, a tall far person's head on top of a near
one's silhouette moved the near one 0.9 m away in one frame: seed 406).

Measured with the best one-camera opt-in (evidence shadow test, ``feet.anchor``, re-measuring after
encounters, height prior 0.1 m, ``feet.head_clear``), line-of-sight 640x480, 0.5 m gate, MOTA paired by
seed: dev 400-419 0.759 -> 0.779 (+0.020 ± 0.020, 13 better / 6 worse), held-out 420-439 0.771 -> 0.796
(+0.025 ± 0.022, 9 / 6), new 460-479 0.801 -> 0.795 (-0.006 ± 0.017, 9 / 10), never-used 480-489
0.760 -> 0.775 (+0.015 ± 0.025, 5 / 3). Displaced along the ray (fp + miss, dev) 0.122 -> 0.108. A
held duplicate behind a real person (seed 402) and a longer worst run (dev 2.7 -> 6.8 s) are its
costs: off by default.
"""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from worldtrack.trackers.base import Person
from worldtrack.trackers.ellipsoid.cameras import CameraView
from worldtrack.trackers.ellipsoid.config import FeetConfig, HeightConfig
from worldtrack.trackers.ellipsoid.forms import ellipse_crop, owner_crop
from worldtrack.trackers.ellipsoid.head_clear import head_is_clear
from worldtrack.trackers.ellipsoid.height import MAX_COVERED_FOR_HEIGHT, head_ray
from worldtrack.trackers.ellipsoid.height_sigma import height_sigma
from worldtrack.trackers.ellipsoid.support import MIN_OWN_PIXELS

#: Height samples a person needs before their head alone places them behind others.
MIN_SAMPLES = 3
#: The head's place counts only this many of its σ along the ray from the track: a hold, not a jump.
GATE_SIGMAS = 2.0


def hold_covered_by_head(people: Sequence[Person], views: Mapping[str, CameraView], labels: Mapping[str, np.ndarray],
                         walkable, feet: FeetConfig, height: HeightConfig) -> int:
    """Move each of ``people`` that one camera alone shows, covered there by others, towards the
    floor point under their clear head at their measured height (see the module docstring).

    Parameters
    ----------
    people : the people this tracker judges
    views, labels : the tracker's cameras and their foreground labels, by camera id
    walkable : callable — (M, 2) floor points → (M,) bool; a move off the floor is not made
    feet : FeetConfig (the ellipse's σ along the ray, the measured height's least σ, min_px)
    height : HeightConfig (plausible range, the depth offset allowed)

    Returns
    -------
    int — how many people were moved
    """
    from worldtrack.trackers.ellipsoid.feet import feet_weight, under_head   # feet.py imports head_clear

    if not people:
        return 0
    xy = np.array([[p.x, p.y] for p in people], dtype=float)
    hs = np.array([p.height for p in people], dtype=float)
    ws = np.array([p.width for p in people], dtype=float)
    shown = {cid: [v.visible_pixels(xy[k], p.height, p.width) >= MIN_OWN_PIXELS for k, p in enumerate(people)]
             for cid, v in views.items()}
    moves = 0
    for cid, image_labels in labels.items():
        view, cam = views[cid], views[cid].camera
        _, ring, box, valid, _ = view.forms(xy, np.full(len(xy), height.range_m[1]), 1.25 * ws)
        current = view.forms(xy, hs, ws)
        for k, p in enumerate(people):
            if (not shown[cid][k] or sum(s[k] for s in shown.values()) != 1 or not valid[k] or p.mode != "tracking"
                    or len(p.height_samples) < MIN_SAMPLES):
                continue
            u0, u1, v0, v1 = (int(b) for b in box[k])
            if u0 >= u1 or v0 >= v1 or (v1 - v0) < feet.min_px:
                continue
            region = ellipse_crop(ring[k], box[k], view.grid, cam.has_distortion)
            owner = owner_crop(box[k], current, view.grid, cam.has_distortion)
            free = (owner == k) | (owner == -1)
            if np.count_nonzero(region & ~free) <= MAX_COVERED_FOR_HEIGHT * np.count_nonzero(region):
                continue   # not covered: the feet anchor's case
            down = view.down_direction(np.array([(u0 + u1) / 2, (v0 + v1) / 2]))
            if down is None:
                continue
            look = (region & free, owner, box[k], down)
            if not head_is_clear(cam, image_labels, look, k):
                continue
            head = head_ray(cam, image_labels, view.occ, look[0], tuple(box[k]), down, border="silhouette")
            sigma_h = height_sigma(p, feet.height_sigma_m, feet.measured_height_sigma_m)
            place = under_head(head, hs[k], sigma_h, xy[k], cam, height.depth_offset_m)
            if place is None:
                continue
            ray = place[0] - cam.centre[:2]
            ray = ray / max(float(np.hypot(*ray)), 1e-9)
            along = float((place[0] - xy[k]) @ ray)
            if abs(along) > GATE_SIGMAS * place[1]:
                continue   # farther than the head's own σ allows: most likely somebody else's head on top
            new = xy[k] + feet_weight(feet.ellipse_sigma_m, place[1]) * along * ray
            if walkable(new[None])[0]:
                p.x, p.y = float(new[0]), float(new[1])
                moves += 1
    return moves


__all__ = ["GATE_SIGMAS", "MIN_SAMPLES", "hold_covered_by_head"]
