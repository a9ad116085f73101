"""Run every benchmark of issue 5 in turn and print their tables (``make bench``).

Question: all of them at once — seed 000's tables on the synthetic world (``paper_kato``), the three
trackers on the same frames (``compare_methods``), the 10-person crowd over 80 seeds
(``crowd_seeds``, issue 4's MOTA target), where a frame's time goes (``speed``) and the trackers on
real footage (``real_data``). Each runs as its own process (so one's memory and
compiled kernels do not affect another's timing), one after the other, and writes
``benchmarks/results/<name>.md``; their tables go to stdout, progress to stderr.

The budget is 15 minutes on a 2-core machine; the sizes and frame counts of each script are
chosen for it (see their docstrings); the whole run takes about 8 minutes. ``--quick`` runs every
script's smoke test (about 1.5 minutes) and writes no result files. The older single-question scripts (``render_speed``,
``particle_speed``, ``particle_entry``) are not part of this run; run them by hand.

Run: ``.venv/bin/python benchmarks/run_all.py [--quick] [--only NAME ...]``. Exits 1 if a script
failed (the others still run).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
SCRIPTS = ("paper_kato", "compare_methods", "crowd_seeds", "speed", "real_data")
BUDGET_S = 15 * 60


def run(name: str, quick: bool) -> tuple[int, float]:
    """Run one script, its output passed through; (exit status, seconds)."""
    cmd = [sys.executable, str(HERE / f"{name}.py")] + (["--quick"] if quick else [])
    print(f"\n## {name}\n", flush=True)
    t0 = time.perf_counter()
    status = subprocess.call(cmd, cwd=HERE.parent)
    return status, time.perf_counter() - t0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="pass --quick to every script (a smoke run)")
    ap.add_argument("--only", nargs="+", choices=SCRIPTS, metavar="NAME", help=f"run only these ({', '.join(SCRIPTS)})")
    args = ap.parse_args(argv)
    t_start = time.perf_counter()
    results = {name: run(name, args.quick) for name in (args.only or SCRIPTS)}
    total = time.perf_counter() - t_start
    print("\n## run_all\n")
    for name, (status, seconds) in results.items():
        print(f"- {name}: {seconds:.0f} s" + ("" if status == 0 else f" — FAILED (exit {status})"))
    over = "" if total <= BUDGET_S else f" — over the {BUDGET_S // 60}-minute budget"
    print(f"- total: {total:.0f} s ({total / 60:.1f} min){over}")
    return 0 if all(status == 0 for status, _ in results.values()) else 1


if __name__ == "__main__":
    raise SystemExit(main())
