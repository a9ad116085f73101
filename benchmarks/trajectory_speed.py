"""Seed 002's speed on one core, its scaling with T, the environment's cost, and GTSAM as the peer.

Question: how long does the MAP estimate of a T-step trajectory take (T = 1 000 … 100 000), does
it grow linearly, what does the environment term cost, and does the banded solver reach GTSAM's
optimum on exactly the same problem — and how much faster?

Problem: one person walking the office with detours (``make_scenario("non-overlapping",
layout="detours")``, 10 steps/s, a long random route) for T steps; its head (stature − 2 cm, ±1.5 cm
gait bob) projected into the four cameras, given lens distortion k1, k2, p1, p2 (k3 = 0, which
GTSAM's Cal3DS2 lacks), with 2 px noise, on-grid time stamps.

Figures (median of ``--repeats`` runs, pinned to one processor; for *full* and *no environment* also
the least run, and the process's CPU seconds beside the wall seconds: on a shared core the wall
time includes waiting for other jobs, the CPU time does not):

- *full*: ``estimate_trajectory`` as ``worldtrack smooth`` runs it — three starts, the barrier,
  per-step covariances;
- *no environment*: the same with ``environment=False`` (one solve: no barrier);
- *race by gap*: ``estimate_trajectory`` with ``race_by_gap=True`` (the starts chosen window by window);
- *same start*: Levenberg–Marquardt from the shortest-path start with and without the barrier, and
  the time of one iteration's work (linearise + banded solve) with and without it;
- *GTSAM* (``pip install 'worldtrack[gtsam]'``; skipped with one line when absent): the problem without
  the barrier (motion, projections, height) from the same straight-line start, ours against GTSAM's
  LM (``optimize()`` alone, and with building the graph); at T = 1 000 their objectives and
  positions are compared; with the barrier as CustomFactors at the smaller sizes.
- *reference*: one ``scipy.linalg.solveh_banded`` on a random SPD band matrix of the same size
  (n = 6T, 11 super-diagonals), measured in the same run: ``full ÷ ref`` is the estimate's cost in
  banded solves, comparable across machines.

Run: ``.venv/bin/python benchmarks/trajectory_speed.py [--sizes 1000,10000,100000] [--cpu 1]
[--repeats 3] [--quick] [--settle] [--route-timing cubic] [--outward 1.3] [--shrink] [--finish]``. Writes
``benchmarks/results/trajectory_speed.md`` (with ``--settle``: ``_settle.md``; with ``--route-timing cubic``:
``_cubic.md``; with ``--outward``: ``_outward.md``; ``--shrink`` and ``--finish`` add ``_shrink``, ``_finish``).
About 4 minutes
(most of it GTSAM at T = 100 000).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from dataclasses import replace
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import scipy.linalg  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table, save_result  # noqa: E402
import gtsam_peer  # noqa: E402
from trajectory_common import long_office_walk, pin_to_one_core, project_observations  # noqa: E402

from worldtrack.trajectory.estimate import TrajectoryOptions, build_environment, estimate_trajectory  # noqa: E402
from worldtrack.trajectory.model import TimeGrid  # noqa: E402
from worldtrack.trajectory.objective import Problem, linearise  # noqa: E402
from worldtrack.trajectory.solver import SolverOptions, levenberg_marquardt, solve_blocks  # noqa: E402
from worldtrack.trajectory.starts import shortest_path_start, straight_start  # noqa: E402


#: GTSAM with the barrier calls Python once per barrier sample per linearisation: it gets this many iterations.
BARRIER_ITERATIONS = 20


#: CPU seconds (the process's own, not the waiting for a busy core) of the last ``timed`` call: median
#: and minimum over its runs, and the minimum wall seconds.
LAST_CPU = [0.0, 0.0, 0.0]


def timed(fn, repeats: int) -> tuple[float, object]:
    """(median wall seconds, last result) of ``fn()`` over ``repeats`` calls; the median and the least
    CPU seconds (``time.process_time``) and the least wall seconds go to ``LAST_CPU``."""
    times, cpu, out = [], [], None
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        times.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    LAST_CPU[:] = [statistics.median(cpu), min(cpu), min(times)]
    return statistics.median(times), out


def reference_solve(n_steps: int, repeats: int) -> float:
    rng = np.random.default_rng(0)
    ab = np.abs(rng.normal(size=(12, 6 * n_steps)))
    ab[-1] += 30.0
    rhs = rng.normal(size=6 * n_steps)
    return timed(lambda: scipy.linalg.solveh_banded(ab, rhs, check_finite=False), max(repeats, 3))[0]


def problem_of(T: int, seed: int):
    scene, t, pts, height = long_office_walk(T + 400, seed)
    obs, _ = project_observations(scene.cameras, t, pts, 2.0, np.random.default_rng(seed + 7))
    first = obs.time[0]
    obs = obs.subset(obs.time < first + T * 0.1 - 1e-9)
    return scene, obs, height


def run_size(T: int, repeats: int, seed: int, gtsam_max: int, gtsam_barrier_max: int, settle: bool = False,
             route_timing: str = "constant", outward: float | None = None, shrink: bool = False,
             finish: bool = False) -> dict:
    scene, obs, height = problem_of(T, seed)
    field = scene.distance_field(0.05)
    opts = TrajectoryOptions(height=height, settle_windows=settle, route_timing=route_timing,
                             solver=SolverOptions(outward_curvature=outward, shrink_on_reject=shrink,
                                                  finish_newton=finish))
    out = {"T": T}
    out["full"], est = timed(lambda: estimate_trajectory(obs, field, opts), repeats)
    out["full_cpu"], out["full_cpu_min"], out["full_min"] = LAST_CPU
    out["n"] = len(est.times)
    out["start"] = est.start
    out["iterations"] = sum(r.iterations for r in est.results.values())
    out["no_env"], _ = timed(lambda: estimate_trajectory(obs, field, replace(opts, environment=False)), repeats)
    out["no_env_cpu"], out["no_env_cpu_min"], out["no_env_min"] = LAST_CPU
    _, gap = timed(lambda: estimate_trajectory(obs, field, replace(opts, race_by_gap=True)), repeats)
    out["gap_cpu"], out["gap_cpu_min"], _ = LAST_CPU
    out["gap_excess"] = gap.costs["total"] / est.costs["total"] - 1
    out["gap_wins"] = ", ".join(f"{k} {v}" for k, v in gap.window_wins.items())
    grid = TimeGrid.covering(obs.time, 0.1)
    env = build_environment(opts, field, 0.1)
    problem = Problem.build(obs, grid, opts.motion, env)
    free = problem.with_environment(env.without_barrier())
    X_short = shortest_path_start(problem.observations, grid, height, field, opts.clearance)
    out["lm_env"], r_env = timed(lambda: levenberg_marquardt(problem, X_short, opts.solver), repeats)
    out["lm_free"], r_free = timed(lambda: levenberg_marquardt(free, X_short, opts.solver), repeats)
    out["it_env"], out["it_free"] = r_env.iterations, r_free.iterations
    step = lambda p: solve_blocks(*(lambda l: (l.D, l.B, -l.g))(linearise(p, X_short)))  # noqa: E731
    out["iter_env"], _ = timed(lambda: step(problem), max(repeats, 3))
    out["iter_free"], _ = timed(lambda: step(free), max(repeats, 3))
    out["ref"] = reference_solve(out["n"], repeats)
    X0 = straight_start(problem.observations, grid, height)
    if gtsam_peer.available() and T <= gtsam_max:
        out["ours_nb"], ours = timed(lambda: levenberg_marquardt(free, X0, opts.solver), repeats)
        peer = gtsam_peer.solve(free, X0)
        out.update(gtsam_solve=peer.solve_s, gtsam_build=peer.build_s, gtsam_it=peer.iterations,
                   ours_it=ours.iterations, obj_ours=ours.costs.total, obj_gtsam=peer.objective,
                   pos_diff=float(np.abs(ours.X[:, [0, 2, 4]] - peer.X[:, [0, 2, 4]]).max()))
        if T <= gtsam_barrier_max:
            peer_b = gtsam_peer.solve(problem, X_short, with_barrier=True, max_iterations=BARRIER_ITERATIONS)
            out.update(gtsam_b_solve=peer_b.solve_s, gtsam_b_obj=peer_b.objective, ours_b_obj=r_env.costs.total,
                       gtsam_b_it=peer_b.iterations)
    return out


def tables(results: list[dict], cpu: str) -> str:
    rows = [[r["T"], r["n"], f"{r['full_min']:.3g} / {r['full']:.3g}", f"{r['full_cpu_min']:.3g} / {r['full_cpu']:.3g}",
             r["full"] / r["ref"], f"{r['no_env_min']:.3g} / {r['no_env']:.3g}",
             f"{r['no_env_cpu_min']:.3g} / {r['no_env_cpu']:.3g}", r["full"] / r["no_env"],
             r["full_cpu"] / r["no_env_cpu"], r["lm_env"],
             r["lm_free"], r["lm_env"] / r["lm_free"], f"{r['it_env']}/{r['it_free']}", r["iter_env"] * 1e3,
             r["iter_free"] * 1e3, r["iter_env"] / r["iter_free"], r["ref"] * 1e3, r["start"], r["iterations"]]
            for r in results]
    text = markdown_table(["T", "steps", "full s (min / median)", "full CPU s (min / median)", "full ÷ ref",
                           "no environment s (min / median)", "no environment CPU s (min / median)", "full ÷ no env",
                           "full ÷ no env (CPU)",
                           "same start, barrier s", "same start, no barrier s", "ratio", "LM iterations",
                           "one iteration, barrier ms", "one iteration, no barrier ms", "ratio", "ref (banded solve) ms",
                           "start won", "LM iterations, all starts"], rows)
    text += ("\n\nThe race by gap (``race_by_gap=True``, :mod:`worldtrack.trajectory.windows`), CPU seconds, "
             "against the same estimate without environment:\n\n") + markdown_table(
        ["T", "race by gap CPU s (min / median)", "÷ no env (CPU, medians)", "÷ no env (CPU, least)",
         "default ÷ no env (CPU, least)", "objective ÷ default − 1", "windows won (ties count for each)"],
        [[r["T"], f"{r['gap_cpu_min']:.3g} / {r['gap_cpu']:.3g}", r["gap_cpu"] / r["no_env_cpu"],
          r["gap_cpu_min"] / r["no_env_cpu_min"], r["full_cpu_min"] / r["no_env_cpu_min"], f"{r['gap_excess']:+.1e}",
          r["gap_wins"]] for r in results])
    by_T = {r["T"]: r for r in results}
    if 1000 in by_T and 10000 in by_T:
        text += (f"\n\nScaling: full(10 000) / full(1 000) = {by_T[10000]['full'] / by_T[1000]['full']:.1f} "
                 f"(CPU seconds: {by_T[10000]['full_cpu'] / by_T[1000]['full_cpu']:.1f}; "
                 f"in banded solves: {by_T[10000]['full'] / by_T[10000]['ref'] / (by_T[1000]['full'] / by_T[1000]['ref']):.2f}).")
    if 100000 in by_T and 10000 in by_T:
        text += f" full(100 000) / full(10 000) = {by_T[100000]['full'] / by_T[10000]['full']:.1f}."
    peer = [r for r in results if "gtsam_solve" in r]
    if peer:
        text += "\n\n## GTSAM on the same problem without the barrier (same start)\n\n" + markdown_table(
            ["T", "ours s", "GTSAM optimize s", "GTSAM build + optimize s", "GTSAM ÷ ours (optimize)",
             "iterations ours / GTSAM", "objective ours", "objective GTSAM", "relative difference",
             "max position difference m"],
            [[r["T"], r["ours_nb"], r["gtsam_solve"], r["gtsam_solve"] + r["gtsam_build"],
              r["gtsam_solve"] / r["ours_nb"], f"{r['ours_it']}/{r['gtsam_it']}", f"{r['obj_ours']:.9g}",
              f"{r['obj_gtsam']:.9g}", f"{abs(r['obj_ours'] - r['obj_gtsam']) / r['obj_gtsam']:.1e}",
              f"{r['pos_diff']:.1e}"] for r in peer])
        withb = [r for r in peer if "gtsam_b_solve" in r]
        if withb:
            text += ("\n\nWith the barrier (GTSAM: one Python CustomFactor per barrier sample, at most "
                     f"{BARRIER_ITERATIONS} iterations), from the shortest-path start:\n\n") + \
                markdown_table(["T", "ours s", "ours iterations", "GTSAM optimize s", "GTSAM iterations",
                                "GTSAM s per iteration ÷ ours", "objective ours", "objective GTSAM"],
                               [[r["T"], r["lm_env"], r["it_env"], r["gtsam_b_solve"], r["gtsam_b_it"],
                                 (r["gtsam_b_solve"] / max(r["gtsam_b_it"], 1)) / (r["lm_env"] / max(r["it_env"], 1)),
                                 f"{r['ours_b_obj']:.6g}", f"{r['gtsam_b_obj']:.6g}"] for r in withb])
    else:
        text += ("\n\nGTSAM: not installed (pip install 'worldtrack[gtsam]') or not asked for (--gtsam-max); the peer "
                 "comparison was skipped.")
    return f"One processor ({cpu}), medians.\n\n" + text


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", default="1000,10000,100000")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--cpu", type=int, default=1, help="processor to pin to (-1: do not pin)")
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--gtsam-max", type=int, default=100000, help="largest T to run GTSAM on")
    ap.add_argument("--gtsam-barrier-max", type=int, default=1000, help="largest T for GTSAM with the barrier")
    ap.add_argument("--quick", action="store_true", help="T = 1 000 and 3 000, one repeat; prints only")
    ap.add_argument("--settle", action="store_true", help="full with settle_windows=True (opt-in, 34b); "
                    "writes results/trajectory_speed_settle.md")
    ap.add_argument("--route-timing", default="constant", choices=["constant", "cubic"],
                    help="full with TrajectoryOptions.route_timing (opt-in cubic, 34m); writes _cubic.md")
    ap.add_argument("--outward", type=float, default=None,
                    help="SolverOptions.outward_curvature (opt-in, 34n; e.g. 1.3); writes _outward.md")
    ap.add_argument("--shrink", action="store_true", help="SolverOptions.shrink_on_reject (opt-in, 34g); adds _shrink")
    ap.add_argument("--finish", action="store_true", help="SolverOptions.finish_newton (opt-in, 34o: with --outward, "
                    "Newton's matrix after the outward run stops); adds _finish")
    args = ap.parse_args(argv)
    cpu = pin_to_one_core(None if args.cpu < 0 else args.cpu)
    sizes = [1000, 3000] if args.quick else [int(s) for s in args.sizes.split(",")]
    repeats = 1 if args.quick else args.repeats
    if not gtsam_peer.available():
        print("trajectory_speed: gtsam not installed (pip install 'worldtrack[gtsam]'); GTSAM columns skipped")
    t_start = time.perf_counter()
    scene, obs, height = problem_of(300, args.seed)                      # load the compiled kernels untimed
    estimate_trajectory(obs, scene.distance_field(0.05), TrajectoryOptions(height=height))
    results = []
    for T in sizes:
        results.append(run_size(T, repeats, args.seed, args.gtsam_max, args.gtsam_barrier_max, args.settle,
                                args.route_timing, args.outward, args.shrink, args.finish))
        print(f"T = {T}: full {results[-1]['full']:.2f} s ({time.perf_counter() - t_start:.0f} s)", file=sys.stderr)
    text = tables(results, cpu)
    print(text)
    tail = ("_settle" if args.settle else "") + ("_cubic" if args.route_timing != "constant" else "") + \
        ("_outward" if args.outward is not None else "") + ("_shrink" if args.shrink else "") + \
        ("_finish" if args.finish else "")
    save_result("trajectory_speed" + tail, "Seed 002: speed on one core, scaling, environment cost, GTSAM"
                + (" (settle_windows)" if args.settle else "") + (" (route_timing='cubic')" if "cubic" in tail else "")
                + (f" (outward_curvature={args.outward})" if args.outward is not None else "")
                + (" (shrink_on_reject)" if args.shrink else "") + (" (finish_newton)" if args.finish else ""),
                text, args.quick, time.perf_counter() - t_start, script="trajectory_speed")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
