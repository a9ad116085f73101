"""Live mode against a real Redis: a map update published on the map stream moves the person's
element on the page within 1 s; camera status live / stale / down from the map's leases and streams."""

from __future__ import annotations

import json
import time

import numpy as np
import pytest

from _servekit import DOTS_JS, Server, open_page
from worldtrack.map.connection import MapKeys
from worldtrack.map.messages import MapPerson, MapState, encode_map_state, encode_observation, Observation
from worldtrack.scene import load_scene
from worldtrack.serve.plan import PlanTransform

KEYS = MapKeys("worldtrack")


def person(pid: int, x: float, y: float, t: float, mode: str = "tracking") -> MapPerson:
    return MapPerson(pid, x, y, 1.7, 0.45, 0.5, 0.0, 1.0, 0.8, mode, t, t - 5.0, 1, "w1")


def publish(client, t: float, people) -> None:
    """What the fusion role writes: one map-stream entry per bucket (id = bucket start, ms)."""
    state = MapState(t, tuple(people), reports=(("c1", t, t),), written=time.time())
    client.xadd(KEYS.map_stream, encode_map_state(state), id=f"{int(t * 1000)}-0")


@pytest.fixture(scope="module")
def live_server(redis_server, finished_run, browser):
    import redis
    client = redis.Redis(port=redis_server.port, decode_responses=True)
    scene_file = finished_run.parent / "syn" / "scene.yaml"
    server = Server("--map", redis_server.url, "--scene", str(scene_file))
    yield client, server, load_scene(scene_file)
    server.stop()


@pytest.fixture
def live(live_server):
    """The live server on an empty map."""
    live_server[0].flushall()
    return live_server


def wait_position(page, pid: int, uv: np.ndarray, timeout_s: float) -> float:
    """Seconds until person ``pid``'s dot is within a pixel of ``uv`` (SVG units)."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout_s:
        for d in page.evaluate(DOTS_JS):
            if d["id"] == pid and np.hypot(d["u"] - uv[0], d["v"] - uv[1]) < 1.0:
                return time.monotonic() - t0
        time.sleep(0.01)
    raise AssertionError(f"person {pid} did not reach {uv} within {timeout_s} s")


def test_a_map_update_moves_the_person_within_a_second(page, live):
    client, server, scene = live
    transform = PlanTransform.fit(scene)
    now = time.time()
    publish(client, now - 0.2, [person(5, 2.0, 3.0, now - 0.2)])          # before the page opens: backlog
    open_page(page, server.url)
    wait_position(page, 5, transform.to_svg([2.0, 3.0])[0], timeout_s=5.0)
    assert page.locator("#people .person").count() == 1
    delays = []
    for k, (x, y) in enumerate([(6.0, 4.0), (4.5, 6.5), (1.0, 1.0)]):
        t = time.time()
        publish(client, t, [person(5, x, y, t), person(9, 8.0, 2.0, t, mode="lost")])
        delays.append(wait_position(page, 5, transform.to_svg([x, y])[0], timeout_s=3.0))
    print(f"map update -> element moved: {', '.join(f'{d:.3f}' for d in delays)} s")
    assert max(delays) < 1.0, f"page updated {delays} s after the map"
    classes = {d["id"]: d["cls"].split() for d in page.evaluate(DOTS_JS)}
    assert "unmeasurable" in classes[9] and "unmeasurable" not in classes[5]   # lost: drawn differently
    assert page.evaluate("window.worldtrack.state.people.length") == 2
    trail = page.locator('#layer-trails polyline[data-id="5"]').get_attribute("points").split()
    assert len(trail) == 4                                              # 4 states within the 10 s trail


def test_camera_status_live_stale_down(page, live):
    client, server, scene = live
    now = time.time()
    client.hset(KEYS.cameras, mapping={"c1": json.dumps({"fps": 10, "worker": "w1"}),
                                       "c2": json.dumps({"fps": 10, "worker": "w2"})})
    client.set(KEYS.camera_lease("c1"), "w1", px=5000)
    client.xadd(KEYS.observations("c1"), encode_observation(Observation("c1", now, "w1", 1, now)),
                id=f"{int(now * 1000)}-0")
    client.xadd(KEYS.observations("c2"), encode_observation(Observation("c2", now - 2.5, "w2", 1, now - 2.5)),
                id=f"{int((now - 2.5) * 1000)}-0")
    open_page(page, server.url)
    page.wait_for_function("""() => [...document.querySelectorAll('#camera-table tbody tr')]
        .map(r => r.cells[1].textContent).join(',') === 'live,stale'""", timeout=5000)
    lag_ms = float(page.locator("#camera-table tbody tr").nth(1).locator("td").nth(2).inner_text().split()[0])
    assert 2400 < lag_ms < 2500 + 2000                                   # c2's last frame is 2.5 s old
    assert page.locator('g.camera[data-camera="c1"] .camera-ring').get_attribute("class").split()[-1] == "live"
    client.delete(KEYS.camera_lease("c1"))
    page.wait_for_function("""() => document.querySelector('#camera-table tbody tr').cells[1].textContent
        === 'stale'""", timeout=5000)                                  # nobody holds c1 any more
    page.wait_for_function("""() => document.querySelectorAll('#camera-table tbody tr')[1].cells[1].textContent
        === 'down'""", timeout=6000)                                   # c2: nothing for 5 s


def test_a_reader_behind_the_map_skips_to_the_newest(redis_server, finished_run):
    """Twenty states written at once (2 s of map): the page gets the last 0.5 s of them, not the past."""
    import redis

    from worldtrack.serve.live import CATCH_UP_S, LiveMap
    client = redis.Redis(port=redis_server.port, decode_responses=True)
    client.flushall()
    got: list[dict] = []
    live = LiveMap(client, KEYS, load_scene(finished_run.parent / "syn" / "scene.yaml"),
                   lambda text: got.append(json.loads(text)), status_every_s=60)
    live.start()
    try:
        time.sleep(0.3)                                       # the reader waits on the stream
        t0 = time.time()
        pipe = client.pipeline(transaction=True)
        for k in range(20):
            t = t0 + 0.1 * k
            pipe.xadd(KEYS.map_stream, encode_map_state(MapState(t, (person(1, 1.0 + 0.1 * k, 2.0, t),))),
                      id=f"{int(t * 1000)}-0")
        pipe.execute()
        deadline = time.monotonic() + 5
        while time.monotonic() < deadline and not any(m["type"] == "state" and m["t"] >= t0 + 1.85 for m in got):
            time.sleep(0.05)
    finally:
        live.stop()
    states = [m["t"] - t0 for m in got if m["type"] == "state"]
    assert states and abs(states[-1] - 1.9) < 1e-3
    assert min(states) >= 1.9 - CATCH_UP_S - 1e-3 and len(states) == 6 and live.skipped == 14
