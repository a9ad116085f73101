"""Track management: a short *lost* state, so a person who vanishes for a moment keeps their id.

A confirmed track ends when its evidence fails for ``end.lost_after_s`` — a person walking behind
a pole, a sign or another person, or a group whose silhouettes merge. When they come out, births
propose them again and they are confirmed under a new id: one identity switch per occlusion, and
IDF1 splits their trajectory in two. Colour alone (:mod:`.identity`) rarely gives the id back:
the colour models of people in groups never mature, and a model of a few views is too noisy for a
strict threshold.

This module keeps every confirmed track that ended, after living at least
``lost.min_age_s``, for ``lost.keep_s`` seconds: where it was last, how it moved, when.
A newly confirmed person takes the id back when exactly one lost person could have walked to where
they stand — within ``lost.near_m`` + ``lost.speed_mps`` × (time since) of the
lost person's last place moved on at their last velocity — and no other lost person comes within
``lost.margin_m`` of that (an ambiguous return gets a new id, as before). The motion
gate is in world metres, so it reads the same in every camera and room. When both people have
colour models in a common camera (:mod:`.identity`), a colour distance above
``lost.colour_veto`` refuses the return: someone else came out.

>>> from worldtrack.trackers.ellipsoid.config import LostConfig
>>> lost = LostTracks(LostConfig())
>>> lost.file(7, xy=(0.0, 0.0), v=(1.0, 0.0), t=1.0)
>>> lost.claim((1.4, 0.1), t=2.0, taken=lambda i: False)   # 1 s later, 1 m on: the same person
7
>>> lost.claim((1.4, 0.1), t=2.0, taken=lambda i: False) is None   # given back once
True
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Iterable, Sequence

import numpy as np

from worldtrack.trackers.base import Person
from worldtrack.trackers.ellipsoid.config import LostConfig


@dataclass(eq=False)
class Vanished:
    """A confirmed person whose track ended: id, last place (2,) m, velocity (2,) m/s, time s.
    Entries are told apart by identity (one id can be filed twice: given back by colour, lost
    again; ``list.remove`` must not compare numpy places)."""

    id: int
    xy: np.ndarray
    v: np.ndarray
    t: float
    #: Lost at the image's edge (:mod:`.exits`): not given back by place alone.
    left_view: bool = False


@dataclass
class LostTracks:
    """The people one tracker lost in the last ``lost.keep_s`` seconds.

    Parameters
    ----------
    config : LostConfig
    """

    config: LostConfig
    lost: list[Vanished] = field(default_factory=list)
    #: Confirmed people on the map at the last :meth:`watch`: id → (person, place, velocity, time).
    _alive: dict[int, tuple[Person, np.ndarray, np.ndarray, float]] = field(default_factory=dict)
    given_back: int = 0

    def file(self, person_id: int, xy: Sequence[float], v: Sequence[float], t: float, left_view: bool = False) -> None:
        """Keep person ``person_id``, last at ``xy`` m moving at ``v`` m/s at time ``t`` s, as lost
        (``left_view``: at the image's edge, their id is not given back by place)."""
        self.lost.append(Vanished(int(person_id), np.asarray(xy, float), np.asarray(v, float), float(t), left_view))

    def watch(self, people: Iterable[Person], t: float, alive: Callable[[Person], bool],
              left_view: Callable[[Person, np.ndarray], bool] | None = None) -> None:
        """After a step: file the confirmed people seen at the last call who are no longer on the
        map (``alive(person)`` is False), remember the confirmed people now on it, forget the lost
        older than ``lost.keep_s``. ``left_view(person, xy)``: whether they were lost at the
        image's edge (:mod:`.exits`)."""
        cfg = self.config
        for pid, (p, xy, v, seen) in list(self._alive.items()):
            if not alive(p):
                del self._alive[pid]
                if p.confirmed and seen - p.born >= cfg.min_age_s:
                    self.file(pid, xy, v, seen, left_view is not None and left_view(p, xy))
        for p in people:
            # The place where the evidence last held them, not where a failing track slid to.
            if p.confirmed and p.id > 0 and (p.count("low") == 0 or _new(self._alive, p)):
                self._alive[p.id] = (p, np.array([p.x, p.y]), np.array([p.vx, p.vy]), t)
        self.lost = [g for g in self.lost if t - g.t <= cfg.keep_s]

    def claim(self, xy: Sequence[float], t: float, taken: Callable[[int], bool],
              colour_distance: Callable[[int], float | None] | None = None) -> int | None:
        """The id of the one lost person who could be at floor place ``xy`` (m) at time ``t`` (s),
        or None; a given-back id leaves the lost list. ``taken(id)``: the id is on the map again;
        ``colour_distance(id)``: the colour distance to that lost person's model, None if unknown."""
        cfg = self.config
        here = np.asarray(xy, float)
        fits = []
        for g in self.lost:
            if taken(g.id):
                continue
            since = max(t - g.t, 0.0)
            ahead = g.xy + g.v * min(since, cfg.keep_s)
            miss = min(float(np.linalg.norm(here - ahead)), float(np.linalg.norm(here - g.xy)))
            fits.append((miss - (cfg.near_m + cfg.speed_mps * since), miss, g))
        inside = sorted((f for f in fits if f[0] <= 0), key=lambda f: f[1])
        if not inside:
            return None
        best = inside[0]
        if any(f is not best and f[1] - best[1] < cfg.margin_m for f in fits):
            return None
        g = best[2]
        if g.left_view:
            return None   # the nearest lost person walked out of view: a newcomer is as likely somebody else
        if colour_distance is not None:
            d = colour_distance(g.id)
            if d is not None and d > cfg.colour_veto:
                return None
        self.lost.remove(g)
        self.given_back += 1
        return g.id


def _new(alive: dict, p: Person) -> bool:
    """Whether ``p`` is not remembered yet (just confirmed: remembered at once)."""
    return p.id not in alive or alive[p.id][0] is not p


__all__ = ["LostTracks", "Vanished"]
