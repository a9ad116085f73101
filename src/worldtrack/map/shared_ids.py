"""A worker's position map whose ids come from the shared map (:mod:`worldtrack.map.worker`), so
trackers in different processes never give two people one id.
"""

from __future__ import annotations

from typing import Callable

from worldtrack.trackers.base import Person, PositionMap


class SharedPositionMap(PositionMap):
    """A :class:`PositionMap` whose new ids come from ``new_id(x, y)`` (the shared map's) instead of
    a local counter, so that trackers in different processes never give two people one id.

    >>> ids = iter([41, 42])
    >>> m = SharedPositionMap(lambda x, y: next(ids))
    >>> m.add(1.0, 1.0).id, m.promote(m.add(2.0, 2.0, tentative=True).id)
    (41, 42)
    >>> m.promote(m.add(3.0, 3.0, tentative=True).id, known_id=7)   # re-identified: its id back
    7
    """

    def __init__(self, new_id: Callable[[float, float], int]):
        super().__init__()
        self.new_id = new_id
        #: While a tracker's warm start copies people from its private passes (local ids), their
        #: ids are replaced by the shared map's: ``{local id: map id}``; None otherwise.
        self.remap: dict[int, int] | None = None

    def add(self, x: float, y: float, height: float = 1.65, width: float = 0.40, mode: str = "capture",
            time: float = 0.0, track_id: int | None = None, tentative: bool = False,
            confirmed: bool | None = None) -> Person:
        if not tentative and (track_id is None or self.remap is not None):
            new = self._free(self.new_id(x, y))
            if self.remap is not None and track_id is not None:
                self.remap[track_id] = new
            track_id = new
        return super().add(x, y, height, width, mode, time, track_id, tentative, confirmed)

    def promote(self, person_id: int, known_id: int | None = None) -> int:
        """As :meth:`PositionMap.promote`; a re-identified person's ``known_id`` (given by the shared
        map before) is taken back as it is, every other id comes from the shared map."""
        if known_id is not None:
            self._next_id = max(self._next_id, known_id + 1)    # the base class accepts ids it gave
            return super().promote(person_id, self._free(known_id))
        p = self[person_id]
        self._next_id = self._free(self.new_id(p.x, p.y))    # the base class gives out _next_id
        return super().promote(person_id)

    def _free(self, pid: int) -> int:
        """Make room for ``pid``: a copy of that person taken from the shared map gives way."""
        if pid in self:
            self.remove(pid)
        return pid


__all__ = ["SharedPositionMap"]
