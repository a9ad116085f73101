"""What every tracker shares: the track record, the person position map and the tracker protocol.

The :class:`PositionMap` is the 1999 paper's "person position management map": every person's id,
floor position, size, mode and score in world coordinates — including people that no camera of
this process currently sees. It is the integration point between trackers, cameras and processes.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Iterable, Iterator, Mapping, Protocol

import numpy as np

#: Track modes. ``capture``: just found, matched without the −1 ring until the score passes the
#: capture threshold (seed 000 §5.2). ``tracking``: normal. ``lost``: kept in the map, not updated.
MODES = ("capture", "tracking", "lost")


@dataclass
class Track:
    """One person in the position map.

    Attributes
    ----------
    id : int — stable for the life of the track, from 1
    x, y : float — floor position, metres
    height, width : float — body size used by the model, metres
    vx, vy : float — floor velocity, m/s
    score : float — the tracker's match score of the last update (ellipsoid: E in [−1, 1])
    mode : str — one of :data:`MODES`
    flags : set of str — e.g. ``unmeasurable`` (head and feet hidden in every view)
    sigma : float — position uncertainty (1-σ, metres)
    born, last_seen : float — times (s) of creation and of the last update with evidence
    frames_low : int — consecutive frames with a score under the keep threshold
    extra : dict — method-specific values written as extra output columns (e.g. ``sx, sy, sz``)
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
    flags: set[str] = field(default_factory=set)
    sigma: float = 0.1
    born: float = 0.0
    last_seen: float = 0.0
    frames_low: int = 0
    age_frames: int = 0
    extra: dict[str, float] = field(default_factory=dict)

    @property
    def xy(self) -> np.ndarray:
        return np.array([self.x, self.y])

    def copy(self) -> "Track":
        """An independent copy (the mutable ``flags`` and ``extra`` are copied too)."""
        return replace(self, flags=set(self.flags), extra=dict(self.extra))


class PositionMap:
    """All people known to the system, keyed by track id.

    Examples
    --------
    >>> m = PositionMap()
    >>> t = m.add(1.0, 2.0, time=0.0)
    >>> t.id, len(m)
    (1, 1)
    """

    def __init__(self) -> None:
        self._tracks: dict[int, Track] = {}
        self._next_id = 1
        self._next_tentative = -1

    def add(self, x: float, y: float, height: float = 1.65, width: float = 0.40, mode: str = "capture",
            time: float = 0.0, track_id: int | None = None, tentative: bool = False) -> Track:
        """Register a new person; ids are never reused within a map.

        A ``tentative`` person (a candidate not yet confirmed) gets a negative id, so the ids users
        see count confirmed people only; :meth:`promote` gives it the next real id.
        """
        if tentative:
            track_id = self._next_tentative
            self._next_tentative -= 1
        elif track_id is None:
            track_id = self._next_id
        if track_id in self._tracks:
            raise ValueError(f"track id {track_id} already exists")
        if track_id > 0:
            self._next_id = max(self._next_id, track_id + 1)
        t = Track(track_id, float(x), float(y), float(height), float(width), mode=mode, born=time, last_seen=time)
        self._tracks[track_id] = t
        return t

    def promote(self, track_id: int) -> int:
        """Give a tentative person (negative id) the next real id; returns the new id."""
        t = self._tracks.pop(track_id)
        t.id = self._next_id
        self._next_id += 1
        self._tracks[t.id] = t
        return t.id

    def remove(self, track_id: int) -> Track:
        return self._tracks.pop(track_id)

    def __getitem__(self, track_id: int) -> Track:
        return self._tracks[track_id]

    def __contains__(self, track_id: int) -> bool:
        return track_id in self._tracks

    def __iter__(self) -> Iterator[Track]:
        return iter(list(self._tracks.values()))

    def __len__(self) -> int:
        return len(self._tracks)

    def positions(self) -> np.ndarray:
        """(N, 2) floor positions in id order."""
        return np.array([[t.x, t.y] for t in self], dtype=float).reshape(-1, 2)

    def snapshot(self) -> list[Track]:
        """Copies of the current tracks (what sinks receive)."""
        return [t.copy() for t in self]


class Tracker(Protocol):
    """The one method that matters: take a synchronised bundle of frames, return the tracks."""

    position_map: PositionMap

    def step(self, frames: Mapping[str, "object"], t: float) -> list[Track]:
        """Update with ``frames`` (``{camera_id: Frame}``) taken at time ``t`` (s)."""
        ...


def warm_started(tracker: object, items: Iterable[tuple[int, float, Mapping[str, object]]]
                 ) -> Iterator[tuple[int, float, Mapping[str, object]]]:
    """The frames ``items`` unchanged, after the tracker's warm start on the first ones.

    A tracker that wants one (``warm_start_frames`` > 0, e.g. the ellipsoid tracker's) gets
    ``warm_start([(t, frames), ...])`` with up to that many first items before the first is
    yielded; any other tracker gets the items as they come.

    Parameters
    ----------
    tracker : object, optionally with ``warm_start_frames`` and ``warm_start``
    items : iterable of ``(index, t, {camera_id: Frame})`` (e.g. a ``VideoSource``)

    Yields
    ------
    the same items, in order. An error met while reading the first items (a corrupt frame) is
    raised after the items read before it, which are warmed on and yielded first, so nothing
    readable is lost.
    """
    n = int(getattr(tracker, "warm_start_frames", 0) or 0)
    it = iter(items)
    if n <= 0:
        yield from it
        return
    head: list = []
    error: BaseException | None = None
    try:
        for item in it:
            head.append(item)
            if len(head) >= n:
                break
    except BaseException as e:     # raised below, once the frames read before it are through
        error = e
    tracker.warm_start([(t, frames) for _, t, frames in head])  # type: ignore[attr-defined]
    yield from head
    if error is not None:
        raise error
    yield from it
