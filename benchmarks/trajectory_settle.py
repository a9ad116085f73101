"""Seed 002: the leader's iterations on the windows still moving (``settle_windows``, 34b) against the default.

Question: issue 34's "environment term ≤ 3× the time without it" — once most windows have settled, does iterating
only on the unsettled ones (:mod:`worldtrack.trajectory.settle`) cut the estimate's CPU time, and does it reach
the default's optimum?

Problem: the walks of ``trajectory_speed.py`` (``problem_of(T, seed)``). Per walk, pinned to one processor, the
least CPU seconds (``time.process_time``) of ``--repeats`` calls of ``estimate_trajectory``:

- *without*: no environment; *default* and *settle*: with it, ``settle_windows`` off and on; their ratios;
- the leader's iterations (with settle: of them restricted, and the whole-trajectory iterations they amount to:
  full ones + Σ restricted steps ÷ T);
- the objective and the largest floor distance of settle against the default, and of both against the *tight*
  optimum (the default's estimate polished with the relative decrease 1e-13, at most 300 more iterations):
  the default stops on a flat slide 1e-5 above it, where paths still creep centimetres per iteration.

Run: ``.venv/bin/python benchmarks/trajectory_settle.py [--sizes 1000,10000] [--seeds 3,42,90] [--repeats 3]``.
Writes ``benchmarks/results/trajectory_settle.md``. About two minutes.
"""

from __future__ import annotations

import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table, save_result  # noqa: E402
from trajectory_common import least_cpu, walks_of, walks_parser  # noqa: E402
from trajectory_speed import problem_of  # noqa: E402

import worldtrack.trajectory.estimate as estimate  # noqa: E402
from worldtrack.trajectory.estimate import TrajectoryOptions, build_environment, estimate_trajectory  # noqa: E402
from worldtrack.trajectory.model import TimeGrid, frame_interval  # noqa: E402
from worldtrack.trajectory.objective import Problem  # noqa: E402
from worldtrack.trajectory.settle import run_settling  # noqa: E402
from worldtrack.trajectory.solver import LevenbergMarquardt  # noqa: E402

LOGS: list = []


def _logged(run, *args):
    result, log = run_settling(run, *args)
    LOGS.append(log)
    return result, log


estimate.run_settling = _logged           # the estimate's own call, its log kept



def floor_gap(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.hypot(a[:, 0] - b[:, 0], a[:, 2] - b[:, 2]).max())


def row(T: int, seed: int, repeats: int) -> list:
    scene, obs, height = problem_of(T, seed)
    field = scene.distance_field(0.05)
    opts = TrajectoryOptions(height=height)
    without, _ = least_cpu(lambda: estimate_trajectory(obs, field, replace(opts, environment=False)), repeats)
    default, a = least_cpu(lambda: estimate_trajectory(obs, field, opts), repeats)
    settle, b = least_cpu(lambda: estimate_trajectory(obs, field, replace(opts, settle_windows=True)), repeats)
    log = LOGS[-1]
    dt = frame_interval(obs.time, obs.camera)
    problem = Problem.build(obs, TimeGrid.covering(obs.time, dt), opts.motion, build_environment(opts, field, dt))
    tight = LevenbergMarquardt(problem, a.X, replace(opts.solver, barrier_relative_decrease=1e-13,
                                                     max_iterations=300)).run()
    Fa, Fb, Ft = a.costs["total"], b.costs["total"], tight.costs.total
    it_a, it_b = a.results[a.start].iterations, b.results[b.start].iterations
    ms = lambda s: f"{s * 1e3:.0f}"  # noqa: E731
    return [T, seed, ms(without), ms(default), ms(settle), f"{default / without:.2f}", f"{settle / without:.2f}",
            f"{settle / default:.2f}", it_a, f"{it_b} ({log.iterations} in {log.phases})",
            f"{it_b - log.iterations + log.work:.1f}", f"{Fb / Fa - 1:+.1e}", f"{floor_gap(a.X, b.X):.3f}",
            f"{Fa / Ft - 1:.1e} / {Fb / Ft - 1:.1e}", f"{floor_gap(a.X, tight.X):.3f} / {floor_gap(b.X, tight.X):.3f}"]


def main(argv: list[str] | None = None) -> int:
    ap = walks_parser(__doc__, 3, 1000)
    args = ap.parse_args(argv)
    cpu, sizes, seeds, repeats = walks_of(args, 1000)
    t0 = time.perf_counter()
    scene, obs, height = problem_of(300, 3)                  # load the compiled kernels untimed
    estimate_trajectory(obs, scene.distance_field(0.05), TrajectoryOptions(height=height, settle_windows=True))
    rows = []
    for T in sizes:
        for seed in seeds:
            rows.append(row(T, seed, repeats))
            print(" | ".join(map(str, rows[-1])), file=sys.stderr, flush=True)
    text = f"({cpu}; CPU ms, the least of {repeats})\n\n" + markdown_table(
        ["T", "seed", "without ms", "default ms", "settle ms", "default ÷ without", "settle ÷ without",
         "settle ÷ default", "leader iterations, default", "settle (restricted, in phases)",
         "settle in whole iterations", "F settle ÷ default − 1", "largest floor gap m",
         "F ÷ tight − 1 (default / settle)", "floor gap to tight m (default / settle)"], rows)
    print(text)
    save_result("trajectory_settle", "Seed 002: iterating on the windows still moving (settle_windows)", text,
                args.quick, time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
