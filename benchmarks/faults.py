"""Faults at run time: SIGINT and SIGTERM at random moments of ``worldtrack track`` (20 each).

Half the moments fall during start-up (0.3-6 s after the start: imports, scene, background,
kernels), half 0-3 s into tracking (inside the compiled kernels). Every run must end with exit
130 (SIGINT) or 143 (SIGTERM), the last line ``interrupted``/``terminated``, no traceback, and
its outputs whole (tests/cli/fault_harness.py says what is checked). The sequence is the test
suite's two-crossing at 160x120 (30 frames repeated to 400), rendered here.

    .venv/bin/python benchmarks/faults.py              # 20 SIGINT + 20 SIGTERM, 3 at a time
    .venv/bin/python benchmarks/faults.py --quick      # 4 + 4, prints only
"""

from __future__ import annotations

import argparse
import collections
import signal
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "cli"))
sys.path.insert(0, str(ROOT / "benchmarks"))

from common import markdown_table, save_result  # noqa: E402
from fault_harness import long_sequence, moments, signalled_run, track_command  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=20, help="runs per signal")
    ap.add_argument("--parallel", type=int, default=3, help="runs at a time")
    ap.add_argument("--quick", action="store_true", help="4 runs per signal; print only")
    args = ap.parse_args()
    n = 4 if args.quick else args.runs
    t0 = time.perf_counter()
    from worldtrack.synth import make_scenario, write_sequence

    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        sequence = write_sequence(make_scenario("two-crossing", size=(160, 120), frames=30, seed=1), tmp / "seq",
                                  png=True, progress=False)
        frames = long_sequence(sequence, tmp / "frames", 400)
        plan = [(s, m) for s in (signal.SIGINT, signal.SIGTERM) for m in moments(int(s) * 1000 + 38, n, (s,))]

        def one(k_item):
            k, (s, (delay, signum, tracking)) = k_item
            out = tmp / f"o{k}"
            return signalled_run(track_command(sequence, frames, out), out, delay, signum, tracking)

        with ThreadPoolExecutor(max_workers=args.parallel) as pool:
            runs = list(pool.map(one, enumerate(plan)))
    rows = []
    for s in (signal.SIGINT, signal.SIGTERM):
        mine = [r for r in runs if r.signum == s]
        phases = collections.Counter(r.phase for r in mine)
        codes = collections.Counter(r.code for r in mine)
        rows.append([signal.Signals(s).name, len(mine), phases["starting"], phases["tracking"],
                     phases["finished before the signal"], ", ".join(f"{c}: {k}" for c, k in sorted(codes.items())),
                     sum(bool(r.problems) for r in mine)])
    failures = [r.describe() for r in runs if r.problems]
    text = (markdown_table(["signal", "runs", "during start-up", "during tracking", "finished first", "exit statuses",
                            "runs with a problem"], rows)
            + "\n\n" + ("Problems:\n\n" + "\n".join(f"- {f}" for f in failures) if failures else "No problem.")
            + "\n\nMoments (s after start, or after tracking began): "
            + "; ".join(f"{signal.Signals(r.signum).name} {r.delay:.2f} {'tracking' if r.phase == 'tracking' else 'start'}"
                        for r in runs) + "\n")
    print(text)
    save_result("faults", "Signals at random moments of worldtrack track", text, args.quick, time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    sys.exit(main())
