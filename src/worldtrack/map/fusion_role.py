"""The fusion role on Redis: one holder at a time (a lease), reading every camera's observations,
writing one map state per time bucket. Any worker (or ``worldtrack map fuse``) can take it over.

A bucket is written when every camera with a live lease has reported past it, or ``max_wait_s``
after its first observation came (a slow or dead worker does not hold the map up). The map
stream's entry id is the bucket's start in ms, and the write is fenced by the lease in one Lua
script together with the state the next holder resumes from (``map:current``): a bucket is
written once, by the holder of the lease, and a new holder continues from the bucket after the
last one written, re-reading the observations from there (they stay in their streams until
``retention_s``), so nothing in the streams is skipped on a take-over.
"""

from __future__ import annotations

import json
import threading
import time
from dataclasses import dataclass, field
from typing import Any, Callable

from worldtrack.map.config import MapConfig
from worldtrack.map.connection import MapKeys
from worldtrack.map.fusion import FusionState, fuse_bucket
from worldtrack.map.lease import Lease
from worldtrack.map.messages import (MapState, Observation, bucket_index, decode_observation, encode_map_state,
                                     stream_id_ms)

#: KEYS = (lease, map stream, current hash); ARGV = (owner, id, minid, state, last bucket, written, t,
#: people count, field, value, …). 1 written, 0 not our lease, -1 bucket already written.
_WRITE_MAP = """
if redis.call('GET', KEYS[1]) ~= ARGV[1] then
  return 0
end
local args = {KEYS[2]}
if ARGV[3] ~= '' then
  table.insert(args, 'MINID'); table.insert(args, '~'); table.insert(args, ARGV[3])
end
table.insert(args, ARGV[2])
for i = 9, #ARGV do table.insert(args, ARGV[i]) end
local ok = pcall(redis.call, 'XADD', unpack(args))
if not ok then
  return -1
end
redis.call('HSET', KEYS[3], 'state', ARGV[4], 'last_bucket', ARGV[5], 'written', ARGV[6], 't', ARGV[7],
           'people', ARGV[8], 'holder', ARGV[1])
for i = 9, #ARGV, 2 do
  if ARGV[i] == 'people' or ARGV[i] == 'aliases' or ARGV[i] == 'reports' then
    redis.call('HSET', KEYS[3], 'map_' .. ARGV[i], ARGV[i + 1])
  end
end
return 1
"""

#: With no state to resume from, start this far back in the observation streams (s).
COLD_START_S = 5.0


@dataclass
class FusionStats:
    """What the fusion role has done (for ``map status`` and the benchmarks)."""

    buckets: int = 0
    observations: int = 0
    late: int = 0
    malformed: int = 0
    takeovers: int = 0
    last_written: float = 0.0
    lag_s: list[float] = field(default_factory=list)


class FusionRole:
    """Contend for the fusion lease; while held, merge observations into the map.

    Parameters
    ----------
    client : redis.Redis — decoded strings
    keys : MapKeys
    cfg : MapConfig
    owner : str — this process's name (the lease's value)
    clock : callable — wall clock, seconds (``time.time``)
    on_state : callable, optional — called with every :class:`MapState` written
    log : callable, optional — called with a line when the role is taken or lost
    """

    def __init__(self, client: Any, keys: MapKeys, cfg: MapConfig, owner: str,
                 clock: Callable[[], float] = time.time, on_state: Callable[[MapState], None] | None = None,
                 log: Callable[[str], None] | None = None):
        self.client, self.keys, self.cfg, self.owner, self.clock = client, keys, cfg, owner, clock
        self.lease = Lease(client, keys.fusion_lease, owner, cfg.lease_s)
        self._write = client.register_script(_WRITE_MAP)
        self.on_state = on_state
        self.log = log or (lambda line: None)
        self.holding = False
        self.stats = FusionStats()
        self.state = FusionState()
        self._cursors: dict[str, str] = {}
        self._buckets: dict[int, list[Observation]] = {}
        self._first_arrival: dict[int, float] = {}
        self._latest: dict[str, float] = {}
        self._cameras: dict[str, float] = {}
        self._cameras_read = 0.0
        self._renewed = 0.0
        self._late_pending = 0
        self._start_ms = 0

    # ------------------------------------------------------------------ the loop
    def run(self, stop: threading.Event) -> None:
        """Contend and fuse until ``stop`` is set (then give the lease back). The lease is renewed by
        a thread of its own, so a long step (a backlog after a take-over) does not let it lapse."""
        from worldtrack.map.lease import LeaseKeeper
        keeper = LeaseKeeper([], self.cfg.renew_s, self._lost)
        keeper.start()
        try:
            while not stop.is_set():
                if not self.holding:
                    if self.lease.acquire():
                        self._take_over()
                        keeper.leases[:] = [self.lease]
                    else:
                        stop.wait(self.cfg.renew_s / 2)     # as a camera standby: take it soon after expiry
                    continue
                self.step(block_ms=20, renew=False)
        finally:
            keeper.stop(release=False)
            if self.holding:
                self.drain()
                self.lease.release()
                self.holding = False
                self.log("fusion: given back")

    def drain(self) -> None:
        """Before giving the role back: wait for the open buckets' last observations (``max_wait_s``),
        then write them all."""
        deadline = self.clock() + self.cfg.max_wait_s + 0.1
        while self.holding and self._buckets and self.clock() < deadline:
            self.step(block_ms=10)
        while self.holding and self._buckets:
            b = min(self._buckets)
            if not self._write_bucket(b, self._buckets.pop(b)):
                break

    def _lost(self, lease) -> None:
        self.holding = False
        self.log("fusion: lease taken by another process; contending again")

    def _take_over(self) -> None:
        self.holding = True
        self.stats.takeovers += 1
        self.takeover_at = self.clock()
        self._renewed = self.clock()
        raw = self.client.hgetall(self.keys.current)
        self.state = FusionState.from_json(raw["state"]) if raw.get("state") else FusionState()
        if self.state.last_bucket is not None:
            start_ms = stream_id_ms((self.state.last_bucket + 1) * self.cfg.bucket_s) - 1
        else:
            start_ms = stream_id_ms(self.clock() - COLD_START_S)
        self._buckets.clear()
        self._first_arrival.clear()
        self._cursors = {}
        self._start_ms = max(0, start_ms)
        self._refresh_cameras(force=True)
        last = "from its first bucket" if self.state.last_bucket is None else \
            f"after bucket t={self.state.last_bucket * self.cfg.bucket_s:.2f}"
        self.log(f"fusion: taken by this worker; map continues {last}")

    def _refresh_cameras(self, force: bool = False) -> None:
        now = self.clock()
        if not force and now - self._cameras_read < 1.0:
            return
        self._cameras_read = now
        raw = self.client.hgetall(self.keys.cameras)
        self._cameras = {c: float(json.loads(v).get("fps") or 10.0) for c, v in raw.items()}
        for c in self._cameras:
            self._cursors.setdefault(self.keys.observations(c), f"{self._start_ms}-0")

    def step(self, block_ms: int = 20, renew: bool = True) -> int:
        """Read what has come, write the buckets that are due; returns buckets written. ``renew``:
        renew the lease here (when no :class:`LeaseKeeper` does)."""
        now = self.clock()
        if renew and now - self._renewed >= self.cfg.renew_s:
            if not self.lease.renew():
                if self.lease.acquire():      # expired while this process stalled, but nobody took it
                    self._take_over()         # somebody may have held it meanwhile: reload the state
                    return 0
                self.holding = False
                self.log("fusion: lease lost (renewal came too late); contending again")
                return 0
            self._renewed = now
        self._refresh_cameras()
        if self._cursors:
            # A bounded batch per step (a backlog after a take-over is read in several).
            count = max(20, 4000 // len(self._cursors))
            replies = self.client.xread(self._cursors, count=count, block=block_ms)
            self._take(replies)
        else:
            time.sleep(block_ms / 1000.0)
        return self._close_due()

    def _take(self, replies: Any) -> None:
        now = self.clock()
        for stream, entries in replies or []:
            for entry_id, fields in entries:
                self._cursors[stream] = entry_id
                try:
                    o = decode_observation(fields)
                except ValueError:
                    self.stats.malformed += 1
                    continue
                self.stats.observations += 1
                b = bucket_index(o.t, self.cfg.bucket_s)
                if self.state.last_bucket is not None and b <= self.state.last_bucket:
                    self.stats.late += 1
                    self._late_pending += 1
                    continue
                self._buckets.setdefault(b, []).append(o)
                self._first_arrival.setdefault(b, now)
                self._latest[o.camera] = max(self._latest.get(o.camera, -1e18), o.t)

    def _live_cameras(self) -> list[str]:
        cams = list(self._cameras)
        if not cams:
            return []
        held = self.client.mget([self.keys.camera_lease(c) for c in cams])
        return [c for c, h in zip(cams, held) if h]

    def _close_due(self) -> int:
        written = 0
        live = None
        while self._buckets:
            b = min(self._buckets)
            end = (b + 1) * self.cfg.bucket_s
            if self.clock() - self._first_arrival[b] < self.cfg.max_wait_s:
                if live is None:
                    live = self._live_cameras()
                # Complete when each live camera's next frame falls after the bucket.
                if not all(self._latest.get(c, -1e18) + 1.0 / self._cameras.get(c, 10.0) >= end - 1e-6
                           for c in live):
                    break
            if not self._write_bucket(b, self._buckets.pop(b)):
                break
            self._first_arrival.pop(b, None)
            written += 1
        return written

    def _write_bucket(self, b: int, observations: list[Observation]) -> bool:
        now = self.clock()
        state = fuse_bucket(self.state, b, observations, self.cfg, written=now)
        state = MapState(state.t, state.people, state.reports, state.aliases, now, self._late_pending)
        self._late_pending = 0
        fields = encode_map_state(state)
        minid = str(stream_id_ms(state.t - self.cfg.retention_s))
        args = [self.owner, f"{stream_id_ms(state.t)}-0", minid, self.state.to_json(), str(b), repr(now),
                repr(state.t), str(len(state.present()))]
        for k, v in fields.items():
            args += [k, v]
        res = self._write(keys=[self.keys.fusion_lease, self.keys.map_stream, self.keys.current], args=args)
        if res == 0:
            self.holding = False
            return False
        self.stats.buckets += res == 1
        self.stats.last_written = now
        self.stats.lag_s.append(now - (b + 1) * self.cfg.bucket_s)
        if len(self.stats.lag_s) > 10000:
            del self.stats.lag_s[:5000]
        if self.on_state is not None:
            self.on_state(state)
        return True


def run_fusion_thread(role: FusionRole) -> tuple[threading.Thread, threading.Event]:
    """Run ``role`` in a daemon thread; set the returned event to stop it."""
    stop = threading.Event()
    th = threading.Thread(target=role.run, args=(stop,), name="fusion", daemon=True)
    th.start()
    return th, stop


__all__ = ["FusionRole", "FusionStats", "run_fusion_thread"]
