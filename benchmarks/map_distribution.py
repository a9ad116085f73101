"""The cost of distribution: one process with N cameras against N workers on the shared map.

Question (issue 39): what do frames/s and accuracy (MOTA, IDF1 against ground truth, 0.5 m gate)
lose or gain when the cameras of one scene are tracked by N ``worldtrack track --map`` workers (one
camera each) whose estimates the fusion merges, instead of by one process that sees them all?

Scenes (held-out seeds: the map was developed on two-rooms seeds 0 and 1): ``two-rooms`` seeds 2-4
(N = 2, two people walking from one room's camera into the other's) and ``crowd`` seed 5 with 4
cameras and 5 people (N = 4, heavily overlapping views). The one process runs
``worldtrack track`` with every camera (its frames/s as it reports them, warm start included). The
workers read their files as fast as they can (``map.pace_files=false``; the fusion waits for every
camera, ``map.max_wait_s=10``) and their frames/s is the scenario's frames over the wall time from
``map start`` to the last worker's exit; their tracks are ``worldtrack replay``'s. Ratio column:
workers ÷ one process, measured in the same run. Both use all cores of the machine (2, shared).

Run: ``.venv/bin/python benchmarks/map_distribution.py [--quick]``. Writes
``benchmarks/results/map_distribution.md``.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table, save_result  # noqa: E402
from map_rig import WORLDTRACK, Server, load_average, run_workers  # noqa: E402

from worldtrack.eval.mot import evaluate  # noqa: E402
from worldtrack.io.tracks import read_tracks  # noqa: E402
from worldtrack.map.connection import MapKeys, connect  # noqa: E402
from worldtrack.map.replay import replay  # noqa: E402
from worldtrack.synth import make_scenario, write_sequence  # noqa: E402

CASES = [("two-rooms", 2, {}), ("two-rooms", 3, {}), ("two-rooms", 4, {}),
         ("crowd", 5, {"cameras": 4, "people": 5, "frames": 100})]


def one_process(seq: Path, cams: list[str], out: Path) -> tuple[float, dict]:
    cmd = [*WORLDTRACK, "track", str(seq / "scene.yaml"), *[a for c in cams for a in ("--video", f"{c}={seq / (c + '.mp4')}")],
           "--out", str(out), "--quiet", "--no-video"]
    err = subprocess.run(cmd, capture_output=True, text=True, check=True).stderr
    fps = float(re.search(r"\(([\d.]+) frames/s\)", err).group(1))
    return fps, evaluate(read_tracks(seq / "gt.csv"), read_tracks(out / "tracks.csv"))


def workers(server: Server, seq: Path, cams: list[str], frames: int, out: Path) -> tuple[float, dict]:
    server.flush()
    wall = run_workers(seq, server.url, cams, out, sets=["map.pace_files=false", "map.max_wait_s=10"])
    client = connect(server.url)
    result = replay(client, MapKeys(), out / "replay")
    return frames / wall, evaluate(read_tracks(seq / "gt.csv"), read_tracks(result.tracks_csv))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="two-rooms seed 2 only; prints only")
    args = ap.parse_args()
    cases = CASES[:1] if args.quick else CASES
    start = time.time()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        server = Server(tmp)
        try:
            for name, seed, params in cases:
                sc = make_scenario(name, seed=seed, **params)
                seq = tmp / f"{name}-{seed}"
                write_sequence(sc, seq, progress=False)
                fps1, m1 = one_process(seq, sc.camera_ids, seq / "one")
                fpsn, mn = workers(server, seq, sc.camera_ids, sc.n_frames, seq / "workers")
                rows.append([f"{name} seed {seed}", len(sc.camera_ids), fps1, fpsn, fpsn / fps1, m1["mota"], mn["mota"],
                             m1["idf1"], mn["idf1"], m1["num_switches"], mn["num_switches"], m1["motp_m"], mn["motp_m"]])
                print(rows[-1], file=sys.stderr)
        finally:
            server.stop()
    table = markdown_table(["scene", "N", "one process frames/s", "N workers frames/s", "ratio", "MOTA one",
                            "MOTA workers", "IDF1 one", "IDF1 workers", "switches one", "switches workers",
                            "error one (m)", "error workers (m)"], rows)
    text = (f"{table}\n\nframes/s count bundles of all N cameras. Load average at the end: {load_average()} "
            f"(2 cores shared with other work; single runs).\n")
    print(text)
    save_result("map_distribution", "One process with N cameras against N workers on the shared map", text,
                args.quick, time.time() - start)


if __name__ == "__main__":
    main()
