"""The fusion lease lapsing under load, reproduced by hand on a real Redis server: the holder's
lease key expires mid-step (another process takes the role and writes), or lapses with nobody
taking it; whoever holds the role next continues after the last bucket in the record — never
from its first bucket — no bucket is written twice and no observation is left out. A step does a
bounded amount of work and renews the lease between buckets; Ctrl-C on a holder with a backlog
gives the role back within the drain's bound and leaves the record whole."""

from __future__ import annotations

import json
import signal
import subprocess
import time
from collections import Counter

import pytest

import worldtrack.map.fusion_role as fusion_role
from _mapkit import WORLDTRACK, wait_until
from worldtrack.map.config import MapConfig
from worldtrack.map.connection import MapKeys, connect
from worldtrack.map.fusion_role import DRAIN_S, MAX_BUCKETS_PER_STEP, FusionRole
from worldtrack.map.messages import (Estimate, Observation, bucket_index, decode_map_state, encode_observation,
                                     stream_id_ms)

CAMERAS = ("west", "east")


def _floor(client, keys) -> int:
    """Two live cameras (leases held for the test); returns the bucket to publish from: now (a holder
    with no record starts reading COLD_START_S back, so a loaded machine cannot make it skip some)."""
    for cam in CAMERAS:
        client.hset(keys.cameras, cam, json.dumps({"fps": 10.0, "worker": f"w-{cam}"}))
        client.set(keys.camera_lease(cam), f"w-{cam}", px=120_000)
    return bucket_index(time.time(), 0.1)


def _publish(client, keys, buckets, people: int = 2, extra: int | None = None) -> None:
    for b in buckets:
        for k, cam in enumerate(CAMERAS):
            t = (b + 0.5) * 0.1
            est = tuple(Estimate(1 + k * people + j, 2.0 * k + 0.01 * (b % 50), 1.0 + j, 1.7, 0.45, 0.1, 0.0,
                                 0.8, 0.7, True) for j in range(people))
            if extra is not None and k == 1:
                est += (Estimate(extra, 6.0, 3.0, 1.7, 0.45, 0.0, 0.0, 0.8, 0.7, True),)
            o = Observation(cam, t, f"w-{cam}", b, t, est)
            client.xadd(keys.observations(cam), encode_observation(o), id=f"{stream_id_ms(t)}-*")


def _record(client, keys):
    return [decode_map_state(f) for _, f in client.xrange(keys.map_stream)]


def _check_whole(client, keys, first: int, last: int) -> None:
    """One state per bucket first..last, each observation in exactly one of them, none late."""
    states = _record(client, keys)
    assert [bucket_index(s.t + 0.05, 0.1) for s in states] == list(range(first, last + 1))
    reported = Counter((c, round(t, 3)) for s in states for c, t, _ in s.reports)
    published = {(cam, round((b + 0.5) * 0.1, 3)) for cam in CAMERAS for b in range(first, last + 1)}
    assert set(reported) == published and max(reported.values()) == 1
    assert sum(s.late for s in states) == 0
    assert all(len(s.present()) >= 4 for s in states)


def _steps(role, until, limit=200):
    for _ in range(limit):
        if until():
            return
        role.step(block_ms=0)
    raise AssertionError(f"{role.owner} did not get there: last bucket {role.state.last_bucket}, "
                         f"open {sorted(role._buckets)[:3]}, holding {role.holding}")


def test_a_lapsed_fusion_lease_continues_after_the_records_last_bucket(redis_url):
    # Leases long enough that only the test makes them lapse (by deleting the key, as expiry does).
    client, keys, cfg = connect(redis_url), MapKeys(), MapConfig(lease_s=60.0, renew_s=5.0)
    b0 = _floor(client, keys)
    lines = []
    a = FusionRole(client, keys, cfg, "A", log=lambda s: lines.append("A " + s))
    b = FusionRole(client, keys, cfg, "B", log=lambda s: lines.append("B " + s))
    _publish(client, keys, range(b0, b0 + 25))
    assert a.lease.acquire()
    a._take_over()
    assert a.step(block_ms=0) <= MAX_BUCKETS_PER_STEP             # a backlog is worked off in bounded steps
    _steps(a, lambda: client.xlen(keys.map_stream) == 25)

    # 1. A's lease lapses mid-run and B takes the role and writes 10 buckets.
    client.delete(keys.fusion_lease)
    _publish(client, keys, range(b0 + 25, b0 + 35))
    assert b.lease.acquire()
    b._take_over()
    _steps(b, lambda: client.xlen(keys.map_stream) == 35)
    # A, not knowing yet, steps on: its write is fenced (and its renewal fails): nothing written.
    a._renewed = -1e9
    a.step(block_ms=0)
    assert not a.holding and client.xlen(keys.map_stream) == 35

    # 2. B dies; A takes the role again: it continues after B's last bucket, not after its own —
    #    from the record even when the state B left beside it is gone (the hash deleted).
    client.delete(keys.fusion_lease, keys.current)
    _publish(client, keys, range(b0 + 35, b0 + 45))
    assert a.lease.acquire()
    a._take_over()
    assert a.state.last_bucket == b0 + 34
    _steps(a, lambda: client.xlen(keys.map_stream) == 45)

    # 3. A's lease lapses and nobody takes it: A takes it again and goes on with what it holds.
    client.delete(keys.fusion_lease)
    _publish(client, keys, range(b0 + 45, b0 + 50))
    a._renewed = -1e9
    _steps(a, lambda: client.xlen(keys.map_stream) == 50)
    assert a.stats.retaken == 1 and a.holding

    # 4. A lapses, B takes the role and writes, B dies, and A's lease keeper takes the free lease
    #    back without a take-over (it only renews): A's next write finds its bucket in the record
    #    and A continues after the record's last bucket instead of writing it again.
    client.delete(keys.fusion_lease)
    _publish(client, keys, range(b0 + 50, b0 + 60), extra=99)      # somebody only B's buckets hold
    assert b.lease.acquire()
    b._take_over()
    _steps(b, lambda: client.xlen(keys.map_stream) == 60)
    client.delete(keys.fusion_lease)
    assert a.lease.acquire()
    _publish(client, keys, range(b0 + 60, b0 + 70))
    _steps(a, lambda: client.xlen(keys.map_stream) == 70)
    assert any("already in the record" in s for s in lines)
    after_b = _record(client, keys)[60]                 # A's first bucket after B's: from B's state
    assert [p.mode for p in after_b.people if p.id == 99] == ["lost"]

    _check_whole(client, keys, b0, b0 + 69)
    assert sum("from its first bucket" in s for s in lines) == 1, lines      # only A's very first take-over
    assert "holder" in client.hgetall(keys.current)


def test_a_slow_step_renews_its_lease_between_buckets_and_stops_writing_once_it_is_taken(redis_url, monkeypatch):
    client, keys, cfg = connect(redis_url), MapKeys(), MapConfig(lease_s=2.0, renew_s=0.25)
    b0 = _floor(client, keys)
    _publish(client, keys, range(b0, b0 + 30))
    a = FusionRole(client, keys, cfg, "A")
    fuse, calls = fusion_role.fuse_bucket, []

    def slow_fuse(*args, **kwargs):              # a loaded machine: each bucket takes 0.4 s
        calls.append(args[1])
        time.sleep(0.4)
        return fuse(*args, **kwargs)
    monkeypatch.setattr(fusion_role, "fuse_bucket", slow_fuse)
    assert a.lease.acquire()
    a._take_over()
    written = a.step(block_ms=0)                     # 10 buckets, 4 s: 2 lease lengths, no keeper thread
    assert written == MAX_BUCKETS_PER_STEP and a.holding and client.get(keys.fusion_lease) == "A"

    def taken_mid_step(*args, **kwargs):             # 2 buckets into the step, B takes the role
        if len(calls) == 12:
            client.set(keys.fusion_lease, "B", px=10_000)
        return slow_fuse(*args, **kwargs)
    monkeypatch.setattr(fusion_role, "fuse_bucket", taken_mid_step)
    a.step(block_ms=0)
    assert not a.holding and client.xlen(keys.map_stream) == 12       # A wrote nothing after
    monkeypatch.setattr(fusion_role, "fuse_bucket", fuse)
    # "B" is gone without writing: A takes the role again and goes on with the buckets it holds.
    client.delete(keys.fusion_lease)
    assert a.lease.acquire()
    a._take_over()
    assert a.stats.retaken == 1 and a.state.last_bucket == b0 + 11
    _steps(a, lambda: client.xlen(keys.map_stream) == 30)
    _check_whole(client, keys, b0, b0 + 29)


@pytest.mark.slow
def test_ctrl_c_on_a_fusion_holder_with_a_backlog_gives_the_role_back_within_the_drain_bound(redis_url, tmp_path):
    client, keys, cfg = connect(redis_url), MapKeys(), MapConfig()
    # The backlog is in the streams before the fuser starts: 300 s of two cameras with 40 people each
    # (capture times from 30 s ahead, so the fuser's cold start, 5 s before it takes the role, reads
    # them all), far more than the drain bound lets it fuse (with 60 s an idle machine fused it all
    # before the signal and left the next holder nothing to continue with).
    b0, n = _floor(client, keys) + 300, 3000
    _publish(client, keys, range(b0, b0 + n), people=40)
    log = open(tmp_path / "fuser.log", "w")
    p = subprocess.Popen([*WORLDTRACK, "map", "fuse", redis_url], stdout=subprocess.DEVNULL, stderr=log)
    try:
        wait_until(lambda: client.xlen(keys.map_stream) >= 1, 120, every=0.01, what="the fuser's first bucket")
        p.send_signal(signal.SIGINT)
        sent = time.monotonic()
        rc = p.wait(30)
        took = time.monotonic() - sent
    finally:
        p.kill()
    text = (tmp_path / "fuser.log").read_text()
    written = client.xlen(keys.map_stream)
    print(f"exit {rc} {took:.2f} s after SIGINT; {written} of {n} buckets written")
    assert rc == 130 and "interrupted" in text and "Traceback" not in text, text
    assert took < DRAIN_S + 3.0 and written < n, text
    assert client.get(keys.fusion_lease) is None                    # given back, not left to expire
    # What it wrote is whole, and a next holder continues right after it.
    role = FusionRole(client, keys, cfg, "next")
    assert role.lease.acquire()
    role._take_over()
    assert role.state.last_bucket == b0 + written - 1
    _steps(role, lambda: client.xlen(keys.map_stream) >= written + 20)
    states = _record(client, keys)
    assert [bucket_index(s.t + 0.05, 0.1) for s in states] == list(range(b0, b0 + len(states)))
    reported = Counter((c, round(t, 3)) for s in states for c, t, _ in s.reports)
    assert len(reported) == 2 * len(states) and max(reported.values()) == 1 and sum(s.late for s in states) == 0
