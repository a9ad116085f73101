"""A region of interest on the floor: a person gets a new id each time they come back into it.

A user who counts visits to a shop's floor, or scores tracks against ground truth cropped to a
tracking area, wants one id per visit: the cropped PETS 2009 S2.L1 ground truth (Milan et al.'s
tracking area) renumbers four people who walk out of the area and back while still in the camera's
view, so a tracker that follows them through (as it should, and does) is charged one identity split
per return. With ``region.area`` set, a confirmed person who has been outside the polygon for at least
``region.outside_s`` and steps back in is reported under a fresh id. Tracking is unchanged: the
map keeps its own ids (they also pace per-person schedules, so none is taken from it), and the
returned tracks carry visit ids instead, numbered 1, 2, ... in the order the visits begin; a person
outside keeps the id of their last visit. So with a region the reported ids are not the map's
(``position_map.get(track.id)`` does not find the person), and trackers sharing one map each number
the visits they report on their own. Off by default (``region.area`` empty).

Measured (issue 37, ``benchmarks/real_data.py --set region.area=<tracking_area.txt's numbers>``): PETS 2009
S2.L1 start frames 0-7, IDF1 against the cropped ids 0.830 -> 0.946 (start frames 3-7, not looked at while
building it: 0.831 -> 0.948), against the whole-view ids 0.945 -> 0.824 (as it should: those keep the id),
MOTA and mean error unchanged (0.926, 0.255 m), ID switches 2.75 -> 3.25 (not looked into).

>>> from worldtrack.trackers.base import Track
>>> from worldtrack.trackers.ellipsoid.region_config import RegionConfig
>>> visits = RegionVisits(RegionConfig(area=[0, 0, 4, 0, 4, 3, 0, 3], outside_s=1.0))
>>> walk = [(0.0, 1.0), (1.0, 5.0), (1.5, 5.0), (2.5, 1.0), (3.0, 5.0), (3.5, 1.0)]   # (t, y)
>>> [visits.relabel([Track(7, 1.0, y)], t)[0].id for t, y in walk]
[1, 1, 1, 2, 2, 2]
>>> [visits.relabel([Track(9, 1.0, y)], t)[0].id for t, y in [(4.0, 9.0), (6.0, 1.0)]]  # entering a first time
[3, 3]
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Sequence

import numpy as np

from worldtrack.scene.floor import points_in_polygon
from worldtrack.trackers.base import Track
from worldtrack.trackers.ellipsoid.region_config import RegionConfig

#: A map id not reported for this long is forgotten, s (a long live run keeps no id for ever).
FORGET_S = 600.0


@dataclass
class Visit:
    """One map id's current visit: the id it is reported under, since when (s) it has been outside
    the region (None: inside), when (s) it was last reported, and whether it has been inside yet
    (a person who enters for the first time keeps the id they were given outside)."""

    public: int
    outside_since: float | None
    last_t: float
    been_inside: bool


class RegionVisits:
    """The ids of the people's visits to ``config.area``, one tracker's (see the module).

    Parameters
    ----------
    config : RegionConfig — the polygon (m) and how long outside makes a new visit (s)
    """

    def __init__(self, config: RegionConfig):
        self.ring = config.ring()
        self.outside_s = float(config.outside_s)
        self.visits: dict[int, Visit] = {}
        #: The last visit id given (0: none yet).
        self.last_id = 0

    @property
    def enabled(self) -> bool:
        """Whether a region is set."""
        return len(self.ring) >= 3

    def relabel(self, tracks: Sequence[Track], t: float) -> list[Track]:
        """``tracks`` at time ``t`` (s), each under the id of the person's current visit: a new one for
        a map id first reported, and for a person back inside after ``outside_s`` or more outside."""
        if not self.enabled or not tracks:
            return list(tracks)
        xy = np.array([[tr.x, tr.y] for tr in tracks], float)
        inside = points_in_polygon(xy, self.ring)
        out = []
        for tr, here in zip(tracks, inside):
            v = self.visits.get(tr.id)
            if v is None:
                v = self.visits[tr.id] = Visit(self._new_id(), None if here else t, t, bool(here))
            elif here:
                if v.been_inside and v.outside_since is not None and t - v.outside_since >= self.outside_s:
                    v.public = self._new_id()
                v.outside_since, v.been_inside = None, True
            elif v.outside_since is None:
                v.outside_since = t
            v.last_t = t
            out.append(replace(tr, id=v.public))
        self.visits = {k: v for k, v in self.visits.items() if t - v.last_t <= FORGET_S}
        return out

    def _new_id(self) -> int:
        self.last_id += 1
        return self.last_id


__all__ = ["FORGET_S", "RegionVisits", "Visit"]
