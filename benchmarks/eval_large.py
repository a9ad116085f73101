"""How long ``worldtrack eval`` takes on large files: two track files of ``--rows`` rows each.

The ground truth is ``--people`` random walkers on a 20 x 20 m floor at 10 frames/s; the prediction
is the same people with 0.1 m of noise, 2 % of rows dropped and one identity swap every 500 frames.
Each repeat runs ``worldtrack eval GT PRED --json`` in a fresh process and records its wall and CPU time and
peak resident memory; the reference, measured in the same run, is reading both files alone
(``read_tracks``, in a fresh process too), so the ratio says what the metrics cost over the reading.
Wall and CPU seconds are both given: on a shared machine the wall time is mostly the neighbours'.

    .venv/bin/python benchmarks/eval_large.py                     # 10^6 rows, 3 repeats
    .venv/bin/python benchmarks/eval_large.py --quick             # 10^5 rows, 1 repeat, prints only
"""

from __future__ import annotations

import argparse
import json
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

from common import markdown_table, save_result  # noqa: E402

_READ = "import sys\nfrom worldtrack.io.tracks import read_tracks\nread_tracks(sys.argv[1]); read_tracks(sys.argv[2])\n"


def write_files(folder: Path, rows: int, people: int, seed: int) -> tuple[Path, Path]:
    """gt.csv and pred.csv of about ``rows`` rows each (frame,time,id,x,y)."""
    rng = np.random.default_rng(seed)
    frames = rows // people
    steps = rng.normal(0.0, 0.05, (frames, people, 2))
    xy = np.clip(rng.uniform(0, 20, (1, people, 2)) + np.cumsum(steps, axis=0), 0, 20)
    f = np.repeat(np.arange(frames), people)
    ids = np.tile(np.arange(1, people + 1), frames)
    gt = folder / "gt.csv"
    _write(gt, f, ids, xy.reshape(-1, 2))
    pred_xy = xy.reshape(-1, 2) + rng.normal(0.0, 0.1, (frames * people, 2))
    pred_ids = ids.copy()
    swap = (f // 500) % 2 == 1                      # ids 1 and 2 swap every other 500 frames
    pred_ids[swap & (ids == 1)], pred_ids[swap & (ids == 2)] = 2, 1
    keep = rng.random(frames * people) > 0.02
    pred = folder / "pred.csv"
    _write(pred, f[keep], pred_ids[keep], pred_xy[keep])
    return gt, pred


def _write(path: Path, frames: np.ndarray, ids: np.ndarray, xy: np.ndarray) -> None:
    table = np.column_stack([frames, frames / 10.0, ids, xy])
    np.savetxt(path, table, fmt=["%d", "%.1f", "%d", "%.4f", "%.4f"], delimiter=",", header="frame,time,id,x,y",
               comments="")


def timed(argv: list[str]) -> tuple[float, float, float, str]:
    """(wall seconds, CPU seconds, peak resident MB, stdout) of a child process (peak: RUSAGE_CHILDREN's
    maximum, so it is the largest of this and the earlier children)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    out = subprocess.run(argv, capture_output=True, text=True, timeout=3600)
    seconds = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    if out.returncode:
        raise SystemExit(f"{' '.join(argv[:3])}…: exit {out.returncode}: {out.stderr.strip()[-300:]}")
    return seconds, cpu, after.ru_maxrss / 1024, out.stdout


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=1_000_000)
    ap.add_argument("--people", type=int, default=20)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="10^5 rows, one repeat; print only")
    args = ap.parse_args()
    rows, repeats = (100_000, 1) if args.quick else (args.rows, args.repeats)
    t0 = time.perf_counter()
    cli = [sys.executable, "-c", "import sys\nfrom worldtrack.cli import main\nsys.exit(main(sys.argv[1:]))"]
    with tempfile.TemporaryDirectory() as tmp:
        gt, pred = write_files(Path(tmp), rows, args.people, seed=38)
        n_gt, n_pred = (sum(1 for _ in open(p)) - 1 for p in (gt, pred))
        read_s, eval_s, eval_cpu, peak = [], [], [], 0.0
        for _ in range(repeats):
            read_s.append(timed([sys.executable, "-c", _READ, str(gt), str(pred)])[1])
            s, cpu, peak, out = timed([*cli, "eval", str(gt), str(pred), "--json"])
            eval_s.append(s)
            eval_cpu.append(cpu)
        metrics = json.loads(out.strip().splitlines()[-1])
    ratio = statistics.median(eval_cpu) / statistics.median(read_s)
    rows_out = [[n_gt, n_pred, f"{min(eval_s):.1f} / {statistics.median(eval_s):.1f}",
                 f"{min(eval_cpu):.1f} / {statistics.median(eval_cpu):.1f}",
                 f"{min(read_s):.1f} / {statistics.median(read_s):.1f}", f"{ratio:.1f}", f"{peak:.0f}",
                 f"{metrics['mota']:.3f}", metrics["num_switches"]]]
    text = (f"{repeats} repeats, each in a fresh process (import time included). Target: eval of two 10^6-row "
            "files in at most 30 s.\n\n"
            + markdown_table(["GT rows", "PRED rows", "eval wall s (min / median)", "eval CPU s (min / median)",
                              "reading both, CPU s (min / median)", "eval / reading (CPU)", "peak MB (largest child)", "MOTA", "ID switches"], rows_out) + "\n")
    print(text)
    save_result("eval_large", "worldtrack eval on large track files", text, args.quick, time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    sys.exit(main())
