"""Seed 002: the leader's iterations under solver option sets, and whether each stops at the default's optimum.

Question (issue 34, "environment term ≤ 3× the time without it"): 3× needs ≈ 10 leader iterations at T = 10 000,
the default takes 10–35. Which of the opt-in solver options (``shrink_on_reject``, 34g; ``outward_curvature``, 34n;
``finish_newton``, 34o: after the outward run stops, Newton's matrix until the default rule stops) cut the
iterations, and does the stop stay within the bar "objective ≤ default·(1 + 1e-6) or lower"?

Problem: the walks of ``trajectory_speed.py`` (``problem_of(T, seed)``); Levenberg–Marquardt with the barrier from
the shortest-path start (the start that wins the race on these walks), as ``trajectory_outward.py``.
Columns per option set: iterations (with ``finish_newton``: of which after the switch), the stop's objective ÷
the default's − 1, the largest floor distance between the two stops (m). Last rows: iterations summed per T, and
how many walks are above the bar.

Run: ``.venv/bin/python benchmarks/trajectory_finish.py [--sizes 1000,10000] [--seeds 3,42,90]
[--sets "shrink_on_reject=1" "shrink_on_reject=1,outward_curvature=1.0,finish_newton=1"] [--held-out 200]
[--never-used 900] [--tag held_out] [--quick]``. Writes ``benchmarks/results/trajectory_finish[_<tag>].md``.
"""

from __future__ import annotations

import sys
import time
from dataclasses import fields, replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table  # noqa: E402
from trajectory_common import (add_seed_blocks, block_of, iteration_totals, rows_of_walks, save_walks,  # noqa: E402
                               walks_of, walks_parser)
from trajectory_timing_steps import setup  # noqa: E402

from worldtrack.errors import InputError  # noqa: E402
from worldtrack.trajectory.solver import LevenbergMarquardt, SolverOptions  # noqa: E402

#: The bar of issue 34: an option set's stop may be at most this far above the default's (relative).
BAR = 1e-6
DEFAULT_SETS = ("shrink_on_reject=1", "outward_curvature=1.0,finish_newton=1",
                "shrink_on_reject=1,outward_curvature=1.0,finish_newton=1")


def parse_set(spec: str) -> dict:
    """``"field=value,…"`` of :class:`SolverOptions` → keyword arguments (bools as 0/1, ``None`` for none).

    >>> parse_set("shrink_on_reject=1,outward_curvature=1.0")
    {'shrink_on_reject': True, 'outward_curvature': 1.0}
    """
    kinds = {f.name: f.type for f in fields(SolverOptions)}
    out = {}
    for item in filter(None, spec.split(",")):
        key, _, value = item.partition("=")
        if key not in kinds or not value:
            raise InputError(f"option set: expected field=value with a SolverOptions field, got {item!r}")
        kind = str(kinds[key])
        out[key] = (None if value == "None" else value == "1" if kind == "bool"
                    else int(value) if kind == "int" else value if kind == "str" else float(value))
    return out


class Counted(LevenbergMarquardt):
    """The solver, remembering at which iteration ``finish_newton`` switched to Newton's matrix."""

    switched_at: int | None = None

    def _finish(self) -> None:
        self.switched_at = self.iterations
        super()._finish()


def row(T: int, seed: int, block: str, sets: list[dict]) -> list:
    problem, X0, opts = setup(T, seed)
    ref = LevenbergMarquardt(problem, X0, opts.solver)
    ref.run()
    F = ref.lin.costs.total
    cells = [T, f"{seed} ({block})", f"{ref.iterations} (F {F:.4f})"]
    for kwargs in sets:
        run = Counted(problem, X0, replace(opts.solver, **kwargs))
        run.run()
        after = "" if run.switched_at is None else f" ({run.iterations - run.switched_at} after)"
        gap = float(np.hypot(*(run.X[:, [0, 2]] - ref.X[:, [0, 2]]).T).max())
        cells.append(f"{run.iterations}{after} {run.lin.costs.total / F - 1:+.1e} {gap:.2f} m")
    return cells


def main(argv: list[str] | None = None) -> int:
    ap = walks_parser(__doc__, 1)
    ap.add_argument("--sets", nargs="+", default=list(DEFAULT_SETS), help="option sets, each 'field=value,…'")
    add_seed_blocks(ap, "trajectory_finish")
    args = ap.parse_args(argv)
    try:
        sets = [parse_set(s) for s in args.sets]
    except (InputError, ValueError) as e:
        print(f"trajectory_finish: {e}", file=sys.stderr)
        return 2
    cpu, sizes, seeds, _ = walks_of(args)
    t0 = time.perf_counter()
    rows = rows_of_walks(sizes, seeds, block_of(args), lambda T, seed, block: row(T, seed, block, sets))
    totals = iteration_totals(rows, sizes, len(sets),
                              lambda cells: f"{sum(float(str(c).split()[-3]) > BAR for c in cells)} above {BAR:g}")
    text = f"({cpu})\n\n" + markdown_table(
        ["T", "walk", "default: iterations", *(f"{s}: iterations, F ÷ default − 1, largest gap" for s in args.sets)],
        rows + totals)
    print(text)
    save_walks("trajectory_finish", "Seed 002: solver option sets, leader iterations and the default's optimum",
               text, args, time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
