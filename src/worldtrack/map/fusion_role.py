"""The fusion role on Redis: one holder at a time (a lease), reading every camera's observations,
writing one map state per time bucket. Any worker (or ``worldtrack map fuse``) can take it over.

The map does not wait for the slowest worker. **The live map** (the hash ``map:current``, which
workers read before each step, and the channel ``map:updates``, on which every update is
published) is updated as soon as observations come, with
:func:`~worldtrack.map.fusion.provisional_state`: the open buckets' reports so far, weighed as
in a complete bucket, on top of the last complete one; a later worker's report of the same bucket
refines it, and a worker that has not reported yet delays only its own people (``map.live_updates``).

**The record** (the stream ``map``, one entry per time bucket, what ``replay`` reads) holds each
bucket's final state, written when every camera with a live lease has reported past it, or
``max_wait_s`` after its first observation came (a slow or dead worker does not hold it up) —
except for a batch worker's cameras (files read as fast as it can, registered with ``lockstep``):
their reports are waited for as long as their leases live, so that a batch run writes the same
record however loaded the machine is.
That entry's id is the bucket's start in ms, and the write is fenced by the lease in one Lua
script together with the state the next holder resumes from: a bucket is written once, by the
holder of the lease, and a new holder continues from the bucket after the last one written,
re-reading the observations from there (they stay in their streams until ``retention_s``), so
nothing in the streams is skipped on a take-over.

**Keeping the lease while working.** The lease is renewed by a thread of its own *and* between
the buckets of a step, and a step does a bounded amount of work (:data:`MAX_READ_PER_STEP`
observations read, :data:`MAX_BUCKETS_PER_STEP` buckets written), so a backlog (after a take-over,
or a process that stalled) is worked off in many short steps instead of one long one that lets the
lease lapse. A holder whose lease lapsed takes it again only if it is free, and then continues
after the last bucket *in the record* (:meth:`FusionRole._take_over`): its own pending work if
nobody wrote meanwhile, else the other holder's state — never from its first bucket. Every write
is fenced by the lease, so a holder that lost it writes nothing more (no two writers), and a
bucket somebody else wrote first is never written again.
"""

from __future__ import annotations

import json
import math
import threading
import time
from typing import Any, Callable

from worldtrack.map.config import MapConfig
from worldtrack.map.connection import MapKeys
from worldtrack.map.fusion import FusionState, fuse_bucket, provisional_state
from worldtrack.map.lease import UPDATE_MAP, WRITE_MAP, Lease
from worldtrack.map.messages import (MapState, Observation, bucket_index, decode_map_state, decode_observation,
                                     encode_map_state, stream_id_ms)
from worldtrack.map.starved import StarvedWorkers
from worldtrack.map.status import FusionStats

#: With no state to resume from, start this far back in the observation streams (s).
COLD_START_S = 5.0
#: Work per step: at most this many observations read (over all cameras) and buckets written.
MAX_READ_PER_STEP = 200
MAX_BUCKETS_PER_STEP = 10
#: The live map is updated from the open buckets only while this few are open (a backlog is
#: written to the record first; each record write updates the live map too).
MAX_LIVE_OPEN = 10
#: On Ctrl-C / SIGTERM the holder writes what it has for at most this long (s), then gives the
#: lease back; what it did not write stays in the streams for the next holder.
DRAIN_S = 1.5


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
        self._write = client.register_script(WRITE_MAP)
        self._update = client.register_script(UPDATE_MAP)
        self._fresh = False          # observations came that the live map does not hold yet
        self._said_unpublished = False
        self.on_state = on_state
        self.log = log or (lambda line: None)
        self.holding = False
        self.stats = FusionStats()
        self.state = FusionState()
        self._started = False        # has this process held the role (state, cursors) before?
        self._cursors: dict[str, str] = {}
        self._caught_up = False      # the last read reached the end of every stream
        self._buckets: dict[int, list[Observation]] = {}
        self._first_arrival: dict[int, float] = {}
        self._latest: dict[str, float] = {}
        self._cameras: dict[str, float] = {}
        self._batch: dict[str, str] = {}     # cameras of batch workers (lockstep) -> worker: waited for
        self._starved = StarvedWorkers(client, cfg.starved_wait_s)
        self._cameras_read = 0.0
        self._renewed = 0.0          # time.monotonic() of the last renewal made by the step loop
        self._late_pending = 0
        self._start_ms = 0
        self._deadline = math.inf    # time.monotonic() by which a drain stops writing

    # ------------------------------------------------------------------ the loop
    def run(self, stop: threading.Event) -> None:
        """Contend and fuse until ``stop`` is set (then write what is due, at most :data:`DRAIN_S`,
        and give the lease back). The lease is renewed by a thread of its own and between the
        buckets of a step."""
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
                self.step(block_ms=20)
        finally:
            try:
                if self.holding:
                    self.drain()                            # the keeper still renews meanwhile
            finally:
                keeper.stop(release=False)
                if self.holding:
                    self.lease.release()
                    self.holding = False
                    self.log("fusion: given back")

    def drain(self, budget_s: float = DRAIN_S) -> None:
        """Before giving the role back: wait a little for the open buckets' last observations, then
        write those whose observations are all read — for at most ``budget_s`` seconds (checked
        between buckets) and up to the first still waiting for a live batch worker's report (the
        last frames of a batch run whose other worker is still going: that worker takes the role
        over). What is left stays in the streams: the next holder continues after the last bucket
        written."""
        self._deadline = time.monotonic() + budget_s
        try:
            wait_end = time.monotonic() + min(self.cfg.max_wait_s + 0.1, budget_s / 2)
            while self.holding and self._buckets and time.monotonic() < wait_end:
                self.step(block_ms=10)
            live = self._live_cameras()
            while self.holding and self._buckets and self._caught_up and time.monotonic() < self._deadline:
                if not self._still_holding():
                    break
                b = min(self._buckets)
                missing = self._missing(b, live)
                if missing and self._waits_for(missing):
                    break       # a live batch worker's report is to come: it takes the role over and writes it
                if not self._write_bucket(b, self._buckets.pop(b)):
                    break
                self._first_arrival.pop(b, None)
        finally:
            self._deadline = math.inf
        if self.holding and self._buckets:
            self.log(f"fusion: {len(self._buckets)} open buckets left in the streams for the next holder")

    def _lost(self, lease) -> None:
        self.holding = False
        self.log("fusion: lease taken by another process; contending again")

    def _still_holding(self) -> bool:
        """Renew the lease when ``renew_s`` has passed since this loop last did; False (and stop
        writing) when it has been taken. A lapsed lease nobody took is taken again."""
        if not self.holding:
            return False
        now = time.monotonic()
        if now - self._renewed < self.cfg.renew_s:
            return True
        if self.lease.renew():
            self._renewed = now
            return True
        if self.lease.acquire():
            self._take_over()
            return self.holding
        self.holding = False
        self.log("fusion: lease lost (renewal came too late); contending again")
        return False

    def _record_end(self) -> tuple[int | None, MapState | None]:
        """The last bucket in the record (the map stream) and its state; (None, None) if empty."""
        last = self.client.xrevrange(self.keys.map_stream, count=1)
        if not last:
            return None, None
        state = decode_map_state(last[0][1])
        return bucket_index(state.t + 0.5 * self.cfg.bucket_s, self.cfg.bucket_s), state

    def _take_over(self, reload: bool = False) -> None:
        """Hold the role: continue after the last bucket written to the record. If that is this
        process's own last bucket (its lease lapsed and nobody wrote meanwhile) it goes on with
        what it has read; otherwise (or with ``reload``) it loads the state the last writer left
        and re-reads the observations after that bucket."""
        self.holding = True
        self._renewed = time.monotonic()
        self.takeover_at = self.clock()
        written, record = self._record_end()
        if self._started and not reload and written == self.state.last_bucket:
            self.stats.retaken += 1
            self.log("fusion: lease taken again; nothing was written meanwhile, map continues " + self._where())
            return
        self.stats.takeovers += not reload
        self._started = True
        raw = self.client.hgetall(self.keys.current)
        state = FusionState.from_json(raw["state"]) if raw.get("state") else FusionState()
        if written is not None and (state.last_bucket is None or state.last_bucket < written):
            state = FusionState.from_record(record, written)      # the hash is behind the record
        self.state = state
        if state.last_bucket is not None:
            start_ms = stream_id_ms((state.last_bucket + 1) * self.cfg.bucket_s) - 1
        else:
            start_ms = stream_id_ms(self.clock() - COLD_START_S)
        self._buckets.clear()
        self._first_arrival.clear()
        self._latest.clear()
        self._cursors, self._caught_up = {}, False
        self._start_ms = max(0, start_ms)
        self._refresh_cameras(force=True)
        self.log("fusion: taken by this worker; map continues " + self._where())

    def _where(self) -> str:
        b = self.state.last_bucket
        return "from its first bucket" if b is None else f"after bucket t={b * self.cfg.bucket_s:.2f}"

    def _refresh_cameras(self, force: bool = False) -> None:
        now = self.clock()
        if not force and now - self._cameras_read < 1.0:
            return
        self._cameras_read = now
        raw = {c: json.loads(v) for c, v in self.client.hgetall(self.keys.cameras).items()}
        self._cameras = {c: float(v.get("fps") or 10.0) for c, v in raw.items()}
        self._batch = {c: str(v.get("worker") or "") for c, v in raw.items() if v.get("lockstep")}
        for c in self._cameras:
            self._cursors.setdefault(self.keys.observations(c), f"{self._start_ms}-0")

    def step(self, block_ms: int = 20, renew: bool = True) -> int:
        """Read what has come (at most :data:`MAX_READ_PER_STEP` observations), write the buckets
        that are due (at most :data:`MAX_BUCKETS_PER_STEP`); returns buckets written. ``renew``:
        renew the lease here too (every ``renew_s``) — whether or not a :class:`LeaseKeeper` does."""
        if renew and not self._still_holding():
            return 0
        self._refresh_cameras()
        if self._cursors:
            count = max(5, MAX_READ_PER_STEP // len(self._cursors))
            replies = self.client.xread(self._cursors, count=count, block=block_ms or None)
            self._caught_up = all(len(entries) < count for _, entries in replies or [])
            self._take(replies)
        else:
            self._caught_up = True
            time.sleep(block_ms / 1000.0)
        written = self._close_due(renew)
        if self._fresh and self.holding and self.cfg.live_updates and 0 < len(self._buckets) <= MAX_LIVE_OPEN:
            self._update_live()
        self._fresh = False
        return written

    def _update_live(self) -> None:
        """Write the open buckets' reports so far to the live map (not to the record)."""
        now = self.clock()
        state = provisional_state(self.state, self._buckets, self.cfg, written=now)
        fields = encode_map_state(state)
        res = self._update(keys=[self.keys.fusion_lease, self.keys.current],
                           args=[self.owner, self.keys.updates, json.dumps(fields), repr(now), repr(state.t),
                                 str(len(state.present())), fields["people"], fields["aliases"], fields["reports"]])
        if res == 0:
            self.holding = False
            return
        self.stats.updates += 1
        self._published(res)

    def _published(self, res: int) -> None:
        if res == 2 and not self._said_unpublished:
            self._said_unpublished = True
            self.log(f"fusion: this Redis user may not publish to {self.keys.updates}: the live map is kept "
                     f"in {self.keys.current} only (grant the channel: ACL SETUSER … '&{self.keys.prefix}:*')")

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
                self._fresh = True
                self._first_arrival.setdefault(b, now)
                self._latest[o.camera] = max(self._latest.get(o.camera, -1e18), o.t)

    def _live_cameras(self) -> list[str]:
        cams = list(self._cameras)
        if not cams:
            return []
        held = self.client.mget([self.keys.camera_lease(c) for c in cams])
        lapsed = {c: self._batch[c] for c, h in zip(cams, held) if not h and c in self._batch}
        return [c for c, h in zip(cams, held) if h] + self._starved.connected(lapsed)

    def _close_due(self, renew: bool = True) -> int:
        """Write the complete (or ``max_wait_s`` old) buckets in order, at most
        :data:`MAX_BUCKETS_PER_STEP`, renewing the lease between them (``renew``)."""
        written, live = 0, None
        while self._buckets and written < MAX_BUCKETS_PER_STEP and time.monotonic() < self._deadline:
            b = min(self._buckets)
            if self.state.last_bucket is None and self._cameras_read < self._first_arrival[b]:
                self._refresh_cameras(force=True)    # the map's first bucket: every camera registered by now
            live = self._live_cameras() if live is None else live
            missing = self._missing(b, live)
            if missing and (self.clock() - self._first_arrival[b] < self.cfg.max_wait_s or self._waits_for(missing)):
                break
            if renew and not self._still_holding():
                break
            if not self._write_bucket(b, self._buckets.pop(b)):
                break
            self._first_arrival.pop(b, None)
            written += 1
        return written

    def _missing(self, b: int, live: list[str]) -> list[str]:
        """The cameras of ``live`` whose report of bucket ``b`` may still come (complete when each
        live camera's next frame falls after the bucket)."""
        end = (b + 1) * self.cfg.bucket_s
        return [c for c in live if self._latest.get(c, -1e18) + 1.0 / self._cameras.get(c, 10.0) < end - 1e-6]

    def _waits_for(self, missing: list[str]) -> bool:
        """Past ``max_wait_s``: does the bucket still wait for these cameras? Yes for a batch worker's
        (files read as fast as it can, :attr:`MapLink.lockstep`) while its lease lives: a bucket
        written without its report would make the record depend on the machine's load (the report
        dropped as late, the other workers reading a map without it); a dead worker's lease lapses
        within ``lease_s`` (one starved of CPU stays connected: :mod:`worldtrack.map.starved`). A live
        camera is not waited for (a slow worker delays only itself)."""
        self._refresh_cameras(force=True)       # a batch flag registered since the last read
        return any(c in self._batch for c in missing)

    def _write_bucket(self, b: int, observations: list[Observation]) -> bool:
        """Fuse bucket ``b`` and write it, fenced by the lease. False when not written: the lease is
        not ours (stop; the bucket stays pending), or somebody else wrote the bucket first (then
        continue after the record's last bucket)."""
        now = self.clock()
        fused = self.state.copy()          # self.state moves on only once the record holds the bucket
        state = fuse_bucket(fused, b, observations, self.cfg, written=now)
        state = MapState(state.t, state.people, state.reports, state.aliases, now, self._late_pending)
        fields = encode_map_state(state)
        minid = str(stream_id_ms(state.t - self.cfg.retention_s))
        args = [self.owner, f"{stream_id_ms(state.t)}-0", minid, fused.to_json(), str(b), repr(now),
                repr(state.t), str(len(state.present())), self.keys.updates, json.dumps(fields)]
        for k, v in fields.items():
            args += [k, v]
        res = self._write(keys=[self.keys.fusion_lease, self.keys.map_stream, self.keys.current], args=args)
        if res == 0:
            # Not ours: write nothing more, keep the bucket. If this process takes the lease again
            # and nobody wrote meanwhile, it goes on from here (_take_over).
            self._buckets[b] = observations
            self.holding = False
            self.log("fusion: lease lost before a write; contending again")
            return False
        if res == -1:
            # The record already holds this bucket (another holder wrote it while this process's
            # lease had lapsed): never write it again, continue after the record's last bucket.
            self.log(f"fusion: bucket t={state.t:.2f} already in the record; continuing after the record's last")
            self._take_over(reload=True)
            return False
        self.state = fused
        self._late_pending = 0
        self.stats.buckets += 1
        self._published(res)
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
