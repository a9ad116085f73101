"""Seed 002: how Levenberg–Marquardt converges with the barrier, iteration by iteration.

Question: why does the winning start need 3–5× the iterations of the estimate without the
environment (issue 34's "environment term ≤ 3×")? Is it the damping, the step limit, the stopping
rule, or the model of the barrier?

Problem: the walk of ``trajectory_speed.py`` (``problem_of(T, seed)``), Levenberg–Marquardt with the
barrier from the shortest-path start (the start that wins the race on these walks), the default
``SolverOptions``. Per iteration: objective F, its relative decrease, the damping μ (relative to
diag H), the largest floor move of the undamped-limit step (the Gauss–Newton step before the
``max_move`` limit), how many states the limit shortened (since 34i: how many moved beyond it, the step
then shaped by the look-ahead, ``SolverOptions.look_ahead``), the largest move taken, the barrier cost;
since 34k the gain ratio ρ (actual ÷ predicted decrease) split by term: the decrease the Gauss–Newton model
predicts for the step taken and the actual one, for the terms without the barrier (motion, pixels, height)
and for the barrier, each term's curvature along the step (secant, 2·(g(X + δ) − g(X))·δ) ÷ the model's
(2·δᵀHδ), and the barrier samples within the clearance; and how this step continues the last one, window by
window (``WINDOW`` steps; windows where the step moves a state > 1 cm): how many go on in the same direction
(cos > 0.95, with the median length ratio this ÷ last) and how many turn back (cos < −0.9).
Then the same run goes on with the tolerance 1e-13 (``--tight-iterations`` more at most): how far the
default stop (relative decrease 1e-5) is from the optimum its own path leads to, in objective and
in metres.

Run: ``.venv/bin/python benchmarks/trajectory_lm_trace.py [--sizes 1000,10000] [--seeds 3]
[--shrink-on-reject]`` (the option: a rejected step shortened as a trust region).
Writes ``benchmarks/results/trajectory_lm_trace.md``. About a minute per (T, seed).
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table, save_result  # noqa: E402
from trajectory_common import pin_to_one_core  # noqa: E402
from trajectory_speed import problem_of  # noqa: E402

from worldtrack.trajectory.estimate import TrajectoryOptions, build_environment  # noqa: E402
from worldtrack.trajectory.model import TimeGrid  # noqa: E402
from worldtrack.trajectory.kernels import model_decrease  # noqa: E402
from worldtrack.trajectory.objective import Linearisation, Problem, linearise  # noqa: E402
from worldtrack.trajectory.solver import LevenbergMarquardt  # noqa: E402
from worldtrack.trajectory.starts import shortest_path_start  # noqa: E402


def floor_moves(delta: np.ndarray) -> np.ndarray:
    """(n,) horizontal move of every state (m) of a step δ (n, 6)."""
    return np.hypot(delta[:, 0], delta[:, 2])


#: Steps per window for comparing a step with the last one (25 s at 10 steps/s).
WINDOW = 250


def continuation(step: np.ndarray, last: np.ndarray | None) -> list[str]:
    """Columns: windows (``WINDOW`` steps) where ``step`` (n, 6) moves a state > 1 cm, of them those going on
    along ``last`` (cos > 0.95) with the median length ratio, and those turning back (cos < −0.9)."""
    if last is None:
        return ["", "", ""]
    same, ratios, back, moving = 0, [], 0, 0
    for a in range(0, len(step), WINDOW):
        u, v = last[a:a + WINDOW][:, [0, 2]].ravel(), step[a:a + WINDOW][:, [0, 2]].ravel()
        if np.abs(v).max(initial=0.0) <= 0.01 or not np.any(u):
            continue
        moving += 1
        cos = float(u @ v / (np.linalg.norm(u) * np.linalg.norm(v)))
        same, back = same + (cos > 0.95), back + (cos < -0.9)
        if cos > 0.95:
            ratios.append(np.linalg.norm(v) / np.linalg.norm(u))
    return [moving, f"{same} ({np.median(ratios):.2f})" if ratios else "0", back]


def split_by_term(free: Problem, X: np.ndarray, delta: np.ndarray, lin: Linearisation,
                  after: Linearisation) -> list[str]:
    """Columns of one accepted step δ (n, 6) from X (n, 6): ρ, then for the terms without the barrier
    (``free``) and for the barrier the predicted and actual decrease and the curvature ratio along δ;
    ``lin`` / ``after``: the whole objective linearised at X / X + δ."""
    f0, f1 = linearise(free, X), linearise(free, X + delta)
    parts = []
    for (g0, D0, B0, F0), (g1, F1) in (((f0.g, f0.D, f0.B, f0.costs.total), (f1.g, f1.costs.total)),
                                        ((lin.g - f0.g, lin.D - f0.D, lin.B - f0.B, lin.costs.barrier),
                                         (after.g - f1.g, after.costs.barrier))):
        predicted = model_decrease(D0, B0, g0, delta)
        curvature = -(predicted + 2 * float(np.sum(g0 * delta)))        # δᵀHδ of the model
        secant = float(np.sum((g1 - g0) * delta))
        parts.append((predicted, F0 - F1, secant / curvature if curvature > 0 else float("nan")))
    total = parts[0][0] + parts[1][0]
    rho = (parts[0][1] + parts[1][1]) / total if total > 0 else float("nan")
    return [f"{rho:.2f}"] + [f"{v:.2e}" if k < 2 else f"{v:.2f}" for part in parts for k, v in enumerate(part)]


def trace(T: int, seed: int, tight_iterations: int, shrink_on_reject: bool) -> tuple[list[list], dict]:
    """Rows of the per-iteration table and the summary of one (T, seed)."""
    scene, obs, height = problem_of(T, seed)
    field = scene.distance_field(0.05)
    opts = TrajectoryOptions(height=height)
    grid = TimeGrid.covering(obs.time, 0.1)
    problem = Problem.build(obs, grid, opts.motion, build_environment(opts, field, 0.1))
    X0 = shortest_path_start(problem.observations, grid, height, field, opts.clearance)
    free = problem.with_environment(problem.environment.without_barrier())
    lm = LevenbergMarquardt(problem, X0, replace(opts.solver, shrink_on_reject=shrink_on_reject))
    rows, limit, last = [], opts.solver.max_move, None
    while not lm.converged and lm.iterations < opts.solver.max_iterations:
        F, X, mu = lm.lin.costs.total, lm.X, lm.mu
        lm.model_floor()                     # solves (and keeps) the next step: the raw Gauss–Newton step
        raw = floor_moves(lm._pending[0]) if lm._pending is not None else np.zeros(1)
        before, inside = lm.lin.copy(), int((lm.lin.barrier_d < problem.environment.barrier.clearance).sum())
        lm.run(1)
        taken = floor_moves(lm.X - X)
        split = split_by_term(free, X, lm.X - X, before, lm.lin) if lm.X is not X else ["rejected"] + [""] * 6
        rows.append([lm.iterations, f"{lm.lin.costs.total:.6f}", f"{(F - lm.lin.costs.total) / F:.1e}", f"{mu:.0e}",
                     f"{raw.max():.3f}", int((raw > limit).sum()), f"{taken.max():.3f}", int((taken > 0.01).sum()),
                     f"{lm.lin.costs.barrier:.3f}", inside] + split + continuation(lm.X - X, last))
        last = lm.X - X if lm.X is not X else last
    X_stop, F_stop, it_stop = lm.X.copy(), lm.lin.costs.total, lm.iterations
    lm.converged, lm.tolerance = False, 1e-13
    lm.run(tight_iterations)
    summary = {"T": T, "seed": seed, "iterations": it_stop, "F": F_stop, "tight_it": lm.iterations - it_stop,
               "F_tight": lm.lin.costs.total, "excess": F_stop / lm.lin.costs.total - 1,
               "dist": float(floor_moves(X_stop - lm.X).max()), "tight_msg": lm.message}
    return rows, summary


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", default="1000,10000")
    ap.add_argument("--seeds", default="3")
    ap.add_argument("--cpu", type=int, default=1, help="processor to pin to (-1: do not pin)")
    ap.add_argument("--tight-iterations", type=int, default=100)
    ap.add_argument("--shrink-on-reject", action="store_true", help="SolverOptions(shrink_on_reject=True)")
    ap.add_argument("--quick", action="store_true", help="T = 300, seed 3; prints only")
    args = ap.parse_args(argv)
    cpu = pin_to_one_core(None if args.cpu < 0 else args.cpu)
    sizes = [300] if args.quick else [int(s) for s in args.sizes.split(",")]
    seeds = [3] if args.quick else [int(s) for s in args.seeds.split(",")]
    t0 = time.perf_counter()
    head = ["iteration", "F", "ΔF / F", "μ", "raw step, largest move m", "states cut", "move taken m",
            "states moved > 1 cm", "barrier cost", "samples within the clearance", "ρ",
            "no barrier: predicted", "actual", "curvature ÷ model's", "barrier: predicted", "actual",
            "curvature ÷ model's", f"windows of {WINDOW} steps moving", "of them going on (length ratio)",
            "turning back"]
    parts, summaries = [f"({cpu})\n"], []
    for T in sizes:
        for seed in seeds:
            rows, summary = trace(T, seed, args.tight_iterations, args.shrink_on_reject)
            summaries.append(summary)
            parts.append(f"### T = {T}, walk seed {seed}\n\n{markdown_table(head, rows)}\n")
            print(f"T = {T} seed {seed}: {summary['iterations']} iterations ({time.perf_counter() - t0:.0f} s)",
                  file=sys.stderr)
    head2 = ["T", "seed", "iterations (default stop)", "F at the stop", "more iterations to 1e-13", "F tight",
             "stop ÷ tight − 1", "largest move stop → tight, m"]
    rows2 = [[s["T"], s["seed"], s["iterations"], f"{s['F']:.8f}", f"{s['tight_it']} ({s['tight_msg']})",
              f"{s['F_tight']:.8f}", f"{s['excess']:.1e}", f"{s['dist']:.4f}"] for s in summaries]
    text = "## The default stop against the tight optimum of the same path\n\n" + markdown_table(head2, rows2) + \
        "\n\n## Per iteration\n\n" + "\n".join(parts)
    print(text)
    save_result("trajectory_lm_trace", "Seed 002: Levenberg–Marquardt with the barrier, iteration by iteration",
                text, args.quick, time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
