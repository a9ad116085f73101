"""A worker on the shared map: owns some cameras (leases), runs a tracker on them, publishes what it
sees and takes from the map the people it does not see.

The worker's tracker needs no Redis code: it steps on its own :class:`~worldtrack.map.shared_ids.SharedPositionMap`, and the
worker, around each step (:class:`~worldtrack.map.map_tracker.MapTracker`):

* **before** — puts on that map the people the shared map holds near its cameras' views (a person
  walking in from a neighbour's view is on it under their id before this worker's cameras show
  them: no new birth) and moves the people its cameras did not show at the previous step to where
  the shared map has them. People its cameras show are left to its tracker.
* **after** — publishes, per camera, the people its tracker holds in that camera's view with its
  estimate, their support, and whether the cameras show them now (a person it holds but cannot see,
  hidden behind a desk, is published as not seen); and the ids its tracker ended there.

New ids come from the map (:class:`~worldtrack.map.shared_ids.SharedPositionMap`): a person the tracker confirms where the
map has just lost somebody takes that person's id (a camera taken over after a worker died finds
its people again), anyone else the next id of the map's counter, so ids never clash between workers.
See :mod:`worldtrack.map.fusion` for how the estimates of a person two workers see are merged.
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from worldtrack.errors import InputError
from worldtrack.geometry.camera import Camera
from worldtrack.map.affirm import CandidateExchange
from worldtrack.map.config import MapConfig
from worldtrack.map.connection import MapKeys
from worldtrack.map.evidence import (LEAD_SHARE, NO_COVARIANCE, floor_information, in_views, looks_empty,
                                     people_boxes, support_of, tracker_covariance, visible_share)
from worldtrack.map.lease import FENCED_XADD, Lease
from worldtrack.map.merges import held_together
from worldtrack.map.messages import (FORMAT_VERSION, REFUTED, Estimate, MapState, Observation, decode_map_state,
                                     encode_observation, stream_id_ms)
from worldtrack.map.rays import camera_rays
from worldtrack.map.same_blob import same_blob_claims
from worldtrack.map.shared_ids import SharedPositionMap
from worldtrack.map.timings import map_epoch, set_epoch
from worldtrack.trackers.base import Frame, PositionMap, Track, Tracker


class MapLink:
    """A worker's side of the shared map: its camera leases, ids, the map it reads, what it publishes.

    Parameters
    ----------
    client : redis.Redis
    keys : MapKeys
    cfg : MapConfig
    name : this worker's name (lease value)
    cameras : {camera_id: Camera} — the cameras this worker owns
    fps : the cameras' frame rate (for the fusion's wait)
    clock : wall clock, seconds
    occlusion : {camera_id: (H, W) floor distance of the obstacles} — the scene's occlusion maps
        (:func:`~worldtrack.map.evidence.floor_information` leaves hidden body points out)
    scene_cameras : every camera of the scene, in the scene's order: new ids then follow a rule
        that does not depend on which worker asks first (:meth:`new_id`); empty: one counter for all
    """

    def __init__(self, client: Any, keys: MapKeys, cfg: MapConfig, name: str, cameras: Mapping[str, Camera],
                 fps: float = 10.0, clock: Callable[[], float] = time.time,
                 occlusion: Mapping[str, np.ndarray] | None = None, scene_cameras: Sequence[str] = ()):
        self.client, self.keys, self.cfg, self.name, self.clock = client, keys, cfg, name, clock
        self.cameras, self.occlusion, self.fps = dict(cameras), dict(occlusion or {}), fps
        self.leases = {c: Lease(client, keys.camera_lease(c), name, cfg.lease_s) for c in self.cameras}
        order = [c for c in scene_cameras if c in self.cameras]
        #: Ids this worker gives out: ``slot + 1 + k * stride`` (k = 0, 1, ...), slot = the scene
        #: index of its first camera (None: the map's one counter, first come first served).
        self.id_slot = (order[0], list(scene_cameras).index(order[0]), len(scene_cameras)) if order else None
        self._xadd = client.register_script(FENCED_XADD)
        self.state: MapState | None = None
        self._state_t: float | None = None
        self.mine_seen: set[int] = set()      # people this worker's cameras have shown (its own)
        self.ever_seen: set[int] = set()
        self.placed: set[int] = set()         # people put on the local map from the shared one
        self.handed_over = 0                  # how many times (hand-overs from a neighbour's view)
        self.claimed = 0                      # new people that took the id of a person the map had
        self.born_here: set[int] = set()      # new ids this worker gave (same_blob: its newborns)
        self.together: dict[tuple[int, int], float] = {}     # map.crossing_s: pairs seen at once, when (s)
        self._reported: dict[int, tuple[str, ...]] = {}
        self.published = 0
        self.last_capture: float | None = None
        #: Batch runs (files not played in real time): before each step wait (at most
        #: ``lockstep_wait_s``) until the map holds the previous frame, so that workers going at
        #: different speeds stay in step and none reads a map from its own future.
        #: The fusion waits for a batch worker's report of each bucket however late it comes (while
        #: its lease lives, :meth:`FusionRole._waits_for`), so the wait here is long too: a worker
        #: that went on without the bucket would read a map that depends on the machine's load.
        self.lockstep = False
        self.lockstep_wait_s = 60.0
        self._first_t: float | None = None
        self._prev_t: float | None = None
        #: The end (s) of the last complete bucket of the map (every live camera's report in).
        self.complete_until, self._record_id = -math.inf, ""
        self._aliases: dict[int, tuple[int, float]] = {}      # batch runs: merges read from the record
        #: Candidates confirmed with other workers' views (:mod:`worldtrack.map.affirm`); None: off.
        self.exchange = CandidateExchange(client, keys, name, self.cameras, self.occlusion, cfg.merge_distance_m) \
            if cfg.affirm_candidates else None

    # ------------------------------------------------------------------ set-up
    def register(self) -> None:
        """Tell the fusion about this worker's cameras (their frame rate; ``lockstep``: a batch run,
        whose reports the fusion waits for however late they come)."""
        info = {"fps": self.fps, "worker": self.name} | ({"lockstep": True} if self.lockstep else {})
        self.client.hset(self.keys.cameras, mapping={c: json.dumps(info) for c in self.cameras})

    def epoch(self, lead_s: float = 0.5, wait: bool = False, poll_s: float = 0.05) -> float:
        """The map's epoch: when video files played as cameras have their frame 0. Set by the first
        worker to ask (``lead_s`` from now), or with ``wait`` by ``worldtrack map start``."""
        return map_epoch(self.client, self.keys, self.cfg.bucket_s, self.clock, lead_s, wait, poll_s)

    def new_id(self, x: float, y: float) -> int:
        """An id for a person the tracker confirms at (x, y): a lost person's of the map nearby, else
        a new one.

        New ids do not depend on which worker asks first (a batch run gives the same ids every
        time): the workers whose first camera has scene index ``slot`` (of ``stride`` cameras)
        give out ``slot + 1``, ``slot + 1 + stride``, ... from their own counter on the map (a
        standby that takes those cameras over continues it), so no two workers give one id.
        """
        claimed = self._claim(x, y)
        if claimed is not None:
            self.claimed += 1
            return claimed
        camera, slot, stride = self.id_slot or ("", 0, 1)      # "": the map's one counter
        pid = (int(self.client.incr(self.keys.ids_of(camera) if camera else self.keys.ids)) - 1) * stride + slot + 1
        self.born_here.add(pid)
        return pid

    def _claim(self, x: float, y: float) -> int | None:
        if self.state is None:
            return None
        best, best_d = None, math.inf
        now = self._state_t if self._state_t is not None else self.state.t
        for p in self.state.people:
            d = math.hypot(p.x - x, p.y - y)
            if p.mode == "lost":
                reach = self.cfg.claim_radius_m + 1.5 * max(0.0, now - p.last_seen)
            elif p.id not in self.mine_seen:
                reach = self.cfg.merge_distance_m
            else:
                continue
            if d < reach and d < best_d:
                best, best_d = p.id, d
        return best

    # ------------------------------------------------------------------ each frame
    def read_map(self) -> MapState | None:
        """The latest map state (None before the first): the live map, or in a batch run (lockstep) the
        last complete bucket (every worker's reports, not whichever came first: runs repeat)."""
        if self.lockstep:
            # Every bucket written since the last read, not only the newest: a merge (alias) is in
            # the state of its own bucket only, and a worker that skipped it would go on publishing
            # the merged id, a new person to the map once the alias is forgotten.
            new = (self.client.xrange(self.keys.map_stream, min=f"({self._record_id}", max="+") if self._record_id
                   else self.client.xrevrange(self.keys.map_stream, count=self._alias_window())[::-1])
            if not new:
                return self.state
            states = [decode_map_state(fields) for _, fields in new]
            # Kept for forget_after_s: several reads may come between two steps (the lockstep wait).
            self._aliases.update({young: (elder, s.t) for s in states for young, elder in s.aliases.items()})
            recent = states[-1].t - self.cfg.forget_after_s
            self._aliases = {y: (e, t) for y, (e, t) in self._aliases.items() if t > recent}
            self._record_id, self.state = new[-1][0], dataclasses.replace(
                states[-1], aliases={young: elder for young, (elder, _) in self._aliases.items()})
            self.complete_until = self.state.t + self.cfg.bucket_s
            return self.state
        raw = self.client.hmget(self.keys.current, ["map_people", "map_aliases", "t", "written", "map_reports",
                                                    "last_bucket"])
        if raw[0] is None:
            return None
        if raw[5] is not None:
            self.complete_until = (int(raw[5]) + 1) * self.cfg.bucket_s
        if self.state is None or float(raw[2]) != self.state.t or float(raw[3] or 0) != self.state.written:
            fields = {"v": FORMAT_VERSION, "t": raw[2], "people": raw[0], "aliases": raw[1] or "{}",
                      "written": raw[3] or "0", "reports": raw[4] or "[]"}
            self.state = decode_map_state(fields)
        return self.state

    def _alias_window(self) -> int:
        """How many buckets back a merge is still applied (``forget_after_s``): what a first read takes."""
        return max(1, int(math.ceil(self.cfg.forget_after_s / self.cfg.bucket_s)))

    def _wait_for_map(self, t: float) -> None:
        if self._first_t is None:
            self._first_t = t
        if not self.lockstep or t - self._first_t < 0.5 / self.fps:
            return                  # frame 0: no map yet; from frame 1 on, the previous frame's
        deadline = time.monotonic() + self.lockstep_wait_s
        while time.monotonic() < deadline:
            # The bucket of the previous frame complete: every worker's report of it is in.
            if self.read_map() is not None and self.complete_until > t - max(1.0 / self.fps, self.cfg.bucket_s):
                return
            time.sleep(0.002)

    def sync(self, tracker: Tracker, t: float) -> None:
        """Before the tracker steps at ``t``: take from the shared map what this worker does not see."""
        self._wait_for_map(t)
        state = self.read_map()
        self._state_t = t
        if self.exchange is not None:   # a batch run reads the others' observations here, a live one after publishing
            self.exchange.before_step(tracker.position_map, state, t, read=self.lockstep)
        if state is None:
            return
        local = tracker.position_map
        for young, elder in state.aliases.items():
            if young not in local:
                continue
            if elder == REFUTED:
                local.remove(young)                      # dropped by the map on negative evidence
            elif elder not in local and isinstance(local, SharedPositionMap):
                local.promote(young, known_id=elder)     # its copy goes on under the elder id, as tracked
                for held in (self.mine_seen, self.ever_seen):
                    if young in held:
                        held.add(elder)
            else:
                local.remove(young)
            self.mine_seen.discard(young)
            self.ever_seen.discard(young)
            self.placed.discard(young)
        present = {p.id: p for p in state.present()}
        cams = list(self.cameras.values())
        dt = min(max(t - state.captured, 0.0), 0.5)
        # A person this worker's tracker holds is set to where the map had them at the time of its
        # previous step (the tracker then predicts them to ``t`` itself); see _follows_map.
        dt_held = dt if self.cfg.share_rule == "support-lead" else \
            min(max((self._prev_t if self._prev_t is not None else t) - state.captured, 0.0), 0.5)
        self._prev_t = t
        for p in present.values():
            x, y = p.x + p.vx * dt, p.y + p.vy * dt
            q = local.get(p.id)
            if q is None:
                # Not where this worker already holds somebody under another id: the map merges
                # those two ids (a copy here would make one worker hold the same person twice).
                if any(in_views(cams, np.array([x, y]), p.height, self.cfg.handover_margin_m)) and \
                        not self._holds_near(local, x, y, p.id, t) and not self._born_in_view(p, x, y, t):
                    self._place(tracker, p, x, y, t)
            elif self._follows_map(p):
                # Not shown by this worker's cameras, or also by another worker's: from where the
                # map has them (this worker's cameras then move them by their evidence).
                q.x, q.y, q.vx, q.vy = p.x + p.vx * dt_held, p.y + p.vy * dt_held, p.vx, p.vy
                if math.isfinite(p.height):
                    q.height = p.height
        for q in list(local):
            if q.id > 0 and q.id in self.placed and q.id not in present and q.id not in self.mine_seen:
                local.remove(q.id)
                self.placed.discard(q.id)

    def _follows_map(self, p) -> bool:
        """Does this worker start person ``p`` (on the map and on its own) from the map's estimate?

        Yes when its cameras do not show them. When they do, by ``map.share_rule``:
        ``information`` — yes whenever another worker's estimate is in the map's (every worker
        that sees a person refines the common estimate with its own images each frame, and the
        map adds their measurements by information, :mod:`worldtrack.map.fusion`);
        ``support-lead`` — unless this worker is the person's lead (it continues from its own).
        """
        if p.id not in self.mine_seen:
            return True
        if self.cfg.share_rule == "information":
            return p.workers > 1 or p.lead not in ("", self.name)
        return p.lead not in ("", self.name)

    def _born_in_view(self, p, x: float, y: float, t: float) -> bool:
        """Did another worker start ``p`` moments ago (``own_births_s``) where this worker's
        cameras already show them? Then this worker finds them in its own images (its new person
        takes their id, :meth:`new_id`, or the map merges the two) rather than from a first
        estimate another view made — at a run's start a far camera's, through a door."""
        return t - p.born < self.cfg.own_births_s and any(in_views(list(self.cameras.values()), np.array([x, y]),
                                                                      p.height))

    def _holds_near(self, local: PositionMap, x: float, y: float, pid: int, t: float) -> bool:
        """Held within merge_distance_m of (x, y), and (``crossing_s``) not seen beside ``pid`` lately
        or within ``crossing_gap_m`` (there its tracker would end ``pid`` again as a duplicate)?"""
        return any(q.id > 0 and (d := math.hypot(q.x - x, q.y - y)) < self.cfg.merge_distance_m and
                   (t - self.together.get((min(q.id, pid), max(q.id, pid)), -math.inf) > self.cfg.crossing_s or
                    d < self.cfg.crossing_gap_m) for q in local)

    def _place(self, tracker: Tracker, p, x: float, y: float, t: float) -> None:
        local = tracker.position_map
        try:
            tracker.init_track(x, y, track_id=p.id, t=t)
        except (InputError, TypeError):
            local.add(x, y, p.height, p.width, mode="tracking", time=t, track_id=p.id, confirmed=True)
        q = local[p.id]
        q.vx, q.vy, q.born, q.last_seen = p.vx, p.vy, p.born, p.last_seen
        q.height = p.height if math.isfinite(p.height) else q.height
        q.width = p.width if math.isfinite(p.width) else q.width
        self.placed.add(p.id)
        self.handed_over += 1

    def observations(self, tracker: Tracker, tracks: Sequence[Track], t: float,
                     frames: Mapping[str, Frame]) -> list[Observation]:
        """What this worker saw at ``t``, one observation per camera it has a frame of."""
        local = tracker.position_map
        sent = self.clock()
        per_cam: dict[str, list[Estimate]] = {c: [] for c in frames if c in self.cameras}
        cams = [c for c in per_cam]
        now_ids = set()
        self.mine_seen = set()
        # Everybody this worker's tracker holds, as boxes in each camera: a person behind another
        # one in a view is measured worse there (their feet, which tell the depth, are hidden).
        bodies = np.array([[tr.x, tr.y, tr.height, tr.width] for tr in tracks]).reshape(-1, 4)
        boxes = {c: people_boxes(self.cameras[c], bodies) for c in cams}
        for k, tr in enumerate(tracks):
            person = local.get(tr.id)
            seen = person is not None and (person.last_seen >= t or person.seen_now(t))
            views = in_views([self.cameras[c] for c in cams], np.array([tr.x, tr.y]), tr.height)
            if not any(views) or not (seen or tr.id in self.ever_seen):
                continue
            mine = [c for c, ok in zip(cams, views) if ok]
            where, occ = np.array([tr.x, tr.y]), [self.occlusion.get(c) for c in mine]
            # This worker's own estimate only where its cameras show most of the body; a person
            # it glimpses (through a door, at the image's edge) it keeps taking from the map.
            share = visible_share([self.cameras[c] for c in mine], where, tr.height, occ)
            if seen and share >= LEAD_SHARE:
                self.mine_seen.add(tr.id)
                self.ever_seen.add(tr.id)
                self.placed.discard(tr.id)
            now_ids.add(tr.id)
            support = support_of(person, tr)
            others = [np.delete(boxes[c], k, axis=0) for c in mine]
            info = floor_information([self.cameras[c] for c in mine], where, tr.height, occlusion=occ, blockers=others)
            cov = tracker_covariance(tracker, person, t) if seen else None
            own = visible_share([self.cameras[c] for c in mine], where, tr.height, occ, others)
            e = Estimate(tr.id, tr.x, tr.y, tr.height, tr.width, tr.vx, tr.vy, float(tr.score), support, seen, *info,
                         share, *(NO_COVARIANCE if cov is None else (cov[0, 0], cov[0, 1], cov[1, 1])), own)
            for c, ok in zip(cams, views):
                if ok:
                    per_cam[c].append(e)
        ended = tuple(sorted(i for i in self._reported if i not in local))
        self._reported = {i: () for i in now_ids}
        self.ever_seen, self.born_here = (ids & {p.id for p in local} for ids in (self.ever_seen, self.born_here))
        held = {e.id: (e.x, e.y) for es in per_cam.values() for e in es if e.seen}   # seen now: where (m)
        seen_ids, self.together = set(held), held_together(self.together, held, t, self.cfg.crossing_s, held,
                                                           self.cfg.crossing_apart_m)
        absent = self._absent(tracker, tracks, t, cams, boxes, seen_ids) if self.cfg.negative_evidence else {}
        cands, affirms = self.exchange.after_step(tracker, tracks, boxes, cams) if self.exchange else ({}, {})
        same = same_blob_claims({c: self.cameras[c] for c in cams}, tracks, self.state, self.born_here, t,
                                self.cfg.same_blob_s, self.cfg.same_blob_iou)
        rays = camera_rays(self.cameras, tracker, cams, tracks, seen_ids, self.occlusion) if self.cfg.head_rays else {}
        return [Observation(c, float(frames[c].t), self.name, int(frames[c].index), sent, tuple(per_cam[c]), ended,
                            absent.get(c, ()), tuple(cands.get(c, ())), tuple(affirms.get(c, ())),
                            same if c == cams[0] else (), rays.get(c, ())) for c in cams]

    def _absent(self, tracker: Tracker, tracks: Sequence[Track], t: float, cams: list[str],
                boxes: Mapping[str, np.ndarray], seen_ids: set[int]) -> dict[str, tuple[int, ...]]:
        """Per camera, the map's people (not seen by this worker now) whose place the camera shows
        clearly with nobody there (:func:`~worldtrack.map.evidence.looks_empty`; the boxes of the
        people this worker holds explain the foreground they cover)."""
        if self.state is None:
            return {}
        out: dict[str, list[int]] = {}
        dt = min(max(t - self.state.captured, 0.0), 0.5)
        held = [tr.id for tr in tracks]
        for p in self.state.present():
            if p.id in seen_ids or not (math.isfinite(p.height) and math.isfinite(p.width)):
                continue
            xy = np.array([p.x + p.vx * dt, p.y + p.vy * dt])
            others = np.array([k for k, i in enumerate(held) if i != p.id], int)
            for c in cams:
                overlay = tracker.overlay(c) if hasattr(tracker, "overlay") else None
                mask = getattr(overlay, "mask", None)
                if looks_empty(self.cameras[c], mask, xy, p.height, p.width, self.occlusion.get(c),
                               boxes[c][others], min_share=LEAD_SHARE):
                    out.setdefault(c, []).append(p.id)
        return {c: tuple(ids) for c, ids in out.items()}

    def publish(self, observations: Sequence[Observation]) -> None:
        """Append the observations to their cameras' streams (only while this worker holds them)."""
        pipe = self.client.pipeline(transaction=False)
        for o in observations:
            self._xadd(keys=[self.keys.camera_lease(o.camera), self.keys.observations(o.camera)],
                       args=self._xadd_args(o), client=pipe)
        for o, res in zip(observations, pipe.execute()):
            if res == 0 and not self._retake(o):
                holder = self.leases[o.camera].holder()[0]
                raise InputError(f"{o.camera}: this worker lost the camera's lease to {holder}; stopping")
            self.published += 1
            self.last_capture = o.t

    def _retake(self, o: Observation) -> bool:
        """The lease expired while this worker stalled: take it again if nobody else has, and publish."""
        return self.leases[o.camera].acquire() and self._xadd(
            keys=[self.keys.camera_lease(o.camera), self.keys.observations(o.camera)], args=self._xadd_args(o)) != 0

    def _xadd_args(self, o: Observation) -> list[str]:
        """The fenced ``XADD``'s arguments: lease holder, entry id, trim bound, the observation's fields."""
        args = [self.name, f"{stream_id_ms(o.t)}-*", str(stream_id_ms(o.t - self.cfg.retention_s))]
        return args + [v for kv in encode_observation(o).items() for v in kv]


__all__ = ["MapLink", "in_views", "set_epoch"]
