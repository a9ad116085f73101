"""Seed 002: does a step on each gap's timing along its path take the along-path error out at once?

Question: 34m found the race leader's last iterations remove the start's error mostly *along* the path (its
timing), and named as next step a Newton step on the timing s(t) of the unobserved steps along their route,
between Levenberg–Marquardt iterations, so that the along-path error goes in one step instead of 10–20
iterations. Does it? And does a line search along the Gauss–Newton step (the tail's gain ratio ρ sits at
1.3–1.8: the step is shorter than the model's own minimum along it) do better?

Problem: the walks of ``trajectory_speed.py`` (``problem_of(T, seed)``); Levenberg–Marquardt with the barrier
from the shortest-path start (the start that wins the race on these walks), default ``SolverOptions``.

- *timing step* (:class:`TimingLM`): every unobserved step moving faster than 5 cm/s keeps only its timing on
  the current path: its position slides by δs along the path's tangent and its velocity stays on the tangent,
  δv = δṡ·t̂ + ṡ·κ·δs·n̂ (κ the path's curvature): two constraints per state, added to the Gauss–Newton matrix
  as a stiff penalty (10⁶ × its largest diagonal entry). Observed steps and the height move freely. The step
  is then carried along the path itself (the states slide along the Hermite curve through the current states,
  their velocities turn with its tangent): a Gauss–Newton step in the path's own coordinates. It is taken if
  it lowers F (one linearisation, as an iteration). Alternated with the iterations (after each one).
- *along / across*: the floor error against the default's stop, along its direction of travel and across it
  (m, RMS over the unobserved steps; ``trajectory_slides.along_across``), after 8 iterations, then after
  1 and 4 timing steps in a row (or 1 and 4 more iterations);
- *line search* (:class:`LineSearchLM`): the step the solver would try, scaled by the first of 1.5, 2, 3 (or
  2, 4, 8) that does not lower F further than the one before; one more evaluation of F per rung.

Each lever: linearisations (iterations + timing steps; evaluations for the line search), its stop's objective
÷ the default's − 1 (≤ 1e-6 or lower is the bar) and the largest floor distance between the two stops (m).

Run: ``.venv/bin/python benchmarks/trajectory_timing_steps.py [--sizes 1000,10000] [--seeds 3,42,90]
[--held-out 200] [--tag held_out] [--quick]``. Writes ``benchmarks/results/trajectory_timing_steps[_<tag>].md``.
About 15 s per walk of T = 10 000.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table  # noqa: E402
from trajectory_common import add_seed_blocks, block_of, rows_of_walks, save_walks, walks_of, walks_parser  # noqa: E402
from trajectory_slides import along_across  # noqa: E402
from trajectory_speed import problem_of  # noqa: E402

from worldtrack.trajectory.environment import hermite_weights  # noqa: E402
from worldtrack.trajectory.estimate import TrajectoryOptions, build_environment  # noqa: E402
from worldtrack.trajectory.kernels import block_cholesky_solve, model_decrease  # noqa: E402
from worldtrack.trajectory.model import TimeGrid, frame_interval  # noqa: E402
from worldtrack.trajectory.objective import Linearisation, Problem, evaluate, linearise  # noqa: E402
from worldtrack.trajectory.solver import LevenbergMarquardt  # noqa: E402
from worldtrack.trajectory.starts import anchor_points, shortest_path_start  # noqa: E402

#: Points per step of the polyline that stands for the Hermite curve through the states.
CURVE_POINTS = 8
#: Slower states (m/s) have no direction of travel: they move freely.
MIN_SPEED = 0.05
#: The constraints' penalty, relative to the state's largest diagonal entry of the Gauss–Newton matrix.
STIFF = 1e6


class PathCurve:
    """The floor path of X (n, 6) as a polyline: the Hermite curve through the states (positions and
    velocities), ``CURVE_POINTS`` points per step, with its arc length and heading."""

    def __init__(self, X: np.ndarray, dt: float):
        H = hermite_weights(np.arange(CURVE_POINTS) / CURVE_POINTS, dt)           # (m, 4)
        p, v = X[:, [0, 2]], X[:, [1, 3]]
        pts = (H[None, :, 0, None] * p[:-1, None] + H[None, :, 1, None] * v[:-1, None]
               + H[None, :, 2, None] * p[1:, None] + H[None, :, 3, None] * v[1:, None]).reshape(-1, 2)
        self.points = np.vstack([pts, p[-1:]])                                    # ((n − 1)·m + 1, 2)
        seg = np.diff(self.points, axis=0)
        self.s = np.r_[0.0, np.cumsum(np.hypot(seg[:, 0], seg[:, 1]))]           # arc length, m
        self.heading = np.unwrap(np.arctan2(seg[:, 1], seg[:, 0]))                # per segment, rad
        self.mid = 0.5 * (self.s[:-1] + self.s[1:])
        self.at_states = self.s[::CURVE_POINTS]                                   # (n,)

    def point(self, s: np.ndarray) -> np.ndarray:
        """(k, 2) floor points at arc lengths s (k,), m."""
        s = np.clip(s, 0.0, self.s[-1])
        return np.column_stack([np.interp(s, self.s, self.points[:, 0]), np.interp(s, self.s, self.points[:, 1])])

    def angle(self, s: np.ndarray) -> np.ndarray:
        """Heading (rad) at arc lengths s."""
        return np.interp(np.clip(s, 0.0, self.s[-1]), self.mid, self.heading)


def timing_constraints(X: np.ndarray, curve: PathCurve, free: np.ndarray, dt: float) -> tuple[np.ndarray, ...]:
    """Per state: the unit tangent t̂ (n, 2) (the velocity's direction), the speed (n,), the curvature κ (n,)
    (1/m) and the two constraint rows (n, 2, 6) that keep a step on the timing — n̂·δp = 0 and
    n̂·δv − ṡ·κ·(t̂·δp) = 0 — zero where ``free`` (n,) bool (the state moves freely)."""
    v = X[:, [1, 3]]
    speed = np.hypot(v[:, 0], v[:, 1])
    t = v / np.maximum(speed, 1e-12)[:, None]
    h = 0.25 * np.maximum(speed * dt, 1e-3)
    kappa = (curve.angle(curve.at_states + h) - curve.angle(curve.at_states - h)) / (2 * h)
    rows = np.zeros((len(X), 2, 6))
    rows[:, 0, 0], rows[:, 0, 2] = -t[:, 1], t[:, 0]                 # n̂ = (−t_y, t_x) on the position
    rows[:, 1, 1], rows[:, 1, 3] = -t[:, 1], t[:, 0]                 # n̂ on the velocity …
    rows[:, 1, 0], rows[:, 1, 2] = -speed * kappa * t[:, 0], -speed * kappa * t[:, 1]   # … − ṡκ t̂ on the position
    rows[free] = 0.0
    return t, speed, kappa, rows


def slide(X: np.ndarray, delta: np.ndarray, curve: PathCurve, tangent: np.ndarray, speed: np.ndarray,
          moving: np.ndarray) -> np.ndarray:
    """X + δ, but every ``moving`` state slides along the curve by δs = t̂·δp with its velocity turned with the
    curve's tangent, at speed ṡ + t̂·δv (the other states: X + δ)."""
    out = X + delta
    k = np.flatnonzero(moving)
    ds = delta[k, 0] * tangent[k, 0] + delta[k, 2] * tangent[k, 1]
    s0 = curve.at_states[k]
    xy = curve.point(s0 + ds)
    out[k, 0], out[k, 2] = xy[:, 0], xy[:, 1]
    turn = curve.angle(s0 + ds) - curve.angle(s0)
    sdot = speed[k] + delta[k, 1] * tangent[k, 0] + delta[k, 3] * tangent[k, 1]
    c, s = np.cos(turn), np.sin(turn)
    out[k, 1] = sdot * (c * tangent[k, 0] - s * tangent[k, 1])
    out[k, 3] = sdot * (s * tangent[k, 0] + c * tangent[k, 1])
    return out


class TimingLM(LevenbergMarquardt):
    """Levenberg–Marquardt with a timing step (see the module notes) after every iteration that did not stop
    (``alternate``; else only when :meth:`timing_step` is called)."""

    def __init__(self, problem: Problem, X0: np.ndarray, options, alternate: bool = True):
        super().__init__(problem, X0, options)
        self.alternate = alternate
        self.unobserved = np.bincount(problem.observations.step, minlength=len(X0)) == 0
        self.tried = self.taken = 0

    def _iterate(self) -> None:
        super()._iterate()
        if self.alternate and not self.converged:
            self.timing_step()

    def timing_step(self) -> bool:
        """One timing step from the current X; whether it lowered F (then X and the linearisation are its)."""
        X, lin, dt = self.X, self.lin, self.problem.grid.dt
        curve = PathCurve(X, dt)
        speed0 = np.hypot(X[:, 1], X[:, 3])
        moving = self.unobserved & (speed0 > MIN_SPEED)
        tangent, speed, _, rows = timing_constraints(X, curve, ~moving, dt)
        diag = np.diagonal(lin.D, axis1=1, axis2=2)
        stiff = STIFF * np.maximum(diag[:, :4].max(axis=1), 1.0)
        D = lin.D + stiff[:, None, None] * np.einsum("nki,nkj->nij", rows, rows)
        damping = self.mu * np.maximum(diag, 1e-12)
        L, C, y, x = self._work
        self.tried += 1
        if not block_cholesky_solve(D, lin.B, damping, -lin.g, L, C, y, x):
            return False
        trial = linearise(self.problem, slide(X, x.copy(), curve, tangent, speed, moving), out=self._spare)
        if not (np.isfinite(trial.costs.total) and trial.costs.total < lin.costs.total):
            return False
        self.X, self.lin, self._spare = slide(X, x.copy(), curve, tangent, speed, moving), trial, lin
        self._pending = self._rejected = None
        self.taken += 1
        return True


class LineSearchLM(LevenbergMarquardt):
    """Levenberg–Marquardt whose step (after the move limit) is scaled by the first rung of ``ladder`` that does
    not lower F further than the rung before (1: the step as it was)."""

    def __init__(self, problem: Problem, X0: np.ndarray, options, ladder: tuple[float, ...]):
        super().__init__(problem, X0, options)
        self.ladder, self.evaluations = ladder, 0

    def _limit(self, lin: Linearisation, delta: np.ndarray, predicted: float) -> tuple[np.ndarray, float]:
        delta, predicted = super()._limit(lin, delta, predicted)
        if predicted <= 0:
            return delta, predicted
        best_t, best = 1.0, evaluate(self.problem, self.X + delta).total
        self.evaluations += 1
        for t in self.ladder:
            f = evaluate(self.problem, self.X + t * delta).total
            self.evaluations += 1
            if not f < best:
                break
            best_t, best = t, f
        if best_t == 1.0:
            return delta, predicted
        scaled = best_t * delta
        model = model_decrease(lin.D, lin.B, lin.g, scaled)      # beyond the model's minimum it may be ≤ 0:
        return scaled, model if model > 0 else best_t * predicted  # then the step's own, scaled


# ------------------------------------------------------------------ the table

def setup(T: int, seed: int) -> tuple[Problem, np.ndarray, TrajectoryOptions]:
    """The walk's problem with the barrier, the shortest-path start and the options."""
    scene, obs, height = problem_of(T, seed)
    field = scene.distance_field(0.05)
    opts = TrajectoryOptions(height=height)
    dt = frame_interval(obs.time, obs.camera)
    grid = TimeGrid.covering(obs.time, dt)
    problem = Problem.build(obs, grid, opts.motion, build_environment(opts, field, dt))
    anchors = anchor_points(problem.observations, height)
    return problem, shortest_path_start(problem.observations, grid, height, field, opts.clearance, 0.1, anchors), opts


def row(T: int, seed: int, block: str) -> list:
    problem, X0, opts = setup(T, seed)
    ref = LevenbergMarquardt(problem, X0, opts.solver)
    ref.run()
    unobserved = np.bincount(problem.observations.step, minlength=problem.grid.n) == 0

    def versus(run, count: int) -> str:
        gap = float(np.hypot(*(run.X[:, [0, 2]] - ref.X[:, [0, 2]]).T).max())
        return f"{count} ({run.lin.costs.total / ref.lin.costs.total - 1:+.1e}, {gap:.2f} m)"

    def errors(X: np.ndarray) -> str:
        return "{:.3f} / {:.3f}".format(*along_across(X, ref.X, unobserved))

    timing = TimingLM(problem, X0, opts.solver)
    timing.run()
    after = [errors(X0)]
    for kind in ("timing", "iterations"):
        run = TimingLM(problem, X0, opts.solver, alternate=False)
        run.run(8)
        if kind == "timing":
            after.append(errors(run.X))
        for k in range(4):
            run.timing_step() if kind == "timing" else run.run(1)
            if k in (0, 3):
                after.append(errors(run.X))
    ladders = [LineSearchLM(problem, X0, opts.solver, ladder) for ladder in ((1.5, 2.0, 3.0), (2.0, 4.0, 8.0))]
    for run in ladders:
        run.run()
    return [T, f"{seed} ({block})", ref.iterations, *after,
            versus(timing, timing.iterations + timing.tried) + f" [{timing.iterations} + {timing.taken}/{timing.tried}]",
            *(versus(run, run.evaluations) + f" [{run.iterations} it.]" for run in ladders)]


def main(argv: list[str] | None = None) -> int:
    ap = walks_parser(__doc__, 1)
    add_seed_blocks(ap, "trajectory_timing_steps")
    args = ap.parse_args(argv)
    cpu, sizes, seeds, _ = walks_of(args)
    t0 = time.perf_counter()
    rows = rows_of_walks(sizes, seeds, block_of(args), row)
    text = f"({cpu})\n\nFloor error along / across the path against the default's stop (m, RMS, unobserved steps).\n\n" + \
        markdown_table(["T", "walk", "default iterations", "start: along / across", "after 8 it.",
                        "+ 1 timing step", "+ 4 timing steps", "+ 1 iteration", "+ 4 iterations",
                        "timing step after every iteration: linearisations (F ÷ default − 1, largest gap) "
                        "[iterations + timing steps taken / tried]",
                        "line search 1.5, 2, 3: evaluations (…) [iterations]", "line search 2, 4, 8"], rows)
    print(text)
    save_walks("trajectory_timing_steps", "Seed 002: timing steps along the path, and a line search", text, args,
               time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
