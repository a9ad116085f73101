"""The live map for the page: the map stream read as it is written, and every camera's status.

A reader thread waits on the map stream (``XREAD BLOCK`` from the last entry it has, see
:mod:`worldtrack.map.messages`) and turns each map state into one JSON message, serialised once
for every browser: per person the position, velocity, σ, height, mode, the cameras that show
them and how many workers reported them. A status thread reads :func:`worldtrack.map.status.map_status`
twice a second and says per camera ``live`` (a worker holds its lease and its last observation
is less than ``stale_s`` old), ``stale`` (older, or nobody holds it any more) or ``down``
(nothing for ``down_s``, or never), with the lag in ms.

σ: map states carry no covariance, so the page's circle is the cameras' floor resolution at the
person's place (:func:`worldtrack.serve.plan.floor_sigma`: the information matrix of
:func:`worldtrack.map.fusion.floor_information` for a :data:`SIGMA_PX`-pixel error, vectorised
over people), growing by :data:`LOST_GROWTH_M_S` for every second a ``lost`` person has not been
seen.

The last ``trail_s`` seconds of messages are kept, so a page that connects late draws the
trails at once. A reader that falls behind the map (a slow machine, a burst) skips to the newest
states it reads (:data:`CATCH_UP_S`), and states less than :data:`MIN_STEP_S` apart are thinned:
a live view shows now, not the past.
"""

from __future__ import annotations

import collections
import json
import math
import threading
import time
from typing import Any, Callable

import numpy as np

from worldtrack.map.connection import MapKeys
from worldtrack.map.messages import MapState, decode_map_state, stream_id_ms, time_of_id
from worldtrack.scene.model import Scene
from worldtrack.serve.plan import cameras_seeing, floor_sigma

#: Pixel error behind the σ circle of a person a camera shows.
SIGMA_PX = 2.0
#: How fast the σ of a person the map has lost grows (m/s: a walk).
LOST_GROWTH_M_S = 1.0
#: σ of a person no camera shows (m).
UNSEEN_SIGMA_M = 1.0
#: Behind the map, the reader skips the states more than this much older than the newest it read (s):
#: the page stays current and its trails get coarser.
CATCH_UP_S = 0.5
#: States closer together than this (map time, s) are thinned to one: a page draws at most 25 a second.
MIN_STEP_S = 0.04
#: Map states read at most at once; a full read means the reader is far behind.
READ_COUNT = 50


def state_message(state: MapState, scene: Scene, now: float | None = None) -> dict[str, Any]:
    """One map state as the page's ``state`` message (positions in metres, times in seconds)."""
    now = time.time() if now is None else now
    people = state.people
    xy = np.array([(p.x, p.y) for p in people], dtype=float).reshape(-1, 2)
    height = np.array([p.height if math.isfinite(p.height) else scene.people.height for p in people])
    seen = cameras_seeing(scene, xy, height)
    sigma = floor_sigma(scene, xy, height, sigma_px=SIGMA_PX, unseen_m=UNSEEN_SIGMA_M) if people else []
    out = []
    for p, h, cams, s in zip(people, height, seen, sigma):
        lost = p.mode != "tracking"
        if lost and math.isfinite(p.last_seen):
            s += LOST_GROWTH_M_S * max(0.0, state.t - p.last_seen)
        out.append({"id": p.id, "x": round(p.x, 3), "y": round(p.y, 3), "vx": _r(p.vx), "vy": _r(p.vy),
                    "sigma": round(float(s), 3), "height": round(float(h), 2), "mode": p.mode,
                    "unmeasurable": int(lost), "cams": cams, "workers": p.workers, "lead": p.lead})
    return {"type": "state", "t": state.t, "captured": state.captured, "written": state.written,
            "lag_ms": round((now - state.captured) * 1000.0, 1), "people": out,
            "aliases": {str(k): v for k, v in state.aliases.items()}}


def _r(v: float) -> float | None:
    return round(v, 3) if math.isfinite(v) else None


def camera_status(status: dict[str, Any], cameras: list[str], stale_s: float, down_s: float) -> dict[str, Any]:
    """The page's ``cameras`` message from :func:`~worldtrack.map.status.map_status`.

    >>> s = {"cameras": {"a": {"holder": "w1", "lag_s": 0.12}, "b": {"holder": None, "lag_s": 2.0}},
    ...      "fusion": {"holder": "w1", "lag_s": 0.2}, "workers": {"w1": {}}}
    >>> [c["state"] for c in camera_status(s, ["a", "b", "c"], 1.0, 5.0)["cameras"]]
    ['live', 'stale', 'down']
    """
    out = []
    for cid in cameras:
        c = status["cameras"].get(cid)
        lag = None if c is None else c.get("lag_s")
        if lag is None or lag >= down_s:
            state = "down"
        elif c.get("holder") and lag < stale_s:
            state = "live"
        else:
            state = "stale"
        out.append({"id": cid, "state": state, "lag_ms": None if lag is None else round(lag * 1000.0),
                    "holder": None if c is None else c.get("holder")})
    fusion = status.get("fusion", {})
    return {"type": "cameras", "cameras": out, "workers": len(status.get("workers", {})),
            "fusion": {"holder": fusion.get("holder"),
                       "lag_ms": None if fusion.get("lag_s") is None else round(fusion["lag_s"] * 1000.0)}}


class LiveMap:
    """Reads the map and hands each message, as JSON text, to ``publish``.

    Parameters
    ----------
    client : redis.Redis (decoded strings; :func:`worldtrack.map.connection.connect`)
    keys : MapKeys
    scene : Scene — the scene the map belongs to
    publish : callable(text) — called from the reader threads
    trail_s : float — how much of the past a page that connects gets (s)
    stale_s, down_s : float — camera status thresholds (s)
    """

    def __init__(self, client: Any, keys: MapKeys, scene: Scene, publish: Callable[[str], None],
                 trail_s: float = 10.0, stale_s: float = 1.0, down_s: float = 5.0, status_every_s: float = 0.5):
        self.client, self.keys, self.scene, self.publish = client, keys, scene, publish
        self.trail_s, self.stale_s, self.down_s, self.status_every_s = trail_s, stale_s, down_s, status_every_s
        self.recent: collections.deque[tuple[float, str]] = collections.deque()
        self.last_cameras: str | None = None
        self.stop_event = threading.Event()
        self.error: str | None = None
        self.skipped = 0
        self._emitted = -math.inf
        self._lock = threading.Lock()
        self._threads: list[threading.Thread] = []

    def start(self) -> None:
        """Build what the first state needs (the cameras' obstacle maps: seconds in a large scene) and
        start the reader threads."""
        if self.scene.obstacles:
            for cid in self.scene.cameras:
                self.scene.occlusion(cid)
        for target in (self._read_states, self._read_status):
            th = threading.Thread(target=target, name=f"serve-{target.__name__}", daemon=True)
            th.start()
            self._threads.append(th)

    def stop(self) -> None:
        self.stop_event.set()
        for th in self._threads:
            th.join(timeout=3)

    def backlog(self) -> list[str]:
        """The messages a page that connects now gets first: the last ``trail_s`` of states and the
        camera status."""
        with self._lock:
            out = [text for _, text in self.recent]
            if self.last_cameras:
                out.append(self.last_cameras)
            return out

    def _emit_state(self, fields: dict[str, str]) -> None:
        try:
            state = decode_map_state(fields)
        except ValueError:
            return
        text = json.dumps(state_message(state, self.scene), separators=(",", ":"))
        with self._lock:
            self.recent.append((state.t, text))
            while self.recent and self.recent[0][0] < state.t - self.trail_s:
                self.recent.popleft()
        self.publish(text)

    def _read_states(self) -> None:
        import redis
        last = None
        while not self.stop_event.is_set():
            try:
                if last is None:
                    head = self.client.xrevrange(self.keys.map_stream, count=1)
                    last = head[0][0] if head else "0-0"
                    if head:
                        since = f"{int(float(head[0][1].get('t', 0)) * 1000 - self.trail_s * 1000)}-0"
                        for _, fields in self.client.xrange(self.keys.map_stream, min=since, max=last):
                            self._emit_state(fields)
                reply = self.client.xread({self.keys.map_stream: last}, block=500, count=READ_COUNT)
                if reply and len(reply[0][1]) == READ_COUNT:      # far behind: jump to the newest
                    head = self.client.xrevrange(self.keys.map_stream, count=1)
                    since = f"{stream_id_ms(time_of_id(head[0][0]) - CATCH_UP_S)}-0"
                    self.skipped += READ_COUNT
                    reply = [(self.keys.map_stream, self.client.xrange(self.keys.map_stream, min=since,
                                                                       max=head[0][0]))]
                self._set_error(None)
            except (redis.RedisError, OSError) as e:
                self._set_error(f"map unreachable ({type(e).__name__})")
                self.stop_event.wait(1.0)
                continue
            for _, entries in reply or ():
                if not entries:
                    continue
                last = entries[-1][0]
                newest = time_of_id(last)
                for entry_id, fields in entries:
                    t = time_of_id(entry_id)
                    if t >= newest - CATCH_UP_S and (t >= self._emitted + MIN_STEP_S or entry_id == last):
                        self._emitted = t
                        self._emit_state(fields)
                    else:
                        self.skipped += 1

    def _read_status(self) -> None:
        import redis

        from worldtrack.map.status import map_status
        while not self.stop_event.is_set():
            try:
                msg = camera_status(map_status(self.client, self.keys), list(self.scene.cameras), self.stale_s,
                                    self.down_s)
                msg["error"] = self.error
            except (redis.RedisError, OSError) as e:
                self._set_error(f"map unreachable ({type(e).__name__})")
                msg = {"type": "cameras", "cameras": [{"id": c, "state": "down", "lag_ms": None, "holder": None}
                                                      for c in self.scene.cameras], "error": self.error}
            text = json.dumps(msg, separators=(",", ":"))
            with self._lock:
                self.last_cameras = text
            self.publish(text)
            self.stop_event.wait(self.status_every_s)

    def _set_error(self, error: str | None) -> None:
        self.error = error


__all__ = ["CATCH_UP_S", "LOST_GROWTH_M_S", "LiveMap", "MIN_STEP_S", "SIGMA_PX", "camera_status", "state_message"]
