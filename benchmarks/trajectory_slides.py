"""Seed 002: what the leader's last iterations do, and two levers against them that do not change the objective.

Question: issue 34's "environment ≤ 3× without" needs the race's leader to converge in ≈ 10 iterations at
T = 10 000 where it takes 21–35 (34l). Which error of the shortest-path start is left for the last iterations,
why does Gauss–Newton remove it so slowly, and do (a) a better timed start or (b) the distance field's curvature
in the barrier's Gauss–Newton matrix cut the iterations while reaching the default's optimum?

Problem: the walks of ``trajectory_speed.py`` (``problem_of(T, seed)``); Levenberg–Marquardt with the barrier
from the shortest-path start (the start that wins the race on these walks), default ``SolverOptions``.

- *along / across*: the floor error of an iterate against the default's stop, split along the stop's direction
  of travel and across it (m, RMS over the unobserved steps), at the start and after 8 iterations;
- *tangential share*: at iteration 12, the barrier samples whose move in the step is ≥ 90 % along the obstacle
  (across ∇d): their share of the barrier model's error (model − actual change of r²), and their (actual −
  linearised) distance after the step, mean weighted by each sample's |error| (mm) — positive: the field curves
  away under a straight move (round a convex corner), which Gauss–Newton does not see;
- (a) *cubic start*: as ``shortest``, but each routed gap walked with cubic timing s(t) along the route, its end
  speeds the MAP without the barrier's velocities at the gap's ends along the route, instead of at constant speed
  — the motion prior's own timing between two states (``shortest_path_start(..., timing="cubic")``, the opt-in
  ``TrajectoryOptions.route_timing``);
- (b) *curvature*: the Gauss–Newton matrix of every barrier sample plus γ·r·r′·∇²d (the exact Hessian's term
  that Gauss–Newton drops; ∇²d by second differences of the field smoothed over one cell), from iteration k
  (:class:`CurvatureLM`). The gradient, hence every optimum, is unchanged.

Each lever: its iterations, its stop's objective ÷ the default's − 1 (≤ 1e-6 or lower is the bar) and the
largest floor distance between the two stops (m).

Run: ``.venv/bin/python benchmarks/trajectory_slides.py [--sizes 1000,10000] [--seeds 3,42,90] [--held-out 200]
[--never-used 500] [--tag never_used] [--quick]``. Writes ``benchmarks/results/trajectory_slides[_<tag>].md``.
About 10 s per walk of T = 10 000.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
from scipy import ndimage
from scipy.special import expit

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table  # noqa: E402
from trajectory_common import add_seed_blocks, block_of, rows_of_walks, save_walks, walks_of, walks_parser  # noqa: E402
from trajectory_speed import problem_of  # noqa: E402

from worldtrack.scene.floor import FloorGrid  # noqa: E402
from worldtrack.trajectory.environment import Z_CUTOFF, Barrier, hermite_weights, sample_field  # noqa: E402
from worldtrack.trajectory.estimate import TrajectoryOptions, build_environment  # noqa: E402
from worldtrack.trajectory.model import TimeGrid, frame_interval  # noqa: E402
from worldtrack.trajectory.objective import Linearisation, Problem  # noqa: E402
from worldtrack.trajectory.solver import LevenbergMarquardt, levenberg_marquardt  # noqa: E402
from worldtrack.trajectory.starts import anchor_points, shortest_path_start, straight_start  # noqa: E402

FLOOR = [0, 2]          # u, v in the state


# ------------------------------------------------------------------ (b) the field's curvature

def field_hessian(field: FloorGrid, smooth: float = 1.0) -> tuple[FloorGrid, FloorGrid, FloorGrid]:
    """∂²d/∂x², ∂²d/∂x∂y, ∂²d/∂y² (1/m) on the field's grid: second differences of the field smoothed by a
    Gaussian of ``smooth`` cells."""
    v = ndimage.gaussian_filter(field.values, smooth) if smooth > 0 else field.values
    h = field.resolution
    gy, gx = np.gradient(v, h)
    gxy, gxx = np.gradient(gx, h)
    gyy = np.gradient(gy, h)[0]
    return tuple(FloorGrid(field.origin, h, a) for a in (gxx, gxy, gyy))


def sample_points(X: np.ndarray, barrier: Barrier, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every barrier sample's step t (M,), Hermite weights (M, 4) and floor point (M, 2) on X (n, 6)."""
    t, alpha = barrier.samples(len(X))
    H = hermite_weights(alpha, dt)
    x0, x1 = X[t], X[t + 1]
    p = np.column_stack([H[:, 0] * x0[:, i] + H[:, 1] * x0[:, i + 1] + H[:, 2] * x1[:, i] + H[:, 3] * x1[:, i + 1]
                         for i in FLOOR])
    return t, H, p


def curvature_blocks(problem: Problem, X: np.ndarray, hessian, gamma: float) -> tuple[np.ndarray, np.ndarray]:
    """γ·Σ r·r′·Pᵀ∇²d·P over the barrier samples as blocks (n, 6, 6), (n − 1, 6, 6): P (2, 12) maps the two
    states to the sample's floor point, r′ = ∂r/∂d = −gain·σ(z) (half the Hessian of r², as D is)."""
    b, n = problem.environment.barrier, len(X)
    t, H, p = sample_points(X, b, problem.grid.dt)
    z = (b.clearance - sample_field(b.field, p)[0]) / b.softness
    keep = z > Z_CUTOFF
    t, H, p, z = t[keep], H[keep], p[keep], z[keep]
    gain = b.gain(problem.environment.weight)
    c = gamma * gain * b.softness * np.logaddexp(0.0, z) * -gain * expit(z)
    hxx, hxy, hyy = (sample_field(g, p)[0] for g in hessian)
    M = np.stack([np.stack([hxx, hxy], -1), np.stack([hxy, hyy], -1)], -2) * c[:, None, None]
    P = np.zeros((len(t), 2, 12))
    for k, i in enumerate(FLOOR):
        P[:, k, [i, i + 1, 6 + i, 7 + i]] = H
    E = np.einsum("mki,mkl,mlj->mij", P, M, P)
    D, B = np.zeros((n, 6, 6)), np.zeros((n - 1, 6, 6))
    np.add.at(D, t, E[:, :6, :6])
    np.add.at(D, t + 1, E[:, 6:, 6:])
    np.add.at(B, t, E[:, :6, 6:])
    return D, B


class CurvatureLM(LevenbergMarquardt):
    """Levenberg–Marquardt whose barrier model adds :func:`curvature_blocks` (×γ) to every linearisation from
    iteration ``after`` on (the linearisation itself, its costs and gradient, unchanged)."""

    def __init__(self, problem: Problem, X0: np.ndarray, options, gamma: float, after: int = 0):
        self.gamma, self.after, self.hessian = gamma, after, field_hessian(problem.environment.barrier.field)
        super().__init__(problem, X0, options)

    def _step(self, lin: Linearisation):
        if self.iterations < self.after:
            return super()._step(lin)
        D, B = lin.D.copy(), lin.B.copy()
        dD, dB = curvature_blocks(self.problem, self.X, self.hessian, self.gamma)
        lin.D += dD
        lin.B += dB
        try:
            return super()._step(lin)
        finally:
            lin.D[...], lin.B[...] = D, B


# ------------------------------------------------------------------ what the last iterations do

def along_across(X: np.ndarray, ref: np.ndarray, unobserved: np.ndarray) -> tuple[float, float]:
    """RMS (m) over ``unobserved`` steps of X − ref (floor) along ref's direction of travel and across it."""
    e = (X[:, FLOOR] - ref[:, FLOOR])[unobserved]
    v = ref[unobserved][:, [1, 3]]
    u = v / np.maximum(np.linalg.norm(v, axis=1), 1e-9)[:, None]
    along = (e * u).sum(axis=1)
    across = e[:, 0] * u[:, 1] - e[:, 1] * u[:, 0]
    return float(np.sqrt(np.mean(along ** 2))), float(np.sqrt(np.mean(across ** 2)))


def tangential_share(run: LevenbergMarquardt) -> tuple[float, float]:
    """For the run's next step: the share of the barrier model's error (Σ model − actual change of r²) from
    samples moving ≥ 90 % across ∇d, and their (actual − linearised) distance after the step, mean weighted by
    |error| (mm)."""
    problem, X = run.problem, run.X
    b, dt = problem.environment.barrier, problem.grid.dt
    delta, damping = run._step(run.lin)
    delta, _ = run._limit(run.lin, delta, float(-np.sum(run.lin.g * delta) + np.sum(damping * delta ** 2)))
    t, _, p0 = sample_points(X, b, dt)
    p1 = sample_points(X + delta, b, dt)[2]
    d0, g0 = sample_field(b.field, p0)
    d1 = sample_field(b.field, p1)[0]
    gain = b.gain(problem.environment.weight)
    r = lambda d: gain * b.softness * np.logaddexp(0.0, (b.clearance - d) / b.softness)  # noqa: E731
    z0 = (b.clearance - d0) / b.softness
    slope, curv = -gain * expit(z0), gain * expit(z0) * (1 - expit(z0)) / b.softness
    lin_dd = (g0 * (p1 - p0)).sum(axis=1)
    model = 2 * r(d0) * slope * lin_dd + (slope ** 2 + r(d0) * curv) * lin_dd ** 2
    error = model - (r(d1) ** 2 - r(d0) ** 2)
    move = np.linalg.norm(p1 - p0, axis=1)
    tangential = (np.abs(lin_dd) <= np.sqrt(1 - 0.9 ** 2) * move) & (move > 1e-3) & (z0 > Z_CUTOFF)
    share = float(error[tangential].sum() / error.sum()) if error.sum() else float("nan")
    w = np.abs(error) * tangential
    return share, float(np.sum(w * (d1 - d0 - lin_dd)) / np.sum(w) * 1e3) if w.sum() else float("nan")


# ------------------------------------------------------------------ the table

def row(T: int, seed: int, block: str) -> list:
    scene, obs, height = problem_of(T, seed)
    field = scene.distance_field(0.05)
    opts = TrajectoryOptions(height=height)
    dt = frame_interval(obs.time, obs.camera)
    grid = TimeGrid.covering(obs.time, dt)
    problem = Problem.build(obs, grid, opts.motion, build_environment(opts, field, dt))
    free = problem.with_environment(problem.environment.without_barrier())
    anchors = anchor_points(problem.observations, height)
    free_X = levenberg_marquardt(free, straight_start(problem.observations, grid, height, anchors), opts.solver).X
    X0 = shortest_path_start(problem.observations, grid, height, field, opts.clearance, 0.1, anchors)
    run, snaps, share = LevenbergMarquardt(problem, X0, opts.solver), {}, (float("nan"), float("nan"))
    while not run.converged and run.iterations < opts.solver.max_iterations:
        if run.iterations == 12:
            share = tangential_share(run)
        run.run(1)
        snaps[run.iterations] = run.X
    ref = run.result
    unobserved = np.bincount(problem.observations.step, minlength=grid.n) == 0
    a0, c0 = along_across(X0, ref.X, unobserved)
    a8, c8 = along_across(snaps.get(8, ref.X), ref.X, unobserved)

    def versus(res) -> str:
        gap = float(np.hypot(*(res.X[:, FLOOR] - ref.X[:, FLOOR]).T).max())
        return f"{res.iterations} ({res.costs.total / ref.costs.total - 1:+.1e}, {gap:.2f} m)"

    cubic = levenberg_marquardt(problem, shortest_path_start(problem.observations, grid, height, field, opts.clearance,
                                                             0.1, anchors, "cubic", free_X[:, [1, 3]]), opts.solver)
    curv1 = CurvatureLM(problem, X0, opts.solver, 1.0, 0).run()
    curv_half = CurvatureLM(problem, X0, opts.solver, 0.5, 6).run()
    return [T, f"{seed} ({block})", ref.iterations, f"{ref.costs.total:.4f}", f"{a0:.2f} / {c0:.2f}",
            f"{a8:.3f} / {c8:.3f}", f"{share[0]:.0%} ({share[1]:+.1f} mm)", versus(cubic), versus(curv1),
            versus(curv_half)]


def main(argv: list[str] | None = None) -> int:
    ap = walks_parser(__doc__, 1)
    add_seed_blocks(ap, "trajectory_slides")
    args = ap.parse_args(argv)
    cpu, sizes, seeds, _ = walks_of(args)
    t0 = time.perf_counter()
    rows = rows_of_walks(sizes, seeds, block_of(args), row)
    text = f"({cpu})\n\n" + markdown_table(
        ["T", "walk", "default iterations", "default F", "start: along / across m", "after 8: along / across m",
         "tangential share of the barrier model's error at it. 12 (weighted d − linear d)",
         "(a) cubic start: iterations (F ÷ default − 1, largest gap)", "(b) curvature γ = 1 from it. 0",
         "(b) curvature γ = 0.5 from it. 6"], rows)
    print(text)
    save_walks("trajectory_slides", "Seed 002: the leader's last iterations, and two levers", text, args,
               time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
