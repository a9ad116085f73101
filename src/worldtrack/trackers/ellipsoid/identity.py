"""Identity by colour (paper 000's future work): who is who when two people meet or one comes back.

The ellipsoid tracker places people by their silhouettes alone, so two people on one line of
sight are interchangeable to it: when they part, each track follows whichever silhouette is
nearer, and a person lost behind another (or a pole) comes back as a new track. This module keeps
a colour model per person and camera: hue-saturation-value histograms of the upper body (the
shirt) and of the lower body (the trousers), from the foreground pixels the person's ellipse
owns, updated only while the person is **clearly isolated** (nobody else's ellipse with its ring
overlaps theirs), so another person's colours never enter it. It then

* **undoes swaps**: two people who were close (their ellipses met in some camera in the last
  ``identity.swap_window_s``) and are now both isolated in one camera exchange their places when
  each one's pixels fit the other's model better than their own by ``identity.swap_margin``;
* **re-identifies** a person who comes back: a confirmed track that ended is kept for
  ``identity.reid_s`` with its model, place and velocity; a newly confirmed person whose model
  is within ``identity.reid_distance`` of it (and no other) and who stands where the lost person
  could have walked to takes the lost person's id.

Distances are Bhattacharyya distances (0 same, 1 disjoint) averaged over the two body parts.

>>> a = np.zeros(HIST_BINS, np.float32); a[0, 0, 0] = 1
>>> b = np.zeros(HIST_BINS, np.float32); b[1, 0, 0] = 1
>>> round(hist_distance(a, a), 3), round(hist_distance(a, b), 3)
(0.0, 1.0)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Mapping, Sequence

import cv2
import numpy as np

from worldtrack.trackers.base import Person
from worldtrack.trackers.ellipsoid.cameras import CameraView
from worldtrack.trackers.ellipsoid.config import IdentityConfig
from worldtrack.trackers.ellipsoid.forms import owner_crop

#: Histogram bins: hue, saturation, value (value keeps dark and light grey clothes apart).
HIST_BINS = (8, 4, 4)
#: The body parts, as shares of the image axis from the top of the head (0) to the feet (1):
#: the upper body without the head, the lower body without the feet (and their shadow).
PARTS = ((0.18, 0.5), (0.5, 0.9))


def hist_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Bhattacharyya distance of two normalised histograms (OpenCV's ``HISTCMP_BHATTACHARYYA``)."""
    return float(cv2.compareHist(a, b, cv2.HISTCMP_BHATTACHARYYA))


@dataclass
class Colours:
    """One person's colours in one camera: a histogram (``HIST_BINS``, sums to 1) per body part;
    ``alone``: seen clearly isolated (else from the pixels nobody else's ellipse covers)."""

    parts: list[np.ndarray]
    updates: int = 1
    alone: bool = True

    def distance(self, other: "Colours") -> float:
        """Mean Bhattacharyya distance over the body parts."""
        return float(np.mean([hist_distance(a, b) for a, b in zip(self.parts, other.parts)]))

    def blend(self, seen: "Colours", rate: float) -> None:
        """Move the model towards ``seen`` by ``rate`` (the first updates count more)."""
        w = max(rate, 1.0 / (self.updates + 1))
        self.parts = [(1 - w) * a + w * b for a, b in zip(self.parts, seen.parts)]
        self.updates += 1


@dataclass
class Lost:
    """A confirmed person whose track ended: kept for re-identification."""

    id: int
    colours: dict[str, Colours]
    xy: np.ndarray
    t: float


@dataclass
class Identities:
    """The colour models of the people of one tracker, and the people it lost.

    Parameters
    ----------
    config : IdentityConfig
    """

    config: IdentityConfig
    models: dict[Person, dict[str, Colours]] = field(default_factory=dict)
    lost: list[Lost] = field(default_factory=list)
    met: dict[tuple[int, int], float] = field(default_factory=dict)
    doubts: dict[tuple[int, int], int] = field(default_factory=dict)
    swapped: dict[tuple[int, int], float] = field(default_factory=dict)
    swaps: int = 0
    reidentified: int = 0

    def update(self, people: Sequence[Person], views: Mapping[str, CameraView], images: Mapping[str, np.ndarray],
               labels: Mapping[str, np.ndarray], t: float, alive) -> None:
        """One frame: see everyone's colours, undo swaps, update the models, file the people who
        left the map (``alive(person)`` is False) as lost.

        Parameters
        ----------
        people : the people on the map this tracker moves (placed for this frame)
        views, images, labels : the tracker's cameras, their BGR images and foreground labels, by id
        t : time stamp, s
        alive : callable — Person → whether they are still on the map
        """
        cfg = self.config
        for p in [q for q in self.models if not alive(q)]:
            if p.id > 0 and p.confirmed and t - p.born >= cfg.min_age_s:
                self.lost.append(Lost(p.id, self.models[p], np.array([p.x, p.y]), p.last_seen))
            del self.models[p]
        self.lost = [g for g in self.lost if t - g.t <= cfg.reid_s]
        seen: dict[str, dict[int, Colours]] = {}
        for cid, image in images.items():
            if cid in labels:
                seen[cid] = see_colours(views[cid], image, labels[cid], people, cfg.min_pixels,
                                        lambda i, j: self.met.__setitem__((min(i, j), max(i, j)), t))
        self._undo_swaps(people, seen, t)
        for cid, found in seen.items():
            for k, colours in found.items():
                if not (colours.alone or (people[k].mode == "capture" and people[k].id < 0)):
                    continue  # a model learns from clear views only (a candidate: from what it owns)
                model = self.models.setdefault(people[k], {})
                if cid in model:
                    model[cid].blend(colours, cfg.update_rate)
                else:
                    model[cid] = colours
        self.met = {k: v for k, v in self.met.items() if t - v <= cfg.swap_window_s}

    def _undo_swaps(self, people: Sequence[Person], seen: Mapping[str, Mapping[int, Colours]], t: float) -> None:
        """Exchange the places of two people who met and now each look like the other."""
        cfg = self.config
        index = {p.id: k for k, p in enumerate(people)}
        for (a, b) in list(self.met):
            i, j = index.get(a), index.get(b)
            if i is None or j is None or not (people[i].confirmed and people[j].confirmed):
                continue
            mi, mj = self.models.get(people[i], {}), self.models.get(people[j], {})
            same = swapped = 0.0
            n = 0
            for cid, found in seen.items():
                if i in found and j in found and cid in mi and cid in mj and \
                        min(mi[cid].updates, mj[cid].updates) >= cfg.min_updates:
                    same += mi[cid].distance(found[i]) + mj[cid].distance(found[j])
                    swapped += mi[cid].distance(found[j]) + mj[cid].distance(found[i])
                    n += 1
            if not (n and swapped + cfg.swap_margin * n < same):
                self.doubts.pop((a, b), None)
                continue
            # Two frames in a row, and not back again soon: one noisy view swaps nobody.
            self.doubts[(a, b)] = self.doubts.get((a, b), 0) + 1
            if self.doubts[(a, b)] < 2 or t - self.swapped.get((a, b), -np.inf) <= cfg.swap_window_s:
                continue
            swap_places(people[i], people[j])
            for found in seen.values():
                if i in found and j in found:
                    found[i], found[j] = found[j], found[i]
            self.swaps += 1
            self.swapped[(a, b)] = t
            del self.met[(a, b)]
            del self.doubts[(a, b)]

    def reidentify(self, p: Person, t: float, taken) -> int | None:
        """The id of the lost person a newly confirmed ``p`` is, or None (``taken(id)``: the id is
        on the map already)."""
        cfg = self.config
        mine = self.models.get(p)
        if not mine:
            return None
        scored = []
        for g in self.lost:
            common = [cid for cid in mine if cid in g.colours]
            if not common or taken(g.id):
                continue
            reach = cfg.reid_near_m + cfg.walk_speed_mps * max(t - g.t, 0.0)
            if math.hypot(p.x - g.xy[0], p.y - g.xy[1]) > reach:
                continue
            scored.append((float(np.mean([mine[c].distance(g.colours[c]) for c in common])), g))
        if not scored:
            return None
        scored.sort(key=lambda s: s[0])
        best, g = scored[0]
        if best > cfg.reid_distance or (len(scored) > 1 and scored[1][0] - best < cfg.reid_margin):
            return None
        self.lost.remove(g)
        self.reidentified += 1
        return g.id


def swap_places(a: Person, b: Person) -> None:
    """Exchange where two people are and how they move (their identities — id, height, colours —
    stay)."""
    for name in ("x", "y", "vx", "vy", "prev_x", "prev_y"):
        va, vb = getattr(a, name), getattr(b, name)
        setattr(a, name, vb)
        setattr(b, name, va)


def see_colours(view: CameraView, image: np.ndarray, labels: np.ndarray, people: Sequence[Person],
                min_pixels: int, met) -> dict[int, Colours]:
    """The colours of each clearly isolated person in one camera, by index into ``people``.

    A person's pixels are the foreground pixels (label 1) of their own ellipse that no other
    ellipse covers, split into :data:`PARTS` along the image of their vertical axis. They are
    clearly isolated (``Colours.alone``) when no other person's ellipse grown by the ring overlaps
    theirs (grown too); ``met(i, j)`` is called for every pair whose grown ellipses overlap. A part
    with fewer than ``min_pixels`` pixels leaves the person out.
    """
    if not people:
        return {}
    cam = view.camera
    xy = np.array([[p.x, p.y] for p in people], float)
    hs = np.array([p.height for p in people], float)
    ws = np.array([p.width for p in people], float)
    forms = view.forms(xy, hs, ws)
    grown = forms._replace(inner=forms.ring)
    out: dict[int, Colours] = {}
    for k in range(len(people)):
        if not forms.valid[k]:
            continue
        u0, u1, v0, v1 = (int(c) for c in forms.box[k])
        if u0 >= u1 or v0 >= v1:
            continue
        window = np.array([u0, u1, v0, v1], np.int64)
        others = _overlapping(k, window, forms, grown)
        alone = True
        if others and (owner_crop(window, grown, view.grid, cam.has_distortion) == -2).any():
            alone = False
            for j in others:
                met(people[k].id, people[j].id)
        own = owner_crop(window, forms, view.grid, cam.has_distortion) == k
        mask = own & (labels[v0:v1, u0:u1] == 1)
        colours = _part_histograms(cam, image[v0:v1, u0:u1], mask, (u0, v0), xy[k], hs[k], min_pixels)
        if colours is not None:
            colours.alone = alone
            out[k] = colours
    return out


def _overlapping(k: int, window: np.ndarray, forms, grown) -> list[int]:
    """Indices of the people whose grown ellipse's box meets person ``k``'s box (a cheap first test)."""
    u0, u1, v0, v1 = window
    box = grown.box
    hit = forms.valid & (box[:, 0] < u1) & (box[:, 1] > u0) & (box[:, 2] < v1) & (box[:, 3] > v0)
    hit[k] = False
    return [int(j) for j in np.flatnonzero(hit)]


def _part_histograms(cam, crop: np.ndarray, mask: np.ndarray, origin: tuple[int, int], xy: np.ndarray,
                     height: float, min_pixels: int) -> Colours | None:
    """HSV histograms of the masked pixels of ``crop`` in each of :data:`PARTS`, or None."""
    ends = cam.project(np.array([[xy[0], xy[1], height], [xy[0], xy[1], 0.0]]))
    if not np.isfinite(ends).all():
        return None
    head, feet = ends[0] - np.asarray(origin, float), ends[1] - np.asarray(origin, float)
    axis = feet - head
    length2 = float(axis @ axis)
    if length2 < 1.0:
        return None
    u, v = np.arange(crop.shape[1])[None, :], np.arange(crop.shape[0])[:, None]   # broadcast: no (h, w) grids
    share = ((u - head[0]) * axis[0] + (v - head[1]) * axis[1]) / length2
    hsv = cv2.cvtColor(crop, cv2.COLOR_BGR2HSV)
    parts = []
    for lo, hi in PARTS:
        part = (mask & (share >= lo) & (share < hi)).astype(np.uint8)
        if cv2.countNonZero(part) < min_pixels:
            return None
        h = cv2.calcHist([hsv], [0, 1, 2], part, list(HIST_BINS), [0, 180, 0, 256, 0, 256])
        parts.append(h / max(float(h.sum()), 1.0))
    return Colours(parts)


__all__ = ["Colours", "HIST_BINS", "Identities", "Lost", "PARTS", "hist_distance", "see_colours", "swap_places"]
