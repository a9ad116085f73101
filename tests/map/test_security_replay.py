"""Credentials (ACL user and password from the URL or the environment, never printed), the scene
check, replay by time and retention by MINID — on a real Redis server."""

from __future__ import annotations

import json
import time

import numpy as np
import pytest
import yaml

from _mapkit import RedisServer
from worldtrack.cli import main
from worldtrack.errors import InputError
from worldtrack.io.tracks import read_tracks
from worldtrack.map.config import MapConfig
from worldtrack.map.connection import MapKeys, claim_scene, connect
from worldtrack.map.fusion_role import FusionRole
from worldtrack.map.simulate import Publishers, SimulatedFloor

SECRET = "s3cret-Pa55"


@pytest.fixture(scope="module")
def acl_server(tmp_path_factory):
    pytest.importorskip("redis")
    server = RedisServer(tmp_path_factory.mktemp("acl"), extra=("--requirepass", "admin-pw"))
    import redis
    admin = redis.Redis(port=server.port, password="admin-pw")
    admin.execute_command("ACL", "SETUSER", "tracker", "on", f">{SECRET}", "~*", "+@all")
    yield server
    server.stop()


def test_acl_user_from_url_or_environment_and_the_password_is_never_shown(acl_server, monkeypatch, capsys):
    url = f"redis://tracker:{SECRET}@127.0.0.1:{acl_server.port}/0"
    assert connect(url).ping()
    monkeypatch.setenv("WORLDTRACK_REDIS_USER", "tracker")
    monkeypatch.setenv("WORLDTRACK_REDIS_PASSWORD", SECRET)
    assert connect(f"redis://127.0.0.1:{acl_server.port}/0").ping()
    monkeypatch.setenv("WORLDTRACK_REDIS_PASSWORD", "wrong")
    assert main(["map", "status", f"redis://127.0.0.1:{acl_server.port}/0"]) == 2
    assert main(["map", "status", f"redis://tracker:also-{SECRET}@127.0.0.1:{acl_server.port}/0"]) == 2
    monkeypatch.delenv("WORLDTRACK_REDIS_PASSWORD")
    monkeypatch.delenv("WORLDTRACK_REDIS_USER")
    assert main(["map", "status", f"redis://127.0.0.1:{acl_server.port}/0"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[0].startswith(f"error: redis://127.0.0.1:{acl_server.port}/0: the server refused user 'tracker'")
    assert err[1] == (f"error: redis://tracker:***@127.0.0.1:{acl_server.port}/0: the server refused user 'tracker' "
                      f"and its password (give them in the URL or in WORLDTRACK_REDIS_USER/WORLDTRACK_REDIS_PASSWORD)")
    assert "wants a password" in err[2] and len(err) == 3
    assert all(SECRET not in line for line in err)


def test_a_worker_refuses_a_map_of_another_scene_and_run_yaml_hides_the_password(acl_server, tmp_path, capsys):
    from worldtrack.synth import make_scenario, write_sequence
    url = f"redis://tracker:{SECRET}@127.0.0.1:{acl_server.port}/3"
    client = connect(url)
    client.flushdb()
    claim_scene(client, MapKeys(), "0" * 64, "elsewhere")
    seq = tmp_path / "seq"
    write_sequence(make_scenario("two-rooms", size=(160, 120), frames=3, seed=0), seq, png=True, progress=False)
    args = ["track", str(seq / "scene.yaml"), "--map", url, "--cameras", "west", "--video", f"west={seq / 'west'}",
            "--out", str(tmp_path / "out"), "--quiet", "--no-video"]
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"error: redis://tracker:***@127.0.0.1:{acl_server.port}/3 (prefix "
                                               f"'worldtrack') belongs to scene 'elsewhere' (sha256 000000000000…), "
                                               f"not this scene 'two-rooms'")
    # The right map: the run records its command line without the password.
    client.flushdb()
    main(args[:-2] + ["--frames", "2", "--no-video", "--set", "map.pace_files=false"])
    info = (tmp_path / "out" / "run.yaml").read_text()
    assert SECRET not in info and "tracker:***@" in info
    assert yaml.safe_load(info)["inputs"]["map"] == f"redis://tracker:***@127.0.0.1:{acl_server.port}/3"
    err = capsys.readouterr().err
    assert SECRET not in err
    # An ACL user without pub/sub channels: the map is written, the update channel left out, said once.
    assert err.count("may not publish to worldtrack:map:updates") == 1 and "Traceback" not in err


def _run_fusion(client, cfg, seconds, until_map_t=None, patience_s=30.0):
    """Run the fusion role for `seconds`, and on past them (up to `patience_s` more) until the map
    stream holds a state at or after `until_map_t` (a loaded machine lags the fusion behind)."""
    role = FusionRole(client, MapKeys(), cfg, "fuser")
    t_end = time.time() + seconds
    t_give_up = t_end + patience_s

    def behind():
        if until_map_t is None:
            return False
        last = client.xrevrange(MapKeys().map_stream, count=1)
        return not last or float(last[0][1]["t"]) < until_map_t

    while time.time() < t_end or (behind() and time.time() < t_give_up):
        if not role.holding:
            assert role.lease.acquire()
            role._take_over()
        role.step(block_ms=10)
    role.drain()
    role.lease.release()


def test_replay_by_time_range_and_streams_trimmed_by_retention(redis_url, tmp_path, capsys):
    client = connect(redis_url)
    cfg = MapConfig(retention_s=1.0)
    pubs = Publishers(client, MapKeys(), cfg, SimulatedFloor(2, 2, np.random.default_rng(2))).start()
    t0 = time.time()
    try:
        _run_fusion(client, cfg, 3.0, until_map_t=t0 + 2.5)
    finally:
        pubs.stop()
    keys = MapKeys()
    first_obs = float(client.xrange(keys.observations("sim000"), count=1)[0][1]["t"])
    first_map = float(client.xrange(keys.map_stream, count=1)[0][1]["t"])
    assert first_obs > t0 + 1.0 and first_map > t0 + 1.0        # older entries trimmed (MINID, ~1 s kept)
    t_from, t_to = first_map + 0.3, first_map + 0.75
    assert main(["replay", redis_url, "--from", repr(t_from), "--to", repr(t_to), "--out", str(tmp_path / "r")]) == 0
    table = read_tracks(tmp_path / "r" / "tracks.csv")
    assert sorted(set(table.frame.tolist())) == [0, 1, 2, 3, 4] and set(table.id.tolist()) == {1, 2, 3, 4}
    assert np.allclose(np.unique(table.time), np.arange(5) * 0.1)
    assert main(["replay", redis_url, "--from=-1h", "--to=-30m", "--out", str(tmp_path / "none")]) == 2
    assert "no map states between -1h and -30m" in capsys.readouterr().err
    assert main(["replay", redis_url, "--from", "yesterday"]) == 2
    assert "'yesterday': expected a time as Unix seconds" in capsys.readouterr().err
