"""Seed 002: Gauss–Newton's curvature for the barrier samples that moved away from the obstacles
(``SolverOptions.outward_curvature``, opt-in).

Question: in the hinge's exponential tail (the optimum's samples sit 1.5–2.7 softness widths beyond the clearance,
34l) Newton's curvature of e^(−2d/w) is largest where a move away from an obstacle starts, so a sample pressed too
close moves ~w/2 = 1.5 cm per iteration (34l's trace: the last iterations of walk 3 at T = 1 000 all move 0.016 m,
ρ 0.9–1.3), and the tail's gain ratio ρ sits at 1.3–1.8. Does a smaller curvature factor for the samples that moved
away in the last step (the trial linearisation compares each sample's distance with the one before the step; they
take ``outward_curvature`` instead of 1 + r·r″/r′² ≈ 2) cut the leader's iterations, and where does it stop?

Problem: the walks of ``trajectory_speed.py`` (``problem_of(T, seed)``); Levenberg–Marquardt with the barrier from
the shortest-path start (the start that wins the race on these walks), default ``SolverOptions`` but the factor.
Columns: iterations, the stop's objective ÷ the default's − 1 (≤ 1e-6 or lower is the bar), the largest floor
distance between the two stops (m); the least CPU of ``--repeats`` runs ÷ the default's.

Run: ``.venv/bin/python benchmarks/trajectory_outward.py [--sizes 1000,10000] [--seeds 3,42,90] [--factors 1.0,1.3]
[--held-out 200] [--never-used 700] [--tag held_out] [--repeats 1] [--quick]``.
Writes ``benchmarks/results/trajectory_outward[_<tag>].md``.
"""

from __future__ import annotations

import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table  # noqa: E402
from trajectory_common import (add_seed_blocks, block_of, iteration_totals, least_cpu, rows_of_walks,  # noqa: E402
                               save_walks, walks_of, walks_parser)
from trajectory_timing_steps import setup  # noqa: E402

from worldtrack.trajectory.solver import levenberg_marquardt  # noqa: E402


def row(T: int, seed: int, block: str, factors: list[float], repeats: int) -> list:
    problem, X0, opts = setup(T, seed)
    cpu, ref = least_cpu(lambda: levenberg_marquardt(problem, X0, opts.solver), repeats)
    cells = [T, f"{seed} ({block})", f"{ref.iterations} (F {ref.costs.total:.4f})"]
    for factor in factors:
        solver = replace(opts.solver, outward_curvature=factor)
        c, res = least_cpu(lambda: levenberg_marquardt(problem, X0, solver), repeats)
        gap = float(np.hypot(*(res.X[:, [0, 2]] - ref.X[:, [0, 2]]).T).max())
        cells.append(f"{res.iterations} ({res.costs.total / ref.costs.total - 1:+.1e}, {gap:.2f} m) {c / cpu:.2f}")
    return cells


def main(argv: list[str] | None = None) -> int:
    ap = walks_parser(__doc__, 1)
    ap.add_argument("--factors", default="1.0,1.3", help="outward curvature factors (comma-separated)")
    add_seed_blocks(ap, "trajectory_outward")
    args = ap.parse_args(argv)
    cpu, sizes, seeds, repeats = walks_of(args)
    factors = [float(f) for f in args.factors.split(",")]
    t0 = time.perf_counter()
    rows = rows_of_walks(sizes, seeds, block_of(args), lambda T, seed, block: row(T, seed, block, factors, repeats))
    totals = iteration_totals(rows, sizes, len(factors))
    text = f"({cpu})\n\n" + markdown_table(
        ["T", "walk", "default: iterations", *(f"factor {f}: iterations (F ÷ default − 1, largest gap) CPU ÷ default"
                                               for f in factors)], rows + totals)
    print(text)
    save_walks("trajectory_outward", "Seed 002: Gauss–Newton's curvature for samples moving away from obstacles",
               text, args, time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
