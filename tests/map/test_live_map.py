"""The live map on a real Redis server: updated as soon as one worker's observation comes, not
when the slowest worker has reported; the record (the map stream) waits for the bucket."""

from __future__ import annotations

import json
import time
from contextlib import contextmanager

from _mapkit import wait_until
from worldtrack.map.config import MapConfig
from worldtrack.map.connection import MapKeys, connect
from worldtrack.map.fusion_role import FusionRole, run_fusion_thread
from worldtrack.map.messages import (Estimate, Observation, bucket_index, decode_map_state, encode_observation,
                                     stream_id_ms)
from worldtrack.map.starved import name_connection
from worldtrack.map.worker import MapLink


def _publish(client, keys, camera: str, t: float, pid: int, x: float) -> None:
    e = Estimate(pid, x, 1.0, 1.7, 0.45, 0.0, 0.0, 0.8, 0.7, True)
    o = Observation(camera, t, f"w-{camera}", 0, time.time(), (e,))
    client.xadd(keys.observations(camera), encode_observation(o), id=f"{stream_id_ms(t)}-*")


def _live_people(client, keys) -> dict[int, tuple[float, str]]:
    raw = client.hmget(keys.current, ["map_people", "t"])
    if raw[0] is None:
        return {}
    state = decode_map_state({"v": "2", "t": raw[1], "people": raw[0]})
    return {p.id: (p.x, p.mode) for p in state.people}


@contextmanager
def _fusing(client, keys, cfg):
    """The fusion role running in a thread of this process (stopped on leaving); yields the middle
    of the bucket now beginning (s), the time to publish the first observations at."""
    role = FusionRole(client, keys, cfg, "fuser")
    thread, stop = run_fusion_thread(role)
    try:
        wait_until(lambda: role.holding, 10, what="the fusion role")
        yield (bucket_index(time.time(), cfg.bucket_s) + 0.5) * cfg.bucket_s
    finally:
        stop.set()
        thread.join(10)


def test_a_slow_worker_delays_only_its_own_people(redis_url):
    client = connect(redis_url)
    keys, cfg = MapKeys(), MapConfig(max_wait_s=3.0)
    for cam in ("fast", "slow"):     # two live cameras: a bucket is complete when both have reported
        client.hset(keys.cameras, cam, json.dumps({"fps": 10.0, "worker": f"w-{cam}"}))
        client.set(keys.camera_lease(cam), f"w-{cam}", px=30000)
    updates = client.pubsub(ignore_subscribe_messages=True)
    updates.subscribe(keys.updates)
    with _fusing(client, keys, cfg) as t0:
        _publish(client, keys, "fast", t0, 1, 2.0)
        _publish(client, keys, "slow", t0, 2, 6.0)
        wait_until(lambda: client.xlen(keys.map_stream) == 1, 10, what="the first complete bucket")
        # The next bucket: only the fast camera reports. Its person moves on the live map at once,
        # long before the bucket is complete or max_wait_s (3 s) has passed; the slow camera's
        # person stays where they were, present.
        sent = time.time()
        _publish(client, keys, "fast", t0 + 0.1, 1, 2.1)
        wait_until(lambda: _live_people(client, keys).get(1, (0, ""))[0] == 2.1, 2.0, every=0.005,
                   what="the fast worker's report on the live map")
        took = time.time() - sent
        assert _live_people(client, keys)[2] == (6.0, "tracking")
        assert client.xlen(keys.map_stream) == 1            # the record waits for the slow camera
        message = wait_until(lambda: updates.get_message(timeout=0.1), 2.0, what="updates")
        assert decode_map_state(json.loads(message["data"])).reports
        # The slow camera's report refines the same bucket and completes it.
        _publish(client, keys, "slow", t0 + 0.1, 2, 6.1)
        wait_until(lambda: client.xlen(keys.map_stream) == 2, 2.0, what="the second complete bucket")
        last = decode_map_state(client.xrevrange(keys.map_stream, count=1)[0][1])
        assert {p.id: p.x for p in last.present()} == {1: 2.1, 2: 6.1}
    print(f"the fast worker's report was on the live map {took * 1000:.0f} ms after it was published")
    assert took < 1.0


def test_a_bucket_waits_for_a_batch_workers_report_past_max_wait_s(redis_url):
    """A batch worker (video files read as fast as it can, registered with ``lockstep``) is waited
    for however late its report comes while its lease lives: the record of a batch run must not
    depend on the machine's load (issue-39j). A live camera is not (a slow worker delays only its
    own people), and a batch camera whose lease lapsed (its worker died) is not either."""
    client = connect(redis_url)
    keys, cfg = MapKeys(), MapConfig(max_wait_s=0.2)
    for cam, batch in (("first", True), ("late", True), ("live", False)):
        link = MapLink(client, keys, cfg, f"w-{cam}", {cam: None})
        link.lockstep = batch                   # as `worldtrack track` sets it (map.pace_files=false, files)
        link.register()
        client.set(keys.camera_lease(cam), f"w-{cam}", px=30000)
    with _fusing(client, keys, cfg) as t0:
        _publish(client, keys, "first", t0, 1, 2.0)
        _publish(client, keys, "live", t0, 3, 9.0)
        time.sleep(5 * cfg.max_wait_s)
        assert client.xlen(keys.map_stream) == 0            # still waiting for the late batch camera
        _publish(client, keys, "late", t0, 2, 6.0)
        wait_until(lambda: client.xlen(keys.map_stream) == 1, 5.0, what="the bucket with the late report")
        first = decode_map_state(client.xrange(keys.map_stream)[0][1])
        assert sorted(c for c, _, _ in first.reports) == ["first", "late", "live"] and first.late == 0
        # The next bucket: the batch cameras report, the live one does not: written after max_wait_s.
        _publish(client, keys, "first", t0 + 0.1, 1, 2.1)
        _publish(client, keys, "late", t0 + 0.1, 2, 6.1)
        wait_until(lambda: client.xlen(keys.map_stream) == 2, 5.0, what="the bucket without the live camera")
        # The next: the late batch worker's lease lapses (it died): written without it.
        _publish(client, keys, "first", t0 + 0.2, 1, 2.2)
        _publish(client, keys, "live", t0 + 0.2, 3, 9.2)
        time.sleep(5 * cfg.max_wait_s)
        assert client.xlen(keys.map_stream) == 2
        client.delete(keys.camera_lease("late"))
        wait_until(lambda: client.xlen(keys.map_stream) == 3, 5.0, what="the bucket after the lease lapsed")


def test_a_holder_that_stops_leaves_a_bucket_a_live_batch_worker_has_not_reported_to_it(redis_url):
    """The last frames of a batch run: the worker that finishes first gives the fusion role back
    (drain). A bucket the other batch worker, still running (its lease lives), has not reported yet
    is left in the streams for it (it takes the role over), not written without its report; once
    that worker's lease is gone (it died or finished) the bucket is written."""
    client = connect(redis_url)
    keys, cfg = MapKeys(), MapConfig(max_wait_s=0.1)
    for cam in ("done", "going"):
        link = MapLink(client, keys, cfg, f"w-{cam}", {cam: None})
        link.lockstep = True
        link.register()
        client.set(keys.camera_lease(cam), f"w-{cam}", px=30000)
    role = FusionRole(client, keys, cfg, "fuser")
    assert role.lease.acquire()
    role._take_over()
    t0 = (bucket_index(time.time(), cfg.bucket_s) + 0.5) * cfg.bucket_s
    _publish(client, keys, "done", t0, 1, 2.0)
    _publish(client, keys, "going", t0, 2, 6.0)
    _publish(client, keys, "done", t0 + 0.1, 1, 2.1)       # its last frame; "going" has not reported it
    wait_until(lambda: role.step(block_ms=10) or client.xlen(keys.map_stream) == 1, 5.0, what="the first bucket")
    role.drain(budget_s=1.0)
    assert client.xlen(keys.map_stream) == 1                # the complete bucket only
    client.delete(keys.camera_lease("going"))
    role.drain(budget_s=1.0)
    assert client.xlen(keys.map_stream) == 2
    last = decode_map_state(client.xrevrange(keys.map_stream, count=1)[0][1])
    assert [c for c, _, _ in last.reports] == ["done"]


def _batch_pair_with_a_lapsed_lease(redis_url, client, keys, cfg, lapsed: str):
    """Two batch workers, ``w-first`` (camera ``first``, its lease held) and ``w-<lapsed>`` (camera
    ``lapsed``, no lease: it lapsed); returns the latter's own connection, named after it."""
    for cam in ("first", lapsed):
        link = MapLink(client, keys, cfg, f"w-{cam}", {cam: None})
        link.lockstep = True
        link.register()
    client.set(keys.camera_lease("first"), "w-first", px=30000)
    own = connect(redis_url)
    assert name_connection(own, f"w-{lapsed}")
    return own


def test_a_batch_worker_whose_lease_lapsed_is_waited_for_while_it_is_still_connected(redis_url):
    """A batch worker starved of CPU (its lease-renewing thread did not run for ``lease_s``) is alive:
    its connection to Redis, named after it, is open, and the bucket waits for its report; a dead
    worker's connection is closed, and the bucket is written without it (worldtrack.map.starved)."""
    client = connect(redis_url)
    keys, cfg = MapKeys(), MapConfig(max_wait_s=0.2, starved_wait_s=30.0)
    starved = _batch_pair_with_a_lapsed_lease(redis_url, client, keys, cfg, "starved")
    with _fusing(client, keys, cfg) as t0:
        _publish(client, keys, "first", t0, 1, 2.0)
        time.sleep(5 * cfg.max_wait_s)
        assert client.xlen(keys.map_stream) == 0            # waiting: its worker is still connected
        _publish(client, keys, "starved", t0, 2, 6.0)
        wait_until(lambda: client.xlen(keys.map_stream) == 1, 5.0, what="the bucket with the starved report")
        assert decode_map_state(client.xrange(keys.map_stream)[0][1]).late == 0
        starved.connection_pool.disconnect()                 # the worker died: its connection closed
        _publish(client, keys, "first", t0 + 0.1, 1, 2.1)
        wait_until(lambda: client.xlen(keys.map_stream) == 2, 5.0, what="the bucket after the worker died")


def test_a_connected_batch_worker_whose_lease_lapsed_is_waited_for_at_most_starved_wait_s(redis_url):
    client = connect(redis_url)
    keys, cfg = MapKeys(), MapConfig(max_wait_s=0.1, starved_wait_s=1.0)
    hung = _batch_pair_with_a_lapsed_lease(redis_url, client, keys, cfg, "hung")
    with _fusing(client, keys, cfg) as t0:
        sent = time.time()
        _publish(client, keys, "first", t0, 1, 2.0)
        wait_until(lambda: client.xlen(keys.map_stream) == 1, 10.0, what="the bucket without the hung worker")
        took = time.time() - sent
    hung.connection_pool.disconnect()
    assert 0.8 < took < 5.0, took
