"""How the command line takes bad input: the fuzz generators of tests/fuzz on many more inputs.

Scene files (``worldtrack scene check``), track CSVs (``worldtrack eval F F --json``) and
calibration points (``worldtrack calibrate``): every mutation of the catalogues on ``--rooms``
rooms, then hypothesis on ``--examples`` more per family (seeded). Each input must end in exit 0
(valid, read as meant) or one ``error:`` line with exit 2, without a traceback, within 2 s and
500 MB; an invalid input accepted is counted as "wrongly accepted". The table gives the counts per
family and lists every failing input.

    .venv/bin/python benchmarks/fuzz.py                 # 10 rooms x every mutation + 600 per family
    .venv/bin/python benchmarks/fuzz.py --quick         # 2 rooms + 30 per family, prints only
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "fuzz"))
sys.path.insert(0, str(ROOT / "benchmarks"))

import fuzz_calibration  # noqa: E402
import fuzz_scene  # noqa: E402
import fuzz_tracks  # noqa: E402
from common import markdown_table, save_result  # noqa: E402
from fuzz_runner import count, run_case  # noqa: E402

FAMILIES = {"scene files": (fuzz_scene.scene_case, fuzz_scene.MUTATIONS),
            "track CSVs": (fuzz_tracks.tracks_case, fuzz_tracks.MUTATIONS),
            "calibration points": (fuzz_calibration.calibration_case, fuzz_calibration.MUTATIONS)}


def run_family(make, mutations, rooms: int, examples: int, folder: Path) -> list:
    """Every mutation on ``rooms`` rooms, then ``examples`` drawn by hypothesis (seeded)."""
    from hypothesis import HealthCheck, given, seed, settings
    from hypothesis import strategies as st

    outcomes = [run_case(make(m, room, b"\x00\xff,: [x\r"), folder) for room in range(rooms) for m in mutations]

    @seed(2038)
    @settings(max_examples=examples, deadline=None, database=None, suppress_health_check=list(HealthCheck))
    @given(st.sampled_from(mutations), st.integers(0, 2 ** 31 - 1), st.binary(max_size=32))
    def explore(mutation, room, inserted):
        outcomes.append(run_case(make(mutation, room, inserted), folder))

    if examples:
        explore()
    return outcomes


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rooms", type=int, default=10, help="rooms (seeds) per mutation of the catalogue")
    ap.add_argument("--examples", type=int, default=600, help="hypothesis examples per family")
    ap.add_argument("--quick", action="store_true", help="2 rooms, 30 examples; print only")
    args = ap.parse_args()
    rooms, examples = (2, 30) if args.quick else (args.rooms, args.examples)
    t0 = time.perf_counter()
    rows, failures = [], []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for make, _ in FAMILIES.values():            # imports are not any input's cost
            run_case(make("as-is", 0), folder)
        for family, (make, mutations) in FAMILIES.items():
            outcomes = run_family(make, mutations, rooms, examples, folder)
            c = count(outcomes)
            invalid = sum(o.case.kind == "invalid" for o in outcomes)
            slowest = max(o.seconds for o in outcomes)
            slowest_wall = max(o.wall_seconds for o in outcomes)
            biggest = max(o.peak_mb for o in outcomes)
            rows.append([family, c["inputs"], invalid, c["exit 0"], c["exit 2"], c["tracebacks"], c["hangs"],
                         c["over 2 s"], c["over 2 s wall"], c["over 500 MB"], c["wrongly accepted"],
                         c["accepted but read wrong"], c["valid refused"], c["bad error line"], f"{slowest:.2f}",
                         f"{slowest_wall:.2f}", f"{biggest:.0f}"])
            failures += [o.describe() for o in outcomes if not o.ok]
            print(f"{family}: {c}", file=sys.stderr)
    headers = ["family", "inputs", "of which invalid", "exit 0", "exit 2", "tracebacks", "hangs", "over 2 CPU s",
               "over 2 s wall (not judged)", "over 500 MB", "wrongly accepted", "accepted, read wrong", "valid refused",
               "bad error line", "slowest (CPU s)", "slowest (wall s)", "most memory (MB)"]
    text = (f"{len(fuzz_scene.MUTATIONS)} scene, {len(fuzz_tracks.MUTATIONS)} track-file and "
            f"{len(fuzz_calibration.MUTATIONS)} calibration mutations (tests/fuzz/fuzz_*.py) on {rooms} rooms each, "
            f"then {examples} hypothesis examples per family (seed 2038). Memory is the growth of the peak "
            "resident size during the input. Time is judged in CPU seconds of the process (the machine is "
            "shared); wall time is shown beside it.\n\n" + markdown_table(headers, rows) + "\n\n"
            + ("Failing inputs:\n\n" + "\n".join(f"- {f}" for f in failures) if failures else "No failing input.")
            + "\n")
    print(text)
    save_result("fuzz", "Bad input: fuzzed scene files, track CSVs and calibration points", text, args.quick,
                time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    sys.exit(main())
