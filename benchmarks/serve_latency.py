"""How fast does ``worldtrack serve --map`` show a map update, with many people on the map?

Question (issue 40): the page must show a map update within 1 s. With N people on the map and a
map state every 0.1 s (the map's default bucket), how long from the fusion writing a state to
(a) a websocket client of the server receiving it and (b) a real browser (Debian's chromium through
Playwright) having drawn it? And how many states a second can the server push at most?

Set-up: our own redis-server; ``worldtrack serve --map`` as its own process pinned to core 1
(``taskset``); this script publishes map states (people random-walking in the scene
``examples/scenes/office_4cams.yaml``) as the fusion role writes them (``XADD`` to the map
stream, ``written`` = wall clock just before). Reference measured in the same run: a plain Redis
reader (``XREAD BLOCK`` on the same stream, in this process) — the floor no server can beat; the
ratio is serve / reference. Burst: states published as fast as possible for 4 s; how many a second
reach the websocket client (a server behind the map skips to the newest states, so fewer than
were published) and how late.

Run: ``.venv/bin/python benchmarks/serve_latency.py [--people 10,100,300] [--seconds 8] [--quick]``.
Writes ``benchmarks/results/serve_latency.md``.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import ROOT, markdown_table, save_result  # noqa: E402
from map_rig import WORLDTRACK, Server, load_average  # noqa: E402

from worldtrack.map.connection import MapKeys  # noqa: E402
from worldtrack.map.messages import MapPerson, MapState, encode_map_state  # noqa: E402
from worldtrack.scene import load_scene  # noqa: E402

SCENE = ROOT / "examples" / "scenes" / "office_4cams.yaml"
KEYS = MapKeys("worldtrack")


class Walkers:
    """N people random-walking at about 1.2 m/s inside the scene's bounds."""

    def __init__(self, scene, n: int, seed: int = 0):
        self.rng = np.random.default_rng(seed)
        x0, x1, y0, y1 = scene.walkable.bounds
        self.lo, self.hi = np.array([x0, y0]) + 0.3, np.array([x1, y1]) - 0.3
        self.xy = self.rng.uniform(self.lo, self.hi, (n, 2))
        self.v = self.rng.normal(0, 1.0, (n, 2))

    def step(self, dt: float) -> None:
        self.v = 0.9 * self.v + self.rng.normal(0, 0.4, self.v.shape)
        self.xy = np.clip(self.xy + self.v * dt, self.lo, self.hi)

    def state(self, t: float) -> MapState:
        people = tuple(MapPerson(i + 1, float(x), float(y), 1.7, 0.45, float(vx), float(vy), 1.0, 0.8, "tracking",
                                 t, t - 10.0, 1, "w1")
                       for i, ((x, y), (vx, vy)) in enumerate(zip(self.xy, self.v)))
        return MapState(t, people, reports=(("cam1", t, t),), written=time.time())


def publish(client, walkers: Walkers, seconds: float, every_s: float | None) -> int:
    """Write map states for ``seconds`` (one per ``every_s``, or as fast as possible); returns how many."""
    n, start = 0, time.time()
    last_ms = 0
    while time.time() - start < seconds:
        t = time.time()
        ms = max(int(t * 1000), last_ms + 1)
        last_ms = ms
        walkers.step(every_s or 0.01)
        client.xadd(KEYS.map_stream, encode_map_state(walkers.state(ms / 1000)), id=f"{ms}-0")
        n += 1
        if every_s:
            time.sleep(max(0.0, start + n * every_s - time.time()))
    return n


def redis_reader(url: str, stop: threading.Event, lags: list[float]) -> None:
    """The reference: a plain XREAD BLOCK reader of the map stream; lag = received - written."""
    import redis
    client = redis.Redis.from_url(url, decode_responses=True)
    last = "$"
    while not stop.is_set():
        for _, entries in client.xread({KEYS.map_stream: last}, block=200) or ():
            now = time.time()
            for entry_id, fields in entries:
                last = entry_id
                lags.append(now - float(fields["written"]))


def ws_reader(url: str, stop: threading.Event, lags: list[float], ready: threading.Event) -> None:
    """A websocket client of the server; lag = received - written (state messages only)."""
    import websockets

    async def go():
        async with websockets.connect(url, max_size=None) as ws:
            ready.set()
            while not stop.is_set():
                try:
                    text = await asyncio.wait_for(ws.recv(), 0.2)
                except asyncio.TimeoutError:
                    continue
                now = time.time()
                if text.startswith('{"type":"state"'):
                    lags.append(now - json.loads(text)["written"])
    asyncio.run(go())


def drain(received: list, quiet_s: float = 1.0, limit_s: float = 60.0) -> None:
    """Wait until nothing has arrived for ``quiet_s`` (the server has caught up)."""
    start, n, last_change = time.time(), len(received), time.time()
    while time.time() - last_change < quiet_s and time.time() - start < limit_s:
        time.sleep(0.1)
        if len(received) != n:
            n, last_change = len(received), time.time()


def pct(v: list[float], q: float) -> float:
    return float(np.percentile(v, q) * 1000) if v else float("nan")


def cpu_seconds(pid: int) -> float:
    """User + system CPU time of a process so far (s; Linux /proc)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def measure(redis_url: str, client, serve_url: str, scene, people: int, seconds: float, browser, pid: int) -> dict:
    client.delete(KEYS.map_stream)
    stop, ready = threading.Event(), threading.Event()
    ref, ws = [], []
    threads = [threading.Thread(target=redis_reader, args=(redis_url, stop, ref), daemon=True),
               threading.Thread(target=ws_reader, args=(serve_url.replace("http", "ws") + "ws", stop, ws, ready),
                                daemon=True)]
    for th in threads:
        th.start()
    ready.wait(10)
    page = browser.new_page(viewport={"width": 1400, "height": 900})
    page.goto(serve_url)
    page.wait_for_function("window.worldtrack && window.worldtrack.ready", timeout=30000)
    time.sleep(0.5)
    walkers = Walkers(scene, people)
    cpu0 = cpu_seconds(pid)
    sent = publish(client, walkers, seconds, 0.1)
    time.sleep(1.0)
    cpu_ms = (cpu_seconds(pid) - cpu0) / sent * 1000
    drawn = page.evaluate("window.worldtrack.lags")
    on_page = page.locator("#people .person").count()
    page.close()
    # Throughput: as fast as possible, the websocket client counts what arrives.
    before = len(ws)
    t0 = time.time()
    burst = publish(client, walkers, 4.0, None)
    rate_in = burst / (time.time() - t0)
    drain(ws)
    received = len(ws) - before
    rate_out = received / 4.0
    behind = float(np.median(ws[before:])) * 1000 if received else float("nan")
    stop.set()
    for th in threads:
        th.join(5)
    skip = 5                                           # the first half second: connections warming up
    ref, ws_lat, drawn = ref[skip:sent], ws[skip:sent], drawn[skip:]
    return {"people": people, "states": sent, "on page": on_page, "server CPU ms/state": cpu_ms,
            "ref p50": pct(ref, 50), "ref p99": pct(ref, 99), "ws p50": pct(ws_lat, 50), "ws p99": pct(ws_lat, 99),
            "drawn p50": pct(drawn, 50), "drawn p99": pct(drawn, 99), "drawn max": pct(drawn, 100),
            "burst published/s": rate_in, "burst pushed/s": rate_out, "burst lag p50": behind,
            "ratio ws/ref p50": pct(ws_lat, 50) / max(pct(ref, 50), 1e-3)}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--people", default="10,100,300", help="people on the map, comma-separated")
    ap.add_argument("--seconds", type=float, default=8.0, help="seconds of 10 Hz states per size")
    ap.add_argument("--no-pin", action="store_true", help="do not pin the server to core 1")
    ap.add_argument("--quick", action="store_true", help="10 and 100 people, 3 s, results not written")
    args = ap.parse_args()
    sizes = [10, 100] if args.quick else [int(v) for v in args.people.split(",")]
    seconds = 3.0 if args.quick else args.seconds
    from playwright.sync_api import sync_playwright

    sys.path.insert(0, str(ROOT / "tests" / "serve"))
    from _servekit import chromium_path
    exe = chromium_path()
    if exe is None:
        print("chromium is not installed (apt-get install chromium); skipped")
        return 0
    started = time.time()
    scene = load_scene(SCENE)
    with tempfile.TemporaryDirectory() as tmp:
        redis = Server(Path(tmp))
        import redis as redis_py
        client = redis_py.Redis(port=redis.port, decode_responses=True)
        port = redis.port + 1 if redis.port < 65000 else 18080
        pin = ["taskset", "-c", "1"] if (os.cpu_count() or 1) > 1 and not args.no_pin else []
        serve = subprocess.Popen([*pin, *WORLDTRACK, "serve", "--map", redis.url, "--scene", str(SCENE),
                                  "--port", str(port)], stderr=subprocess.DEVNULL)
        url = f"http://127.0.0.1:{port}/"
        try:
            for _ in range(600):
                try:
                    urllib.request.urlopen(url + "api/plan", timeout=1)
                    break
                except OSError:
                    time.sleep(0.1)
            rows = []
            with sync_playwright() as p:
                browser = p.chromium.launch(executable_path=exe, args=["--no-sandbox"])
                for n in sizes:
                    r = measure(redis.url, client, url, scene, n, seconds, browser, serve.pid)
                    print(json.dumps(r), flush=True)
                    rows.append(r)
                browser.close()
        finally:
            serve.terminate()
            serve.wait(10)
            redis.stop()
    headers = list(rows[0])
    table = markdown_table(headers, [[r[h] for h in headers] for r in rows])
    text = (f"Map states at 10 Hz for {seconds:g} s per size, then 4 s as fast as possible; latencies in ms from "
            f"the state's writing (`written`) to: `ref` a plain Redis XREAD reader (the floor), `ws` a websocket "
            f"client of the server, `drawn` the page in chromium after drawing it; `burst`: 4 s of states as fast "
            f"as this process writes them (the server skips to the newest when behind); `server CPU`: the serve "
            f"process's CPU time during the 10 Hz phase per state (its camera-status thread included). Load average "
            f"{load_average()}.\n\n{table}\n")
    print(text)
    save_result("serve_latency", "worldtrack serve: map update to page", text, args.quick, time.time() - started)
    return 0


if __name__ == "__main__":
    sys.exit(main())
