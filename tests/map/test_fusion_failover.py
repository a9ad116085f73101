"""The fusion role on a real Redis server: killed with SIGKILL, another process takes it over
within 2 s and every observation in the streams reaches the map; leases and fencing."""

from __future__ import annotations

import json
import signal
import subprocess
import time

import numpy as np
import pytest

from _mapkit import WORLDTRACK, wait_until
from worldtrack.map.config import MapConfig
from worldtrack.map.connection import MapKeys, connect
from worldtrack.map.lease import FENCED_XADD, Lease, LeaseKeeper, acquire_all
from worldtrack.map.messages import decode_map_state, decode_observation
from worldtrack.map.simulate import Publishers, SimulatedFloor


def _fuser(url: str, log) -> subprocess.Popen:
    return subprocess.Popen([*WORLDTRACK, "map", "fuse", url], stdout=subprocess.DEVNULL, stderr=log)


@pytest.mark.slow
def test_killed_fusion_holder_is_replaced_within_2_s_and_nothing_is_lost(redis_url, tmp_path):
    client = connect(redis_url)
    keys, cfg = MapKeys(), MapConfig()
    log = open(tmp_path / "fusers.log", "w")
    first = _fuser(redis_url, log)
    holder = wait_until(lambda: client.get(keys.fusion_lease), 60, what="the first fusion holder")
    second = _fuser(redis_url, log)
    # The standby is up (imports done, connected) before the holder dies: on a loaded machine its
    # start-up alone can outlast the test's 2 s of publishing.
    wait_until(lambda: (tmp_path / "fusers.log").read_text().count("contending for the fusion role") == 2, 120,
               what="the standby fusion process")
    pubs = Publishers(client, keys, cfg, SimulatedFloor(4, 3, np.random.default_rng(0))).start()
    try:
        time.sleep(2.0)
        first.send_signal(signal.SIGKILL)
        killed = time.time()
        new = wait_until(lambda: (lambda h: h if h and h != holder else None)(client.get(keys.fusion_lease)), 5.0,
                         every=0.01, what="a new fusion holder")
        took = time.time() - killed
        time.sleep(2.0)
    finally:
        pubs.stop()
        time.sleep(cfg.max_wait_s + 0.5)         # the last buckets
        second.send_signal(signal.SIGINT)
        try:
            second.wait(10)                      # the drain is bounded (DRAIN_S)
        finally:
            for p in (first, second):            # a fuser left running would hold the role in the next test
                p.kill()
                p.wait()
    print(f"fusion taken over {took:.2f} s after SIGKILL")
    assert took < 2.0 and new != holder
    assert second.returncode == 130, (tmp_path / "fusers.log").read_text()[-800:]
    states = [decode_map_state(f) for _, f in client.xrange(keys.map_stream)]
    reported = {(c, round(t, 3)) for s in states for c, t, _ in s.reports}
    published = {(o.camera, round(o.t, 3)) for cam in pubs.cams
                 for o in (decode_observation(f) for _, f in client.xrange(keys.observations(cam)))}
    assert len(published) >= 4 * 10 * 3.5 and published <= reported       # every observation reached the map
    assert sum(s.late for s in states) == 0
    times = np.array([s.t for s in states])
    assert np.allclose(np.diff(times), cfg.bucket_s)                      # one state per bucket, none missing
    assert all(len(s.present()) == 12 for s in states)                      # nobody lost or duplicated
    assert {p.id for p in states[-1].people} == set(range(1, 13))


def test_a_lease_is_held_by_one_owner_and_fences_its_writes(redis_url):
    client = connect(redis_url)
    a = Lease(client, "t:lease", "a", 0.3)
    b = Lease(client, "t:lease", "b", 0.3)
    assert a.acquire() and not b.acquire() and a.holder()[0] == "a"
    xadd = client.register_script(FENCED_XADD)
    assert xadd(keys=["t:lease", "t:s"], args=["b", "1000-*", "", "f", "1"]) == 0          # not b's to write
    assert xadd(keys=["t:lease", "t:s"], args=["a", "1000-*", "", "f", "1"]) == "1000-0"
    assert xadd(keys=["t:lease", "t:s"], args=["a", "900-*", "", "f", "2"]) == -1          # not after the last
    time.sleep(0.35)
    assert b.acquire() and not a.renew() and a.holder()[0] == "b"
    assert not acquire_all([Lease(client, "t:free", "a", 1.0), a]) and client.get("t:free") is None
    lost = []
    keeper = LeaseKeeper([b], 0.05, lost.append)
    keeper.start()
    time.sleep(0.5)                                  # renewed past its 0.3 s
    assert b.holder()[0] == "b" and not lost
    client.set("t:lease", "c")                       # taken from under it
    time.sleep(0.2)
    keeper.stop(release=True)
    assert lost == [b] and client.get("t:lease") == "c"


def test_status_names_workers_cameras_leases_and_people(redis_url, capsys):
    from worldtrack.cli import main
    client = connect(redis_url)
    keys, cfg = MapKeys(), MapConfig()
    pubs = Publishers(client, keys, cfg, SimulatedFloor(2, 2, np.random.default_rng(1)), name="simhost:1").start()
    client.hset(keys.workers, "simhost:1", json.dumps({"cameras": ["sim000", "sim001"], "state": "tracking",
                                                       "fusion": False, "frames": 12, "t": time.time()}))
    try:
        assert main(["map", "fuse", redis_url, "--seconds", "1.5"]) == 0
        assert main(["map", "status", redis_url]) == 0
    finally:
        pubs.stop()
    out = capsys.readouterr().out
    assert "simhost:1: tracking, cameras sim000,sim001, 12 frames" in out
    assert "sim000: held by simhost:1 (" in out and "observations, lag" in out
    assert "people: 4 present, 0 lost" in out and "fusion: free" in out
