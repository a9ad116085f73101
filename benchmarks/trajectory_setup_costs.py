"""Seed 002: what each part of the estimate with the environment costs, against the estimate without it.

Question: issue 34's "environment term ≤ 3× the time without it" — how much of the estimate with the
barrier is the set-up of its starts (the shortest-path route, each start's first linearisation) and how
much the winning start's Levenberg–Marquardt, and so how far could a cheaper set-up alone bring the ratio?

Problem: the walks of ``trajectory_speed.py`` (``problem_of(T, seed)``). Each figure is the least CPU
seconds (``time.process_time``) of ``--repeats`` calls, pinned to one processor:

- *full* / *without*: ``estimate_trajectory`` with and without the environment, as ``trajectory_speed.py``
  times them (without: the straight start, one Levenberg–Marquardt solve, the covariances);
- *free LM*: that one solve without the barrier (from the straight start); *covariance*: the marginals;
- *route*: ``shortest_path_start`` (the free-space routes of the blocked gaps);
- *start set-up*: one ``LevenbergMarquardt(problem, X0)`` (the start's linearisation with the barrier and
  the solver's buffers), made for each of the three starts;
- *leader LM*: Levenberg–Marquardt with the barrier from the shortest-path start to convergence (the start
  that wins on these walks; the straight and map starts leave the race at their first model floor);
- *ratio without set-up*: (full − route − 3 × start set-up) ÷ without, the ratio if the set-up were free;
- *iterations for 3×*: the leader iterations at its measured cost per iteration that 3 × without leaves
  after the rest of full.

Run: ``.venv/bin/python benchmarks/trajectory_setup_costs.py [--sizes 1000,10000] [--seeds 3,42,90] [--settle]``
(``--settle``: the estimate and the leader with ``settle_windows``, :mod:`worldtrack.trajectory.settle`).
Writes ``benchmarks/results/trajectory_setup_costs.md``. About a minute.
"""

from __future__ import annotations

import sys
import time
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table, save_result  # noqa: E402
from trajectory_common import least_cpu, walks_of, walks_parser  # noqa: E402
from trajectory_speed import problem_of  # noqa: E402

from worldtrack.trajectory.estimate import TrajectoryOptions, build_environment, estimate_trajectory  # noqa: E402
from worldtrack.trajectory.model import TimeGrid, frame_interval  # noqa: E402
from worldtrack.trajectory.objective import Problem  # noqa: E402
from worldtrack.trajectory.settle import run_settling  # noqa: E402
from worldtrack.trajectory.solver import LevenbergMarquardt, levenberg_marquardt  # noqa: E402
from worldtrack.trajectory.starts import anchor_points, shortest_path_start, straight_start  # noqa: E402
from worldtrack.trajectory.uncertainty import marginal_covariances  # noqa: E402



def row(T: int, seed: int, repeats: int, settle: bool = False) -> list:
    scene, obs, height = problem_of(T, seed)
    field = scene.distance_field(0.05)
    opts = TrajectoryOptions(height=height, settle_windows=settle)
    full, est = least_cpu(lambda: estimate_trajectory(obs, field, opts), repeats)
    without, _ = least_cpu(lambda: estimate_trajectory(obs, field, replace(opts, environment=False)), repeats)
    dt = frame_interval(obs.time, obs.camera)
    grid = TimeGrid.covering(obs.time, dt)
    problem = Problem.build(obs, grid, opts.motion, build_environment(opts, field, dt))
    free = problem.with_environment(problem.environment.without_barrier())
    anchors = anchor_points(problem.observations, height)
    straight = straight_start(problem.observations, grid, height, anchors)
    free_lm, _ = least_cpu(lambda: levenberg_marquardt(free, straight, opts.solver), repeats)
    route, short = least_cpu(lambda: shortest_path_start(problem.observations, grid, height, field, opts.clearance,
                                                         0.1, anchors), repeats)
    setup, _ = least_cpu(lambda: LevenbergMarquardt(problem, short, opts.solver), repeats)
    lead = (lambda: run_settling(LevenbergMarquardt(problem, short, opts.solver))[0]) if settle else \
        (lambda: levenberg_marquardt(problem, short, opts.solver))
    leader, res = least_cpu(lead, repeats)
    cov, _ = least_cpu(lambda: marginal_covariances(res.linearisation.D, res.linearisation.B), repeats)
    rest = full - leader
    per_iteration = leader / max(res.iterations, 1)
    ms = lambda s: f"{s * 1e3:.1f}"  # noqa: E731
    return [T, seed, ms(full), ms(without), f"{full / without:.2f}", ms(free_lm), ms(cov), ms(route), ms(setup),
            f"{ms(leader)} ({res.iterations})", f"{leader / full:.0%}", f"{(route + 3 * setup) / full:.0%}",
            f"{(full - route - 3 * setup) / without:.2f}", f"{(3 * without - rest) / per_iteration:.0f}", est.start,
            ", ".join(f"{k} {r.iterations}" for k, r in est.results.items())]


def main(argv: list[str] | None = None) -> int:
    ap = walks_parser(__doc__, 5)
    ap.add_argument("--settle", action="store_true", help="settle_windows=True (34b); writes _settle.md")
    args = ap.parse_args(argv)
    cpu, sizes, seeds, repeats = walks_of(args)
    t0 = time.perf_counter()
    scene, obs, height = problem_of(300, 3)                  # load the compiled kernels untimed
    estimate_trajectory(obs, scene.distance_field(0.05), TrajectoryOptions(height=height))
    rows = [row(T, seed, repeats, args.settle) for T in sizes for seed in seeds]
    text = f"({cpu}; CPU ms, the least of {repeats})\n\n" + markdown_table(
        ["T", "seed", "full ms", "without ms", "full ÷ without", "free LM ms", "covariance ms", "route ms",
         "start set-up ms (each)", "leader LM ms (iterations)", "leader ÷ full", "route + 3 set-ups ÷ full",
         "ratio without set-up", "leader iterations for 3×", "start won", "iterations per start"], rows)
    print(text)
    tail = " (settle_windows)" if args.settle else ""
    save_result("trajectory_setup_costs" + ("_settle" if args.settle else ""),
                "Seed 002: the parts of the estimate with the environment" + tail, text, args.quick, time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
