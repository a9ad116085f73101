"""The particle tracker's working representation: one cloud of particles per filter.

A tracking filter's cloud belongs to a person of the :class:`~worldtrack.trackers.base.PositionMap`
(``person`` is their id; the tracker keeps its clouds keyed by it); a detection filter's cloud
(``person`` None) watches a floor region. Everything needed to continue a *person* lives on the
map; a cloud holds only what the method needs frame to frame: the particles, this frame's
observation, the colours learnt, the hidden samples of last frame.

The tracking filters hold ``particles`` particles each, so their arrays stack to (filters,
particles, …): :class:`CloudStack` keeps them as rows of one array from frame to frame, so that the
likelihood and the resampling read all filters at once without copying.

>>> c = Cloud(np.zeros((3, 3)), np.zeros((3, 3)), h=np.array([1.6, 1.7, 1.8]))
>>> c.take(np.array([2, 2, 0])); c.h.tolist()
[1.8, 1.8, 1.6]
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from worldtrack.trackers.particle.floor import FloorRegion

#: The per-particle arrays of a :class:`Cloud`, all indexed alike: the state (``xyz, v, h``) and
#: this frame's observation (``logpi, likely, col_h``).
PARTICLE_FIELDS = ("xyz", "v", "h", "logpi", "likely", "col_h")


@dataclass(eq=False)
class Cloud:
    """One particle filter: a tracking filter (``person`` set), or a detection filter.

    Attributes
    ----------
    xyz : (P, 3) float — particle positions, metres; ``v`` (P, 3) their own velocities, m/s;
        ``h`` (P,) each particle's object height (where its column's top is expected), metres
    person : int or None — the id of the person a tracking filter follows
    region : FloorRegion or None — the area a detection filter scatters over
    centre : (2,) float or None — the floor mean after the last resampling, metres; ``t_update``
        (s) its time (the object velocity of ``motion.model="object"`` measures from them)
    logw : (P,) float or None — a detection filter's log weights of the last frame (None: scatter
        afresh); ``until`` (s) when a detection filter that watches a lost track's place is dropped
        (None: kept for good); ``lost_id`` the id of that lost track
    logpi, likely, col_h : (P,) — this frame's observation
    colours : {camera_id: ColourModel} — the colours learnt
    k_lo : {camera_id: int} — how many of the lowest column samples of this filter's particles were
        hidden last frame (an order statistic over them)
    """

    xyz: np.ndarray
    v: np.ndarray
    person: int | None = None
    region: FloorRegion | None = None
    centre: np.ndarray | None = None
    t_update: float | None = None
    logw: np.ndarray | None = None
    until: float | None = None
    lost_id: int | None = None
    logpi: np.ndarray | None = None
    likely: np.ndarray | None = None
    col_h: np.ndarray | None = None
    h: np.ndarray | None = None
    colours: dict = field(default_factory=dict)
    k_lo: dict = field(default_factory=dict)

    def take(self, idx: np.ndarray) -> None:
        """Keep the particles ``idx`` (with repeats), this frame's observation included."""
        for name in PARTICLE_FIELDS:
            a = getattr(self, name)
            if a is not None:
                setattr(self, name, a[idx])

    def subset(self, idx: np.ndarray, **fields) -> "Cloud":
        """A new cloud of the particles ``idx`` (index array or mask), this frame's observation
        included; ``fields`` set the new cloud's other fields or replace its per-particle ones."""
        own = {name: getattr(self, name)[idx] for name in PARTICLE_FIELDS
               if name not in fields and getattr(self, name) is not None}
        return Cloud(**own, **fields)


class CloudStack:
    """The per-particle arrays of clouds holding N particles each, as rows of (F, N, …) arrays kept
    from frame to frame."""

    def __init__(self) -> None:
        self._rows: dict = {}            # per particle field, the clouds' rows and their array
        self._which: dict = {}           # (F, N) -> each of F·N particles' cloud index

    def stacked(self, clouds: Sequence[Cloud], name: str) -> np.ndarray:
        """(F, N, ...) the per-particle array ``name`` of ``clouds``: the array whose rows they hold,
        if :meth:`set_rows` gave them those rows and they still hold them (not to be changed then,
        except as the clouds' own arrays), else a stacked copy."""
        rows, a = self._rows.get(name, ((), None))
        if len(rows) == len(clouds) and all(getattr(c, name) is r for c, r in zip(clouds, rows)):
            return a
        return np.stack([getattr(c, name) for c in clouds])

    def set_rows(self, clouds: Sequence[Cloud], name: str, a: np.ndarray) -> None:
        """Give each of ``clouds`` its row of ``a`` (F, N, ...) as its ``name`` (views), and remember
        them for :meth:`stacked`."""
        rows = list(a)
        for c, r in zip(clouds, rows):
            setattr(c, name, r)
        self._rows[name] = (rows, a)

    def which(self, f: int, n: int) -> np.ndarray:
        """(F·N,) int: each particle's cloud index, for F clouds of N particles (kept per shape)."""
        w = self._which.get((f, n))
        if w is None:
            w = self._which[(f, n)] = np.repeat(np.arange(f), n)
        return w


__all__ = ["PARTICLE_FIELDS", "Cloud", "CloudStack"]
