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

import numpy as np

from worldtrack.trackers.base import Person
from worldtrack.trackers.ellipsoid.cameras import CameraView
from worldtrack.trackers.ellipsoid.config import IdentityConfig
from worldtrack.trackers.ellipsoid.colours import (HIST_BINS, PARTS, Colours, Sight, colours_of, hist_distance,
                                                    look)


@dataclass(eq=False)
class Lost:
    """A confirmed person whose track ended: kept for re-identification. Entries are told apart by
    identity (one id can be lost twice, and ``list.remove`` must not compare numpy places)."""

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
        if not people:
            self.met = {k: v for k, v in self.met.items() if t - v <= cfg.swap_window_s}
            return
        sights = {cid: look(views[cid], people, cfg.isolation) for cid in images if cid in labels}
        for sight in sights.values():
            self.met.update(dict.fromkeys(sight.met, t))
        learners = np.array([p.mode == "capture" and p.id < 0 for p in people])  # a candidate learns from what it owns
        seen = _Seen(views, images, labels, sights, cfg.min_pixels)
        pairs = self._pairs(people)
        for cid, sight in sights.items():
            checked = [x for i, j, _, cameras in pairs if cid in cameras for x in (i, j)]
            seen.ask(cid, np.flatnonzero(sight.alone | learners).tolist() + checked)
        self._undo_swaps(people, seen, pairs, t)
        for cid, found in seen.found.items():
            for k, colours in found.items():
                if not (colours.alone or learners[k]):
                    continue  # a model learns from clear views only (a candidate: from what it owns)
                model = self.models.setdefault(people[k], {})
                if cid in model:
                    model[cid].blend(colours, cfg.update_rate)
                else:
                    model[cid] = colours
        self.met = {k: v for k, v in self.met.items() if t - v <= cfg.swap_window_s}

    def _pairs(self, people: Sequence[Person]) -> list[tuple[int, int, tuple[int, int], set[str]]]:
        """The pairs that met whose colours can be compared, in the order they met: (index i,
        index j, their ids, the cameras where both are confirmed and have models that have learnt
        enough). A pair of people on the map with no such camera clears its doubt."""
        index = {p.id: k for k, p in enumerate(people)}
        mature: dict[int, set[str]] = {}   # by person id
        for p in people:
            if p.confirmed and p in self.models:
                cameras = {cid for cid, c in self.models[p].items() if c.updates >= self.config.min_updates}
                if cameras:
                    mature[p.id] = cameras
        out = []
        if len(mature) > 1:
            for (a, b) in self.met:
                if a in mature and b in mature and mature[a] & mature[b]:
                    out.append((index[a], index[b], (a, b), mature[a] & mature[b]))
        for (a, b) in [q for q in self.doubts if q in self.met]:
            i, j = index.get(a), index.get(b)
            if i is not None and j is not None and people[i].confirmed and people[j].confirmed and \
                    not (mature.get(a, set()) & mature.get(b, set())):
                del self.doubts[(a, b)]
        return out

    def _undo_swaps(self, people: Sequence[Person], seen: "_Seen", pairs, t: float) -> None:
        """Exchange the places of two people who met and now each look like the other."""
        cfg = self.config
        for i, j, pair, cameras in pairs:
            mi, mj = self.models[people[i]], self.models[people[j]]
            same = swapped = 0.0
            n = 0
            for cid, found in seen.found.items():
                if cid in cameras and i in found and j in found:
                    same += mi[cid].distance(found[i]) + mj[cid].distance(found[j])
                    swapped += mi[cid].distance(found[j]) + mj[cid].distance(found[i])
                    n += 1
            if not (n and swapped + cfg.swap_margin * n < same):
                self.doubts.pop(pair, None)
                continue
            # Two frames in a row, and not back again soon: one noisy view swaps nobody.
            self.doubts[pair] = self.doubts.get(pair, 0) + 1
            if self.doubts[pair] < 2 or t - self.swapped.get(pair, -np.inf) <= cfg.swap_window_s:
                continue
            swap_places(people[i], people[j])
            for cid, found in seen.found.items():
                seen.ask(cid, [i, j])          # their colours go with them in every camera
                if i in found and j in found:
                    found[i], found[j] = found[j], found[i]
            self.swaps += 1
            self.swapped[pair] = t
            del self.met[pair]
            del self.doubts[pair]

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

    def colour_distance(self, p: Person, lost_id: int) -> float | None:
        """Colour distance (mean over the cameras both have models in) between ``p`` and the lost
        person ``lost_id``; None when either has no model there."""
        mine = self.models.get(p)
        for g in self.lost:
            if g.id == lost_id and mine:
                common = [cid for cid in mine if cid in g.colours]
                if common:
                    return float(np.mean([mine[c].distance(g.colours[c]) for c in common]))
        return None


def swap_places(a: Person, b: Person) -> None:
    """Exchange where two people are and how they move (their identities — id, height, colours —
    stay)."""
    for name in ("x", "y", "vx", "vy", "prev_x", "prev_y"):
        va, vb = getattr(a, name), getattr(b, name)
        setattr(a, name, vb)
        setattr(b, name, va)


class _Seen:
    """People's colours in each camera this frame, measured when first asked for (``found``: by
    camera, index → :class:`Colours`, in index order)."""

    def __init__(self, views, images, labels, sights: Mapping[str, Sight], min_pixels: int):
        self.views, self.images, self.labels, self.sights = views, images, labels, sights
        self.min_pixels = min_pixels
        self.found: dict[str, dict[int, Colours]] = {cid: {} for cid in sights}
        self.asked: dict[str, set[int]] = {cid: set() for cid in sights}

    def ask(self, cid: str, indices: Sequence[int]) -> None:
        """Measure the colours in ``cid`` of those of ``indices`` not measured yet."""
        new = sorted(set(indices) - self.asked[cid])
        if not new:
            return
        self.asked[cid].update(new)
        found = self.found[cid]
        found.update(colours_of(self.views[cid], self.images[cid], self.labels[cid], self.sights[cid],
                                np.array(new, np.int64), self.min_pixels))
        ordered = sorted(found.items())
        found.clear()
        found.update(ordered)


def see_colours(view: CameraView, image: np.ndarray, labels: np.ndarray, people: Sequence[Person],
                min_pixels: int, met) -> dict[int, Colours]:
    """The colours of everyone ``people`` holds in one camera, by index (:func:`.colours.look`
    then :func:`.colours.colours_of` for all of them); ``met(i, j)`` is called for every pair of
    ids whose grown ellipses crowd each other. ``Colours.alone``: clearly isolated."""
    if not people:
        return {}
    sight = look(view, people)
    for i, j in sight.met:
        met(i, j)
    return colours_of(view, image, labels, sight, np.arange(len(people)), min_pixels)


__all__ = ["Colours", "HIST_BINS", "Identities", "Lost", "PARTS", "hist_distance", "see_colours", "swap_places"]
