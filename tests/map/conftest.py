"""A real Redis server for the shared-map tests: started on a free 127.0.0.1 port, stopped after.

``make test`` installs Debian's ``redis-server`` (and ``ffmpeg``) when they are missing; without
them these tests are skipped with one line saying so.
"""

from __future__ import annotations

import pytest

from _mapkit import RedisServer


@pytest.fixture(scope="session")
def redis_server(tmp_path_factory):
    pytest.importorskip("redis")
    server = RedisServer(tmp_path_factory.mktemp("redis"))
    yield server
    server.stop()


@pytest.fixture
def redis_url(redis_server):
    """An empty database on the session's server."""
    import redis
    redis.Redis(port=redis_server.port).flushall()
    return redis_server.url


@pytest.fixture(scope="session")
def two_rooms(tmp_path_factory):
    """The two-rooms scenario (seed 1, 320x240, 10 fps; the second person sets off 6 s after the first, so
    they do not meet in the door) written as videos with ground truth."""
    from worldtrack.synth import make_scenario, write_sequence
    out = tmp_path_factory.mktemp("two_rooms")
    write_sequence(make_scenario("two-rooms", seed=1, stagger=6.0), out, progress=False)
    return out


