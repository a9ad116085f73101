"""Depth along a camera's line of sight from every cue the frame gives, weighed by how sure each is.

One camera places a person well across its line of sight and badly along it: the distance rests
on how big the person looks, so a wrong height, legs the colour of the floor or somebody passing
in front move the matched ellipse metres along the ray. After the matching rounds, each person
that one camera alone shows is placed along that camera's line of sight by the inverse-variance
mean of the cues (a Kalman update along the ray; across it the match stands):

===================  ==============================================  ==================================
cue                  used when                                       σ along the ray, m
===================  ==============================================  ==================================
the matched ellipse  always                                          0.3 where the feet are trusted,
                                                                     else ``weak_sigma_m`` (0.6: legs
                                                                     not foreground, others cover it)
the prediction       a tracked person (constant velocity: the        ``prior_speed_mps`` × dt × √(1 + n),
                     velocity prior)                                 n the frames since the feet were
                                                                     last trusted (at most 25)
the feet             clear of others, the head's ray above them at   0.1
                     the person's height, and the legs below the
                     knees foreground, not "unsure" (:mod:`.legs`)
the top of the head  clear of others, where the feet are not         σ_h · d / (H − h)
                     trusted: where its ray is at the person's
                     height
===================  ==============================================  ==================================

σ_h is the person's height uncertainty: ``feet.height_sigma_m`` until three measurements are in,
then their median's own standard error, at least ``feet.measured_height_sigma_m`` (3 cm: the
measurements share their biases, and one wrong height must not outweigh the rest). Where nothing
but the ellipse and the prediction are left (a person behind another), the prediction carries
them: no 0.6 m jump in 0.1 s because a covered silhouette fits a farther ellipse. Its σ grows
while the feet are unseen, so that a wrong velocity does not carry a person away (a fixed σ let
one coast 1.8 m towards the camera in a crossing). People no camera shows are held by the
prediction along the first camera's line of sight.

With ``depth.remeasure_after_encounter``, a person whose view was covered by others has their
height samples dropped once they are clear again, so the height is measured afresh instead of
carried through a crossing (where a track may have taken the other person's place).

>>> round(fuse_along([(0.0, 0.3), (0.6, 0.1)]), 3)      # the feet (σ 0.1) outweigh the ellipse
0.54
"""

from __future__ import annotations

import weakref
from typing import Mapping, Sequence

import numpy as np

from worldtrack.trackers.base import Person
from worldtrack.trackers.ellipsoid.cameras import CameraView
from worldtrack.trackers.ellipsoid.depth_hold import hold_covered_by_head
from worldtrack.trackers.ellipsoid.depth_step import bound_steps
from worldtrack.trackers.ellipsoid.config import DepthConfig, FeetConfig, HeightConfig
from worldtrack.trackers.ellipsoid.encounters import covered_in_some_view
from worldtrack.trackers.ellipsoid.feet import under_head
from worldtrack.trackers.ellipsoid.feet_pixel import feet_sigma_m
from worldtrack.trackers.ellipsoid.forms import ellipse_crop, owner_crop
from worldtrack.trackers.ellipsoid.height import MAX_COVERED_FOR_HEIGHT, head_ray, measure_feet, silhouette_ends
from worldtrack.trackers.ellipsoid.height_sigma import height_sigma
from worldtrack.trackers.ellipsoid.legs import legs_foreground_share
from worldtrack.trackers.ellipsoid.support import MIN_OWN_PIXELS

#: The prediction's σ stops growing after this many frames without trusted feet.
MAX_WEAK_FRAMES = 25


def fuse_along(cues: Sequence[tuple[float, float]]) -> float:
    """Inverse-variance mean of ``(offset along the ray m, σ m)`` cues (0 with none)."""
    w = np.array([1.0 / s ** 2 for _, s in cues])
    a = np.array([o for o, _ in cues])
    return float(w @ a / w.sum()) if len(cues) else 0.0


class DepthFusion:
    """The per-frame depth update (:meth:`apply`) and what it remembers between frames: each
    person's predicted place and whether others covered them."""

    def __init__(self, config: DepthConfig, feet: FeetConfig, height: HeightConfig) -> None:
        self.config, self.feet, self.height = config, feet, height
        self._predicted: "weakref.WeakKeyDictionary[Person, np.ndarray]" = weakref.WeakKeyDictionary()
        self._met: "weakref.WeakKeyDictionary[Person, bool]" = weakref.WeakKeyDictionary()
        self._weak: "weakref.WeakKeyDictionary[Person, int]" = weakref.WeakKeyDictionary()
        self._velocity: "weakref.WeakKeyDictionary[Person, np.ndarray]" = weakref.WeakKeyDictionary()

    def remember_prediction(self, people: Sequence[Person]) -> None:
        """Keep the predicted place of each tracked person (call after the prediction, before matching)."""
        if not (self.config.fuse or self.config.max_along_speed_mps > 0):
            return
        for p in people:
            if p.mode == "tracking":
                self._predicted[p] = np.array([p.x, p.y])
                self._velocity[p] = np.array([p.vx, p.vy])

    def apply(self, people: Sequence[Person], views: Mapping[str, CameraView], labels: Mapping[str, np.ndarray],
              walkable, dt: float) -> int:
        """Place each of ``people`` that one camera alone shows along that camera's line of sight
        (see the module docstring), and those no camera shows by their prediction along the first
        camera's; with ``max_along_speed_mps``, then keeps each within walking reach of their
        last place along the line of sight (:mod:`.depth_step`); returns how many were moved."""
        moves = self._fuse(people, views, labels, walkable, dt)
        if self.config.head_when_covered:
            moves += hold_covered_by_head(people, views, labels, walkable, self.feet, self.height)
        if self.config.max_along_speed_mps > 0 and people:
            last = {p: xy - self._velocity[p] * dt for p, xy in self._predicted.items() if p in self._velocity}
            moves += bound_steps(people, last, self._lone_centre(people, views),
                                 self.config.max_along_speed_mps, dt, walkable)
        self._predicted.clear()
        self._velocity.clear()
        return moves

    @staticmethod
    def _lone_centre(people: Sequence[Person], views: Mapping[str, CameraView]):
        """index -> the centre (3,) of the one camera of ``views`` that shows ``people[index]``, or None."""
        def centre(k: int):
            p = people[k]
            seen = [v for v in views.values() if v.visible_pixels(np.array([p.x, p.y]), p.height, p.width) >= MIN_OWN_PIXELS]
            return seen[0].camera.centre if len(seen) == 1 else None
        return centre

    def _fuse(self, people: Sequence[Person], views: Mapping[str, CameraView], labels: Mapping[str, np.ndarray],
              walkable, dt: float) -> int:
        """The fusion of :meth:`apply` (``fuse``), or without it the encounters only; returns the moves."""
        if not self.config.fuse or not people:
            if self.config.remeasure_after_encounter and people:   # the encounters, without the fusion
                for p, covered in zip(people, covered_in_some_view(people, views, self.height.range_m[1])):
                    self.note_encounter(p, covered)
            return 0
        xy = np.array([[p.x, p.y] for p in people], dtype=float)
        shown = {cid: [v.visible_pixels(xy[k], p.height, p.width) >= MIN_OWN_PIXELS for k, p in enumerate(people)]
                 for cid, v in views.items()}
        # Those no camera shows (behind others) are held along the first camera's line of sight by
        # the prediction: a covered silhouette is no evidence of where they went.
        hidden = [k for k in range(len(people)) if not any(s[k] for s in shown.values())]
        moves = 0
        for n, (cid, image_labels) in enumerate(labels.items()):
            view = views[cid]
            alone = [k for k in range(len(people)) if shown[cid][k] and sum(s[k] for s in shown.values()) == 1]
            cues = self._cues(view, image_labels, people, xy, alone + (hidden if n == 0 else []), dt)
            for k, (ray, found) in cues.items():
                new = xy[k] + fuse_along(found) * ray
                if walkable(new[None])[0]:
                    people[k].x, people[k].y = float(new[0]), float(new[1])
                    moves += 1
        return moves

    def _cues(self, view: CameraView, labels: np.ndarray, people: Sequence[Person], xy: np.ndarray,
              alone: Sequence[int], dt: float) -> dict[int, tuple[np.ndarray, list[tuple[float, float]]]]:
        """{index: (the line of sight's floor direction (2,), [(offset along it m, σ m), …])}."""
        cfg, hi = self.config, self.height.range_m[1]
        cam = view.camera
        hs = np.array([p.height for p in people], dtype=float)
        ws = np.array([p.width for p in people], dtype=float)
        _, ring, box, valid, _ = view.forms(xy, np.full(len(xy), hi), 1.25 * ws)
        current = view.forms(xy, hs, ws)
        out = {}
        for k in alone:
            p = people[k]
            if not valid[k] or p.mode not in ("tracking", "capture"):
                continue
            ray = xy[k] - cam.centre[:2]
            distance = float(np.hypot(*ray))
            if distance < cam.centre[2] - 0.5 * hs[k]:
                continue  # seen from above: depth is not the weak direction
            ray = ray / max(distance, 1e-9)
            found = []
            weak = self._weak.get(p, 0)
            if p in self._predicted:   # the prediction's σ grows with the frames since the feet were last seen
                sigma = max(cfg.prior_speed_mps * dt, 0.02) * np.sqrt(1.0 + weak)
                found.append((float((self._predicted[p] - xy[k]) @ ray), sigma))
            b = box[k]
            u0, u1, v0, v1 = b
            clear = False
            if u0 < u1 and v0 < v1 and (v1 - v0) >= self.feet.min_px:
                region = ellipse_crop(ring[k], b, view.grid, cam.has_distortion)
                owner = owner_crop(b, current, view.grid, cam.has_distortion)
                free = (owner == k) | (owner == -1)
                covered = np.count_nonzero(region & ~free) > MAX_COVERED_FOR_HEIGHT * np.count_nonzero(region)
                self.note_encounter(p, covered)
                if not covered:
                    clear = self._silhouette_cues(view, labels, region & free, tuple(b), p, xy[k], ray, found)
            found.append((0.0, self.feet.ellipse_sigma_m if clear else cfg.weak_sigma_m))
            self._weak[p] = 0 if clear else min(weak + 1, MAX_WEAK_FRAMES)
            out[k] = (ray, found)
        return out

    def _silhouette_cues(self, view: CameraView, labels: np.ndarray, region: np.ndarray, box: tuple,
                         p: Person, xy: np.ndarray, ray: np.ndarray, found: list) -> bool:
        """Append the feet's and the head's cues of a person clear of others to ``found``; True when
        the feet were trusted (the silhouette is whole, so the ellipse's own place is too)."""
        cam, lo, hi = view.camera, *self.height.range_m
        u0, u1, v0, v1 = box
        down = view.down_direction(np.array([(u0 + u1) / 2, (v0 + v1) / 2]))
        if down is None:
            return False
        feet = measure_feet(cam, labels, view.occ, xy, region, box, down=down,
                            max_depth_offset_m=self.height.depth_offset_m)
        if (feet is not None and lo <= feet[1] <= hi and abs(feet[1] - p.height) <= self.feet.height_match_m
                and self._legs_shown(cam, labels, region, box, down)):
            sigma = feet_sigma_m(cam, feet[0][:2], down, self.feet.sigma_m, self.feet.pixel_sigma_px)
            found.append((float((feet[0][:2] - xy) @ ray), sigma))
            return True
        sigma_h = height_sigma(p, self.feet.height_sigma_m, self.feet.measured_height_sigma_m)
        place = under_head(head_ray(cam, labels, view.occ, region, box, down), p.height, sigma_h, xy, cam,
                           self.height.depth_offset_m)
        if place is not None:
            found.append((float((place[0] - xy) @ ray), place[1]))
        return False

    def _legs_shown(self, cam, labels: np.ndarray, region: np.ndarray, box: tuple, down: np.ndarray) -> bool:
        """The silhouette below the knees is foreground, not "unsure" (shadow-like)."""
        ends = silhouette_ends(cam, labels, region, box, down)
        return ends is not None and legs_foreground_share(labels, region, box, *ends) >= self.config.legs_min_share

    def note_encounter(self, p: Person, covered: bool) -> None:
        """With ``remeasure_after_encounter``: once a person covered by others is clear again, drop
        their height samples so the height is measured afresh."""
        if not self.config.remeasure_after_encounter:
            return
        if covered:
            self._met[p] = True
        elif self._met.pop(p, False):
            p.height_samples.clear()
            p.height_tries = 0


__all__ = ["DepthFusion", "MAX_WEAK_FRAMES", "fuse_along"]
