"""Depth from the feet: where a camera sees a person whole and alone, their feet pin the distance.

An ellipsoid matched to a person's silhouette is uncertain mostly along the camera's line of
sight, and biased there: a body is narrower than its ellipse at the legs and the head, so a
smaller, farther ellipse fits the silhouette better (0.5–1 m too far at 8 m from a camera 2.85 m
high, even with the right height). The feet, back-projected to the floor, do not depend on the
model's height or width. So after the matching rounds each person seen clear of others, with
the feet in view and not on an obstacle, moves along that camera's line of sight towards the
feet, by the share their uncertainties give (a Kalman update along the ray):
``w = σ_ellipse² / (σ_ellipse² + σ_feet²)``. Only people that one camera alone shows: two views
from different sides pin the depth already, and in a crowd the bottom of a region is too often
somebody else's feet (the 10-person crowd in two cameras fell from MOTA 0.99 to 0.52 on a seed
with the anchor applied in both views).

The feet are trusted only when the silhouette is a whole person standing there: the top of the
head's viewing ray, above the feet found, must be at a plausible height within
``height_match_m`` of the person's height. Legs in the floor's colour end the foreground at the
waist; that "foot" would put the person metres too far, and the head's height above it is far too
low, so it is not used.

Three ways the feet went unread or misread with one camera (issue 37, line-of-sight dev seeds 20-39):

- a person whole in view near the image's side: the search box (the tallest person's ellipse and
  ring) reaches past the edge, so the feet were never read; the silhouette is asked instead
  (:func:`~.border.cut_by_border`, ``border="silhouette"``);
- feet beside another person's ellipse (:func:`touches_other`): the bottom of the region there may be
  that person's body (a far person's silhouette running down into a near one's) and is not taken;
- a track already too far along the ray to hold its own feet: its region ends above them, the
  silhouette goes on below, and the head at a wrong height holds it there; the feet are looked for
  again with the region drawn at the cut (``REACH_STEPS`` times).

Measured with the best one-camera opt-in (evidence shadow test, ``feet.anchor``, re-measuring after
encounters, height prior 0.1 m), 640x480, 0.5 m gate: MOTA on dev seeds 20-39 0.740 -> 0.807; on
never-used seeds 170-189 0.736 -> 0.764 (IDF1 0.731 -> 0.813), 150-169 0.767 -> 0.780.

>>> round(feet_weight(0.3, 0.1), 2)
0.9
"""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from worldtrack.trackers.base import Person
from worldtrack.trackers.ellipsoid.anchor_footprint import standing_point
from worldtrack.trackers.ellipsoid.anchor_gates import feet_doubted, height_gate_m
from worldtrack.trackers.ellipsoid.cameras import CameraView
from worldtrack.trackers.ellipsoid.config import AnchorHeightConfig, FeetConfig, HeightConfig
from worldtrack.trackers.ellipsoid.feet_pixel import feet_sigma_m
from worldtrack.trackers.ellipsoid.head_clear import head_is_clear
from worldtrack.trackers.ellipsoid.forms import ellipse_crop, owner_crop
from worldtrack.trackers.ellipsoid.height import MAX_COVERED_FOR_HEIGHT, head_ray, measure_feet, silhouette_ends
from worldtrack.trackers.ellipsoid.support import MIN_OWN_PIXELS
from worldtrack.trackers.ellipsoid.toes import beyond_toes


def feet_weight(ellipse_sigma_m: float, feet_sigma_m: float) -> float:
    """Share of the way from the ellipse's place to the feet (0–1): σ_e² / (σ_e² + σ_f²)."""
    e, f = ellipse_sigma_m ** 2, feet_sigma_m ** 2
    return e / (e + f) if e + f > 0 else 0.0


def anchor_to_feet(people: Sequence[Person], views: Mapping[str, CameraView], labels: Mapping[str, np.ndarray],
                   walkable, config: FeetConfig, height: HeightConfig, gate: AnchorHeightConfig | None = None) -> int:
    """Move each of ``people`` along the line of sight of every camera that shows their feet
    (see the module docstring); returns how many moves were made.

    Parameters
    ----------
    people : the people this tracker judges (every one's ellipse owns pixels)
    views, labels : the tracker's cameras and their foreground labels, by camera id
    walkable : callable — (M, 2) floor points → (M,) bool; a move off the floor is not made
    config : FeetConfig; height : HeightConfig (plausible range, the depth offset allowed)
    gate : AnchorHeightConfig — how tight ``config.height_sigmas``'s gate is (default: its defaults)
    """
    if not config.anchor or not people:
        return 0
    # Only people one camera alone shows: a second view from elsewhere pins the depth already, and
    # in a crowd the bottom (or top) of a region is too often somebody else's feet (or head).
    seen_by = [sum(v.visible_pixels(np.array([p.x, p.y]), p.height, p.width) >= MIN_OWN_PIXELS
                   for v in views.values()) for p in people]
    xy = np.array([[p.x, p.y] for p in people], dtype=float)
    hs = np.array([p.height for p in people], dtype=float)
    ws = np.array([p.width for p in people], dtype=float)
    moves = 0
    for cid, image_labels in labels.items():
        view = views[cid]
        found = _feet_in_view(view, image_labels, (xy, hs, ws), people, height, config, gate or AnchorHeightConfig())
        for k, (place, sigma) in found.items():
            if seen_by[k] != 1:
                continue
            ray = place - view.camera.centre[:2]
            ray = ray / max(float(np.hypot(*ray)), 1e-9)
            along = float((place - xy[k]) @ ray)
            new = xy[k] + feet_weight(config.ellipse_sigma_m, sigma) * along * ray
            if walkable(new[None])[0]:
                people[k].x, people[k].y = float(new[0]), float(new[1])
                moves += 1
    return moves


def _feet_in_view(view: CameraView, labels: np.ndarray, people: tuple[np.ndarray, np.ndarray, np.ndarray],
                  persons: Sequence[Person], height: HeightConfig, config: FeetConfig, gate_config: AnchorHeightConfig
                  ) -> dict[int, tuple[np.ndarray, float]]:
    """{index: (floor point (2,), its σ along the line of sight, m)} of the people this camera shows
    clear of others: their feet, or where feet are not to be trusted, the point under the top of
    the head at the person's height (σ: the height's uncertainty times the ray's slope)."""
    xy, hs, ws = people
    lo, hi = height.range_m
    cam = view.camera
    _, ring, box, valid, _ = view.forms(xy, np.full(len(xy), hi), 1.25 * ws)
    current = view.forms(xy, hs, ws)
    out: dict[int, np.ndarray] = {}
    for k, p in enumerate(persons):
        if not valid[k] or p.mode not in ("tracking", "capture"):
            continue
        b = box[k]
        u0, u1, v0, v1 = b
        if u0 >= u1 or v0 >= v1 or (v1 - v0) < config.min_px:
            continue
        if np.hypot(*(xy[k] - cam.centre[:2])) < cam.centre[2] - 0.5 * hs[k]:
            continue  # seen from above: the feet are in the middle of the silhouette
        look = _look(view, labels, b, ring[k], current, k)
        if look is None:
            continue
        probe = xy[k]
        for step in range(REACH_STEPS + 1):
            found = measure_feet(cam, labels, view.occ, probe, look[0], tuple(look[2]), down=look[3],
                                 max_depth_offset_m=height.depth_offset_m, border="silhouette")
            below = _cut_below(cam, labels, look)
            if below is None:
                break
            if step == REACH_STEPS:
                found = None  # still cut: the bottom found is the region's edge, not the feet
                break
            # The silhouette goes on below the region drawn at the track's place: the track is too
            # far along the line of sight to hold its own feet. Look again, drawn at the cut.
            probe = below
            _, ring1, box1, valid1, _ = view.forms(probe[None], np.array([hi]), np.array([1.25 * ws[k]]))
            nearer = _look(view, labels, box1[0], ring1[0], current, k) if valid1[0] else None
            if nearer is None:  # others cover the place below: keep the head's word, at the track's region
                found = None
                break
            look = nearer
        pixel = cam.project(found[0][None])[0] if found is not None else None
        gate = height_gate_m(p.height_samples, config.height_match_m, config.height_sigmas, gate_config.scatter_floor_m,
                             gate_config.min_samples)
        if found is not None and lo <= found[1] <= hi and abs(found[1] - hs[k]) <= gate \
                and not touches_other(look[1], look[2], pixel, k) \
                and not feet_doubted(view, current, k, pixel, found[0][:2], config):
            sigma = feet_sigma_m(cam, found[0][:2], look[3], config.sigma_m, config.pixel_sigma_px)
            stands = (standing_point(found[0][:2], cam.centre, hs[k]) if config.footprint
                      else beyond_toes(found[0][:2], cam.centre[:2], config.centre_offset_m))
            out[k] = (stands, sigma)
            continue
        if not config.head_fallback or (config.head_clear and not head_is_clear(cam, labels, look, k)):
            continue
        head = head_ray(cam, labels, view.occ, look[0], tuple(look[2]), look[3], border="silhouette")
        sigma_h = config.measured_height_sigma_m if len(p.height_samples) >= 3 else config.height_sigma_m
        place = under_head(head, hs[k], sigma_h, xy[k], cam, height.depth_offset_m)
        if place is not None:
            out[k] = place
    return out


#: Times the feet are looked for again, nearer along the line of sight, when the silhouette goes on below the region.
REACH_STEPS = 3


def _look(view: CameraView, labels: np.ndarray, box: np.ndarray, ring: np.ndarray, current, k: int):
    """Where person ``k``'s feet may be seen in ``box`` (the tallest plausible ellipse and its ring,
    ``ring``): (region clear of others (h, w) bool, owner (h, w) int32, box (4,), image down (2,)), or None
    when others cover too much of it or the box is empty."""
    cam = view.camera
    u0, u1, v0, v1 = (int(v) for v in box)
    if u0 >= u1 or v0 >= v1:
        return None
    region = ellipse_crop(ring, box, view.grid, cam.has_distortion)
    owner = owner_crop(box, current, view.grid, cam.has_distortion)
    free = (owner == k) | (owner == -1)
    if np.count_nonzero(region & ~free) > MAX_COVERED_FOR_HEIGHT * np.count_nonzero(region):
        return None
    down = view.down_direction(np.array([(u0 + u1) / 2, (v0 + v1) / 2]))
    return None if down is None else (region & free, owner, box, down)


def _cut_below(cam, labels: np.ndarray, look) -> np.ndarray | None:
    """The floor point (2,) under the silhouette's bottom when the region's bottom edge cuts it (its
    lowest foreground pixel within 2 px of the box's bottom, foreground below it in the image), else None."""
    region, _, box, down = look
    ends = silhouette_ends(cam, labels, region, tuple(box), down)
    if ends is None:
        return None
    bottom = ends[1]
    u, v = int(round(bottom[0] + 2 * down[0])), int(round(bottom[1] + 2 * down[1]))
    if bottom[1] < box[3] - 2 or not (0 <= u < labels.shape[1] and 0 <= v < labels.shape[0]) or labels[v, u] != 1:
        return None
    feet = cam.backproject(bottom[None], 0.0)[0]
    return feet[:2] if np.isfinite(feet).all() else None


#: Feet within this share of the search box's height (px) of another person's ellipse are not trusted.
FEET_CLEARANCE = 0.03


def touches_other(owner: np.ndarray, box: np.ndarray, pixel: np.ndarray, k: int) -> bool:
    """Whether image point ``pixel`` (u, v) lies within ``FEET_CLEARANCE`` × the box's height of a pixel
    that another person's ellipse covers (``owner`` of ``box``: index, −1 nobody, −2 several): the bottom of
    a silhouette there may be the other person's body, not these feet."""
    u0, u1, v0, v1 = (int(b) for b in box)
    r = max(2, int(round(FEET_CLEARANCE * (v1 - v0))))
    if not np.isfinite(pixel).all():
        return True
    u, v = int(round(pixel[0])) - u0, int(round(pixel[1])) - v0
    win = owner[max(0, v - r):max(0, v + r + 1), max(0, u - r):max(0, u + r + 1)]
    return bool(np.any((win != k) & (win != -1)))


def under_head(head, h: float, sigma_h: float, xy: np.ndarray, cam, depth_offset_m: float
                ) -> tuple[np.ndarray, float] | None:
    """The floor point under where the head ray ``head`` (origin, direction) is at height ``h``
    (m), and its σ along the line of sight for a height uncertain by ``sigma_h`` (m); None when
    the ray does not come down to ``h`` or the point is off the track (0.4 m across its line of
    sight, ``depth_offset_m`` plus 3 σ along it)."""
    if head is None:
        return None
    origin, d = head
    if d[2] >= -1e-6 or origin[2] <= h:
        return None
    s = (h - origin[2]) / d[2]
    place = origin[:2] + s * d[:2]
    ray = place - cam.centre[:2]
    distance = float(np.hypot(*ray))
    ray = ray / max(distance, 1e-9)
    off = place - xy
    sigma = sigma_h * distance / (origin[2] - h)
    if abs(float(off[0] * ray[1] - off[1] * ray[0])) > 0.4 or abs(float(off @ ray)) > depth_offset_m + 3 * sigma:
        return None
    return place, sigma


__all__ = ["anchor_to_feet", "feet_weight", "under_head"]
