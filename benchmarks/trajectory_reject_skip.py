"""Seed 002: a rejected step that comes back unchanged is not linearised again (34b) — same estimates, less work?

Question: in a run of rejections near an obstacle (μ at 1e-18 … 1e-13 of diag H) raising the damping hardly
changes the step; the solver now skips the trial of a step whose change from the rejected one cannot undo the
rejection (``LevenbergMarquardt._still_rejected``). Are the estimates bit for bit those of evaluating every
trial, and how many linearisations does it save?

Problem: the walks of ``trajectory_speed.py`` (``problem_of(T, seed)``). Per walk, pinned to one processor,
``estimate_trajectory`` with the skip (the default) and with every trial evaluated (the skip switched off by
patching the class), least CPU seconds of ``--repeats`` calls; *identical*: the two estimates' X equal bit for bit.

Run: ``.venv/bin/python benchmarks/trajectory_reject_skip.py [--sizes 1000,10000] [--seeds 3,42,90]``.
Writes ``benchmarks/results/trajectory_reject_skip.md``. About a minute.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table, save_result  # noqa: E402
from trajectory_common import walks_of, walks_parser  # noqa: E402
from trajectory_speed import problem_of  # noqa: E402

from worldtrack.trajectory.estimate import TrajectoryOptions, estimate_trajectory  # noqa: E402
from worldtrack.trajectory.solver import LevenbergMarquardt  # noqa: E402

SKIP = LevenbergMarquardt._still_rejected
COUNT = [0]


def counting(self, delta):
    same = SKIP(self, delta)
    COUNT[0] += same
    return same


def run(obs, field, opts, skip: bool, repeats: int):
    LevenbergMarquardt._still_rejected = counting if skip else (lambda self, delta: False)
    best, est = float("inf"), None
    for _ in range(repeats):
        COUNT[0] = 0
        c0 = time.process_time()
        est = estimate_trajectory(obs, field, opts)
        best = min(best, time.process_time() - c0)
    LevenbergMarquardt._still_rejected = SKIP
    return best, est, COUNT[0]


def row(T: int, seed: int, repeats: int) -> list:
    scene, obs, height = problem_of(T, seed)
    field = scene.distance_field(0.05)
    opts = TrajectoryOptions(height=height)
    off, a, _ = run(obs, field, opts, False, repeats)
    on, b, skipped = run(obs, field, opts, True, repeats)
    return [T, seed, "yes" if np.array_equal(a.X, b.X) else f"no ({np.abs(a.X - b.X).max():.1e})",
            b.results[b.start].iterations, skipped, f"{off * 1e3:.0f}", f"{on * 1e3:.0f}", f"{on / off:.2f}"]


def main(argv: list[str] | None = None) -> int:
    ap = walks_parser(__doc__, 3)
    args = ap.parse_args(argv)
    cpu, sizes, seeds, repeats = walks_of(args)
    t0 = time.perf_counter()
    scene, obs, height = problem_of(300, 3)                  # load the compiled kernels untimed
    estimate_trajectory(obs, scene.distance_field(0.05), TrajectoryOptions(height=height))
    rows = [row(T, seed, repeats) for T in sizes for seed in seeds]
    text = f"({cpu}; CPU ms, the least of {repeats})\n\n" + markdown_table(
        ["T", "seed", "identical", "leader iterations", "trials skipped", "every trial ms", "skip ms", "skip ÷ every"],
        rows)
    print(text)
    save_result("trajectory_reject_skip", "Seed 002: rejected steps that come back unchanged", text, args.quick,
                time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
