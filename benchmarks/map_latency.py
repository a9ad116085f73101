"""Latency from capture to map update with 4 workers on one machine, at the scenario's frame rate.

Question (issue 39): with four ``worldtrack track --map`` workers, one camera each, playing their
videos as live cameras (10 frames/s, every frame kept), how long after a frame's capture time is
the map state that holds it written? Target: p99 < 50 ms.

Set-up: the ``crowd`` scenario with 4 corner cameras of the hall, 5 people, 320x240, 100 frames
(seed 3, held out: the map was developed on two-rooms seeds 0 and 1); our own redis-server; the
workers wait for ``worldtrack map start``; the fusion role runs in its own ``worldtrack map fuse``
process pinned to core 1 (``--fusion worker``: in a thread of one of the workers, where it shares
the interpreter lock with that worker's tracker). From the map stream, per merged observation: capture → published (the worker's tracking
step, the reference measured in the same run), published → map written (transport and fusion), and
capture → map written (the total), and per map state the last observation's publication → map
written (the fusion's own work, without waiting for slower workers). The first second is left out (workers warming up). Each
repetition is a fresh run; the table gives every repetition and the median.

Run: ``.venv/bin/python benchmarks/map_latency.py [--repeats 3] [--quick]``. Writes
``benchmarks/results/map_latency.md``.
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table, save_result  # noqa: E402
from map_rig import WORLDTRACK, Server, load_average, percentiles, run_workers  # noqa: E402

from worldtrack.map.connection import MapKeys, connect  # noqa: E402
from worldtrack.map.messages import decode_map_state  # noqa: E402
from worldtrack.synth import make_scenario, write_sequence  # noqa: E402


def one_run(server: Server, scene_dir: Path, cams: list[str], out: Path, dedicated: bool) -> dict:
    server.flush()
    fuser = None
    if dedicated:
        pin = ["taskset", "-c", "1"] if shutil.which("taskset") else []
        fuser = subprocess.Popen([*pin, *WORLDTRACK, "map", "fuse", server.url], stdout=subprocess.DEVNULL,
                                 stderr=subprocess.DEVNULL)
    try:
        run_workers(scene_dir, server.url, cams, out,
                    sets=["map.fusion_in_worker=false"] if dedicated else [])
        time.sleep(1.0)
    finally:
        if fuser is not None:
            fuser.terminate()
            fuser.wait(10)
    client = connect(server.url)
    epoch = float(client.get(MapKeys().epoch))
    states = [decode_map_state(f) for _, f in client.xrange(MapKeys().map_stream)]
    total, step, fusion, own = [], [], [], []
    for s in states:
        if s.reports and min(t for _, t, _ in s.reports) >= epoch + 1.0:
            own.append(s.written - max(sent for _, _, sent in s.reports))
        for cam, t, sent in s.reports:
            if t < epoch + 1.0:
                continue
            total.append(s.written - t)
            step.append(sent - t)
            fusion.append(s.written - sent)
    late = sum(s.late for s in states)
    return {"total": percentiles(total), "step": percentiles(step), "fusion": percentiles(fusion),
            "own": percentiles(own),
            "n": len(total), "late": late, "states": len(states)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--frames", type=int, default=100)
    ap.add_argument("--fusion", choices=("process", "worker"), default="process",
                    help="the fusion role in its own `worldtrack map fuse` process (pinned to core 1), or in a "
                         "thread of one of the workers")
    ap.add_argument("--quick", action="store_true", help="one run of 40 frames; prints only")
    args = ap.parse_args()
    repeats, frames = (1, 40) if args.quick else (args.repeats, args.frames)
    start = time.time()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        sc = make_scenario("crowd", seed=3, cameras=4, people=5, frames=frames)
        write_sequence(sc, tmp / "seq", progress=False)
        server = Server(tmp)
        try:
            for k in range(repeats):
                r = one_run(server, tmp / "seq", sc.camera_ids, tmp / f"run{k}", args.fusion == "process")
                rows.append(r)
                print(f"run {k}: capture→map p50 {r['total'][0] * 1000:.1f} ms p99 {r['total'][1] * 1000:.1f} ms",
                      file=sys.stderr)
        finally:
            server.stop()

    def ms(v: float) -> float:
        return round(v * 1000, 1)
    table_rows = [[k, r["n"], ms(r["step"][0]), ms(r["step"][1]), ms(r["fusion"][0]), ms(r["fusion"][1]),
                   ms(r["own"][0]), ms(r["own"][1]), ms(r["total"][0]), ms(r["total"][1]), r["late"]]
                  for k, r in enumerate(rows)]
    med = [statistics.median(r[key][i] for r in rows) for key in ("step", "fusion", "own", "total") for i in (0, 1)]
    table_rows.append(["median", "", *[ms(v) for v in med], ""])
    table = markdown_table(["run", "observations", "capture→published p50 (ms)", "p99", "published→map p50 (ms)",
                            "p99", "last report→map p50 (ms)", "p99", "capture→map p50 (ms)", "p99", "late"],
                           table_rows)
    where = "its own process" if args.fusion == "process" else "a thread of one worker"
    text = (f"{table}\n\nFour workers (one camera each, `crowd` seed 3, 4 cameras, 5 people, 320x240, "
            f"{frames} frames at 10 frames/s played as live cameras), the fusion role in {where}. Target: "
            f"capture→map p99 < 50 ms; median p99 {ms(med[7])} ms "
            f"({'met' if med[7] < 0.05 else 'not met'}). Last report→map is the fusion's own part (from the last "
            f"observation of a bucket to its state being written); published→map also holds the wait for the "
            f"slowest worker. Ratio of the map's own share (published→map p99) to "
            f"the tracking step's (capture→published p99): {med[3] / med[1]:.2f}. Load average at the end: "
            f"{load_average()} (2 cores shared with other work).\n")
    print(text)
    save_result("map_latency", "Capture-to-map latency with 4 workers", text, args.quick, time.time() - start)


if __name__ == "__main__":
    main()
