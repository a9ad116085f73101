"""The tracker a map worker steps: its inner tracker wrapped by the worker's :class:`~worldtrack.map.worker.MapLink`
(sync with the shared map before each step, publish after)."""

from __future__ import annotations

from typing import Callable, Mapping

import numpy as np

from worldtrack.map.evidence import in_views
from worldtrack.map.shared_ids import SharedPositionMap
from worldtrack.map.timings import StepTimings
from worldtrack.map.worker import MapLink
from worldtrack.trackers.base import Frame, PositionMap, Track, Tracker


class MapTracker:
    """A tracker stepping on the shared map: :class:`MapLink` ``sync`` before each step and
    ``publish`` after. Everything else is the inner tracker's (the :class:`Tracker` protocol).

    The inner tracker's warm start (tracking the first frames forwards and backwards, to start on
    frame 0 with the people in view) runs only in batch runs (files read as fast as the worker
    can): on live cameras it would hold the first frames back (~1 s) and publish them late. And
    only when the shared map has nobody near this worker's views (a worker starting with the map,
    not one taking a camera over), its people taking the map's ids.
    """

    def __init__(self, inner: Tracker, link: MapLink, on_step: Callable[[float], None] | None = None,
                 timings: StepTimings | None = None):
        self.inner, self.link, self.on_step, self.timings = inner, link, on_step, timings
        self.extra_columns = inner.extra_columns

    @property
    def position_map(self) -> PositionMap:
        return self.inner.position_map

    @property
    def warm_start_frames(self) -> int:
        if not isinstance(self.position_map, SharedPositionMap) or not self.link.lockstep:
            return 0        # live cameras (or files played as such): holding frames back is latency
        state = self.link.read_map()
        cams = list(self.link.cameras.values())
        if state is not None and any(any(in_views(cams, np.array([p.x, p.y]), p.height,
                                                  self.link.cfg.handover_margin_m)) for p in state.present()):
            return 0
        return self.inner.warm_start_frames

    def warm_start(self, frames) -> None:
        pm = self.position_map
        pm.remap = {}
        try:
            self.inner.warm_start(frames)
        finally:
            pm.remap = None

    def init_track(self, x: float, y: float, track_id: int | None = None, t: float = 0.0) -> Track:
        return self.inner.init_track(x, y, track_id=track_id, t=t)

    def overlay(self, camera_id: str):
        return self.inner.overlay(camera_id)

    def step(self, frames: Mapping[str, Frame], t: float) -> list[Track]:
        clock, marks = self.link.clock, [t, self.link.clock()]
        self.link.sync(self.inner, t)
        marks.append(clock())
        tracks = self.inner.step(frames, t)
        marks.append(clock())
        observations = self.link.observations(self.inner, tracks, t, frames)
        marks.append(clock())
        self.link.publish(observations)
        marks.append(clock())
        if self.timings is not None:
            self.timings.write(marks)
        if self.link.exchange is not None and not self.link.lockstep:
            self.link.exchange.read(self.link.state)    # live: the others' newest, for the next step
        if self.on_step is not None:
            self.on_step(t)
        return tracks


__all__ = ["MapTracker"]
