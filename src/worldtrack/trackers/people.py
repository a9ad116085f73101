"""The people: every person's state on the shared position map, and what trackers report.

* :class:`Person` — everything a tracker needs to continue a person: position, size, velocity,
  mode, whether confirmed, height samples, when and by which cameras last seen, life-cycle
  counters. Persons live in the :class:`PositionMap`.
* :class:`PositionMap` — the 1999 paper's "person position management map": every person's state
  in world coordinates, including people no camera of this tracker sees. Several trackers (each
  with its own cameras) may share one map: per-frame counters advance once per time stamp, and
  "seen" wins over "not seen" whichever tracker steps first (see :meth:`Person.tick`).
* :class:`Track` — what a tracker reports for a person in a frame (output only: sinks read it).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Iterator, Sequence

import numpy as np

#: Person modes. ``capture``: just found, matched without the −1 ring until confirmed (paper 000
#: §5.2). ``tracking``: normal. ``lost``: kept in the map, not updated (in output records: no
#: camera shows them, or their evidence is failing). ``occluded`` (output records only): shown,
#: but mostly hidden behind others or with head and feet hidden.
MODES = ("capture", "tracking", "lost", "occluded")


@dataclass
class Track:
    """What a tracker reports for one person in one frame (sinks read it; it holds no state).

    Attributes
    ----------
    id : int — stable for the life of the person, from 1
    x, y : float — floor position, metres
    height, width : float — body size, metres
    vx, vy : float — floor velocity, m/s
    score : float — the tracker's match score of the last update (ellipsoid: E in [−1, 1])
    mode : str — one of :data:`MODES`
    flags : set of str — e.g. ``unmeasurable`` (head and feet hidden in every view)
    sigma : float — position uncertainty (1-σ per floor axis, metres)
    born, last_seen : float — times (s) of creation and of the last update with evidence
    extra : dict — method-specific output columns (e.g. the particle tracker's ``z, sx, sy, sz``)
    """

    id: int
    x: float
    y: float
    height: float = 1.65
    width: float = 0.40
    vx: float = 0.0
    vy: float = 0.0
    score: float = 0.0
    mode: str = "tracking"
    flags: set[str] = field(default_factory=set)
    sigma: float = 0.1
    born: float = 0.0
    last_seen: float = 0.0
    extra: dict[str, float] = field(default_factory=dict)

    @property
    def xy(self) -> np.ndarray:
        return np.array([self.x, self.y])

    @property
    def speed(self) -> float:
        """Floor speed, m/s."""
        return float(np.hypot(self.vx, self.vy))

    def copy(self) -> "Track":
        """An independent copy (the mutable ``flags`` and ``extra`` are copied too)."""
        return Track(self.id, self.x, self.y, self.height, self.width, self.vx, self.vy, self.score, self.mode,
                     set(self.flags), self.sigma, self.born, self.last_seen, dict(self.extra))


@dataclass(eq=False)
class Person:
    """One person in the position map: all a tracker needs to continue them.

    Attributes
    ----------
    id : int — from 1 once confirmed; negative while a tentative candidate (see
        :meth:`PositionMap.promote`)
    x, y : float — floor position, metres; ``prev_x, prev_y`` where they were at the previous
        time stamp (before this step's prediction), for velocities
    height, width : float — body size, metres
    vx, vy : float — floor velocity, m/s
    score : float — match score of the last update
    mode : str — one of :data:`MODES`
    confirmed : bool — a person, not a candidate: reported in the tracks
    flags : set of str — e.g. ``unmeasurable``
    sigma : float — position uncertainty (1-σ, metres)
    born, last_seen : float — seconds
    t : float — the time of the state (position and velocity), seconds; ``prev_x, prev_y, prev_t``
        the state before :meth:`PositionMap.advance` moved it to a new time stamp
    seen_by : tuple of str — the cameras that showed the person at ``seen_at``
    seen_at : float — the last time stamp any camera showed the person (−inf: never)
    counters : dict — life-cycle counters (frames in a row with low score, unseen, …) by name,
        advanced with :meth:`tick` and :meth:`reset`
    height_samples : list of float — the person's height measurements, metres
    height_tries : int — frames in which a height measurement was attempted
    height_px : list of float — how large (px) the view of each height sample showed the person
        (inf: several views); the ellipsoid tracker's ``height.prefer_large`` keeps the largest
    height_doubts : list of (float, float) — height measurements (m, view px) that disagree with the
        samples, held back (the ellipsoid tracker's ``height.reset_sigmas``)
    support, own_share : float — the share of the person's own pixels that are foreground, and
        of their visible pixels that nobody else covers (ellipsoid tracker; NaN unknown)
    rescue_after : float — no rescue search before this time (s)
    birth_camera : str or None — the camera whose foreground proposed this candidate
    low_since : float or None — since when (s) the person's evidence has been failing
    extra : dict — method-specific output values (e.g. ``z, sx, sy, sz``)
    """

    id: int
    x: float
    y: float
    height: float = 1.65
    width: float = 0.40
    vx: float = 0.0
    vy: float = 0.0
    score: float = 0.0
    mode: str = "capture"
    confirmed: bool = False
    flags: set[str] = field(default_factory=set)
    sigma: float = 0.1
    born: float = 0.0
    last_seen: float = 0.0
    t: float = 0.0
    prev_x: float = 0.0
    prev_y: float = 0.0
    prev_t: float | None = None
    seen_by: tuple[str, ...] = ()
    seen_at: float = -np.inf
    counters: dict[str, int] = field(default_factory=dict)
    height_samples: list[float] = field(default_factory=list)
    height_tries: int = 0
    height_px: list[float] = field(default_factory=list)
    height_doubts: list[tuple[float, float]] = field(default_factory=list)
    support: float = float("nan")
    own_share: float = float("nan")
    rescue_after: float = -np.inf
    birth_camera: str | None = None
    low_since: float | None = None
    extra: dict[str, float] = field(default_factory=dict)
    _touched: dict[str, float] = field(default_factory=dict, repr=False)

    @property
    def xy(self) -> np.ndarray:
        return np.array([self.x, self.y])

    def count(self, name: str) -> int:
        """The life-cycle counter ``name`` (0 if never advanced)."""
        return self.counters.get(name, 0)

    def tick(self, name: str, t: float, by: int = 1) -> int:
        """Advance counter ``name`` by ``by`` for time stamp ``t``, once per time stamp.

        A counter that a tracker has already advanced or :meth:`reset` at ``t`` is left alone:
        trackers sharing a map each step at ``t``, and a person one of them sees (reset) is seen,
        whichever steps first. Returns the counter.
        """
        if self._touched.get(name) != t:
            self.counters[name] = self.counters.get(name, 0) + by
            self._touched[name] = t
        return self.counters[name]

    def once(self, name: str, t: float) -> bool:
        """True the first time it is asked for ``name`` at time ``t``: for updates that trackers
        sharing the map must apply once per time stamp (a prediction, a velocity)."""
        key = "once:" + name
        if self._touched.get(key) == t:
            return False
        self._touched[key] = t
        return True

    def reset(self, name: str, t: float) -> None:
        """Set counter ``name`` to 0 at time ``t`` (wins over a :meth:`tick` at the same ``t``)."""
        self.counters[name] = 0
        self._touched[name] = t

    def mark_seen(self, t: float, cameras: Sequence[str]) -> None:
        """The cameras ``cameras`` show the person at time ``t`` (several trackers add theirs)."""
        self.seen_by = tuple(sorted(set(cameras) | (set(self.seen_by) if self.seen_at == t else set())))
        self.seen_at = t
        self.last_seen = t

    def seen_now(self, t: float) -> bool:
        """Whether some camera (of any tracker on the map) showed the person at time ``t``."""
        return self.seen_at == t

    def track(self) -> Track:
        """The output record of this person now."""
        return Track(self.id, self.x, self.y, self.height, self.width, self.vx, self.vy, self.score, self.mode,
                     set(self.flags), self.sigma, self.born, self.last_seen, dict(self.extra))


class PositionMap:
    """All people known to the system, keyed by id: the integration point between trackers.

    Examples
    --------
    >>> m = PositionMap()
    >>> p = m.add(1.0, 2.0, time=0.0)
    >>> p.id, len(m)
    (1, 1)
    >>> c = m.add(3.0, 2.0, time=0.0, tentative=True)
    >>> c.id, m.promote(c.id), sorted(q.id for q in m)
    (-1, 2, [1, 2])
    """

    def __init__(self) -> None:
        self._people: dict[int, Person] = {}
        self._next_id = 1
        self._next_tentative = -1
        #: Pairs of ids and how many frames in a row they have been close (duplicate rules).
        self.close_pairs: dict[tuple[int, int], int] = {}
        #: ``close_pairs`` before the time stamp ``close_time`` (several trackers count it once).
        self.close_before: dict[tuple[int, int], int] = {}
        self.close_time: float | None = None
        #: The cameras of the trackers stepping on this map (each tracker adds its own): a tracker
        #: leaves the people another tracker's cameras show to that tracker.
        self.cameras: set[str] = set()

    def add(self, x: float, y: float, height: float = 1.65, width: float = 0.40, mode: str = "capture",
            time: float = 0.0, track_id: int | None = None, tentative: bool = False,
            confirmed: bool | None = None) -> Person:
        """Register a new person; ids are never reused within a map.

        A ``tentative`` person (a candidate not yet confirmed) gets a negative id, so the ids users
        see count confirmed people only; :meth:`promote` gives it the next real id. ``confirmed``
        defaults to ``mode == "tracking"`` for people with a real id.
        """
        if tentative:
            track_id = self._next_tentative
            self._next_tentative -= 1
        elif track_id is None:
            track_id = self._next_id
        if track_id in self._people:
            raise ValueError(f"track id {track_id} already exists")
        if track_id > 0:
            self._next_id = max(self._next_id, track_id + 1)
        if confirmed is None:
            confirmed = track_id > 0 and mode == "tracking"
        p = Person(track_id, float(x), float(y), float(height), float(width), mode=mode, confirmed=confirmed,
                   born=time, last_seen=time, t=time, prev_x=float(x), prev_y=float(y))
        self._people[track_id] = p
        return p

    def promote(self, person_id: int, known_id: int | None = None) -> int:
        """Give a tentative person (negative id) the next real id, or ``known_id`` (a person
        re-identified: their id from before, not on the map); returns the new id."""
        if known_id is not None and (known_id in self._people or known_id <= 0 or known_id >= self._next_id):
            raise ValueError(f"track id {known_id} cannot be given back")
        p = self._people.pop(person_id)
        if known_id is not None:
            p.id = known_id
            self._people[p.id] = p
            return p.id
        p.id = self._next_id
        self._next_id += 1
        self._people[p.id] = p
        return p.id

    def remove(self, person_id: int) -> Person:
        """Take a person off the map (and out of the duplicate rules' pairs)."""
        self.close_pairs = {k: v for k, v in self.close_pairs.items() if person_id not in k}
        return self._people.pop(person_id)

    def __getitem__(self, person_id: int) -> Person:
        return self._people[person_id]

    def get(self, person_id: int) -> Person | None:
        return self._people.get(person_id)

    def __contains__(self, person_id: int) -> bool:
        return person_id in self._people

    def __iter__(self) -> Iterator[Person]:
        return iter(list(self._people.values()))

    def __len__(self) -> int:
        return len(self._people)

    def advance(self, t: float) -> None:
        """Move the map to time stamp ``t``: every person whose state is older keeps where they were
        (``prev_x, prev_y, prev_t``) and is now at ``t``. Trackers call it first in each step;
        several trackers at the same ``t`` advance it once."""
        for p in self._people.values():
            if p.t < t:
                p.prev_x, p.prev_y, p.prev_t = p.x, p.y, p.t
                p.t = t

    def positions(self) -> np.ndarray:
        """(N, 2) floor positions in map order."""
        return np.array([[p.x, p.y] for p in self], dtype=float).reshape(-1, 2)

    def tracks(self) -> list[Track]:
        """The confirmed people's output records, in map order (what a tracker returns)."""
        return [p.track() for p in self._people.values() if p.confirmed]
