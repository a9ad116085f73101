"""How many cameras one fusion process keeps up with: simulated publishers (no images) at 10 Hz.

Question (issue 39): with 16, 64 and 256 cameras, each seeing 5 people and publishing an
observation 10 times a second, what throughput and lag does one fusion process reach, and what is
the largest camera count it keeps up with?

Set-up: our own redis-server on 127.0.0.1; the publishers (:class:`worldtrack.map.simulate.Publishers`,
each camera under its own lease, one pipelined round trip per tick) run in this process pinned to
core 0; the fusion is a ``worldtrack map fuse`` process pinned to core 1 (``taskset``), as it would
run on its own. Each count runs ``--seconds`` (default 8) after a 2 s start.

Reported per camera count: observations published and merged per second; lag = when a bucket's
state was written minus the latest capture time merged into it (p50, p99: the fusion's share of
the capture-to-map latency; a bucket is written as soon as every camera has reported it, the
fusion waits at most ``max_wait_s`` = 0.5 s for late cameras); late observations (came after their bucket was written,
so not merged); and the publisher's own overruns (ticks it started late: then the publishers, not
the fusion, are the limit). "Keeps up" = p99 lag below 0.5 s and nothing late.
Reference in the same run: the lag at 16 cameras (the ratio column).

Run: ``.venv/bin/python benchmarks/map_scale.py [--cameras 16,64,256] [--seconds 8] [--quick]``.
Writes ``benchmarks/results/map_scale.md``.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table, save_result  # noqa: E402
from map_rig import WORLDTRACK, Server, load_average, percentiles  # noqa: E402

from worldtrack.map.config import MapConfig  # noqa: E402
from worldtrack.map.connection import MapKeys, connect  # noqa: E402
from worldtrack.map.messages import decode_map_state  # noqa: E402
from worldtrack.map.simulate import Publishers, SimulatedFloor  # noqa: E402


def run(server: Server, cameras: int, people: int, seconds: float) -> dict:
    server.flush()
    client = connect(server.url)
    keys, cfg = MapKeys(), MapConfig()
    pin = ["taskset", "-c", "1"] if shutil.which("taskset") and os.cpu_count() and os.cpu_count() > 1 else []
    log = open(Path(tempfile.gettempdir()) / f"map_scale_fuse_{cameras}.log", "w")
    fuser = subprocess.Popen([*pin, *WORLDTRACK, "map", "fuse", server.url], stdout=subprocess.DEVNULL, stderr=log)
    while not client.get(keys.fusion_lease):
        time.sleep(0.05)
    pubs = Publishers(client, keys, cfg, SimulatedFloor(cameras, people, np.random.default_rng(cameras))).start()
    time.sleep(2.0)
    t0 = time.time()
    time.sleep(seconds)
    t1 = time.time()
    pubs.stop()
    time.sleep(cfg.max_wait_s + 0.5)
    fuser.terminate()
    fuser.wait(10)
    states = [decode_map_state(f) for _, f in client.xrange(keys.map_stream, min=f"{int(t0 * 1000)}-0",
                                                                max=f"{int(t1 * 1000)}-0")]
    merged = sum(len(s.reports) for s in states)
    lag = [s.written - s.captured for s in states]
    late = sum(s.late for s in states)
    p50, p99 = percentiles(lag)
    return {"cameras": cameras, "obs_s": cameras * 10.0, "merged_s": merged / (t1 - t0), "lag50": p50, "lag99": p99,
            "late": late, "overruns": pubs.overruns, "people": int(np.median([len(s.present()) for s in states])) if states else 0}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cameras", default="16,64,256")
    ap.add_argument("--people", type=int, default=5)
    ap.add_argument("--seconds", type=float, default=8.0)
    ap.add_argument("--quick", action="store_true", help="16 and 64 cameras, 3 s each; prints only")
    args = ap.parse_args()
    counts = [16, 64] if args.quick else [int(c) for c in args.cameras.split(",")]
    seconds = 3.0 if args.quick else args.seconds
    if hasattr(os, "sched_setaffinity") and (os.cpu_count() or 1) > 1:
        os.sched_setaffinity(0, {0})
    start = time.time()
    with tempfile.TemporaryDirectory() as tmp:
        server = Server(Path(tmp))
        try:
            rows = [run(server, n, args.people, seconds) for n in counts]
        finally:
            server.stop()
    ref = rows[0]["lag99"]
    table = markdown_table(
        ["cameras", "people", "published obs/s", "merged obs/s", "lag p50 (s)", "lag p99 (s)", "p99 ÷ 16-camera",
         "late", "publisher overruns", "keeps up"],
        [[r["cameras"], r["people"], r["obs_s"], r["merged_s"], r["lag50"], r["lag99"], r["lag99"] / ref, r["late"],
          r["overruns"], "yes" if r["lag99"] < 0.5 and r["late"] == 0 else "no"] for r in rows])
    text = (f"{table}\n\nOne fusion process (`worldtrack map fuse`, pinned to core 1), publishers in one process "
            f"(core 0), {args.people} people per camera at 10 Hz, {seconds:g} s per count. Load average at the end: "
            f"{load_average()} (2 cores shared with other work).\n")
    print(text)
    save_result("map_scale", "Fusion throughput and lag by camera count (simulated publishers)", text, args.quick,
                time.time() - start)


if __name__ == "__main__":
    main()
