"""Seed 002: four changes to the barrier's Levenberg–Marquardt step, against the default, on the speed walks.

Question: issue 34's unmet line is "environment term ≤ 3× the time without it". The winning start's
Levenberg–Marquardt with the barrier needs 20–35 iterations where the estimate without it needs 5–9
(``trajectory_lm_trace.py``): can a different step — one that follows the obstacles, goes further where
the model is pessimistic, or corrects the straight step to second order — reach the same optimum in
markedly fewer iterations (≤ ~11 at T = 10 000 would be needed for 3×)?

Problem: the walks of ``trajectory_speed.py`` (``problem_of(T, seed)``), Levenberg–Marquardt with the
barrier from the shortest-path start (the start that wins the race on these walks), the default
``SolverOptions``. Each variant changes only the step (after the default's look-ahead / move limit) and
keeps LM's acceptance: a changed step that does not lower F is followed by the plain Gauss–Newton step
(kept, no new solve), so F still falls monotonically and a fixed point (g = 0, δ = 0) is the same optimum.

- *window scale*: each window between observed runs (``windows.window_cuts``) scales its step by its own
  factor, doubled (≤ 4) after a step whose window gain ratio ρ_w was > 1.25, halved (≥ 1) after ρ_w < 0.75;
- *window extrapolation*: a window whose Gauss–Newton step goes on along its last one (cos > 0.95, length
  ratio q in 0.3–0.97) takes δ / (1 − q) (≤ 4): the geometric series of steps that shrink by q;
- *projection*: after the step, every state within 0.3 m of the clearance is moved along the field's
  gradient at its new place to the distance the linear model predicted (d + ∇d·δp): a slide round a
  convex end then keeps its distance instead of drifting outward (velocities: the derivative of the shift);
  *smoothed*: the shift first averaged twice over ± 1.5 s (31 steps), as a motion the prior can follow;
- *geodesic* (Transtrum & Sethna 2011): δ = v + ½a with a = −(H + μD)⁻¹ J_bᵀ r_vv, r_vv the barrier
  residuals' second directional derivative along v by finite differences (step h·v), kept if 2|a| ≤ 0.75|v|.

Columns: iterations and CPU ms (least of ``--repeats``) of the default and of each variant, the variant's
objective against the default's stop (relative) and the largest floor distance between the two estimates
(a variant's CPU ms include one more linearisation at the start, for the per-step costs the window variants read;
"steps changed / fallbacks": steps the variant changed, and of them those that raised F and were replaced).
The mechanism columns (default run): the least distance of any barrier sample to an obstacle at the stop
(the clearance is 0.2 m, the hinge's softness 3 cm), and the largest floor move of each of the last five
iterations.

Run: ``.venv/bin/python benchmarks/trajectory_lm_variants.py [--sizes 1000,10000] [--seeds 3,42,90]``.
Writes ``benchmarks/results/trajectory_lm_variants.md``. About a minute per (T, seed).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
from scipy.ndimage import uniform_filter1d

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table, save_result  # noqa: E402
from trajectory_common import least_cpu, walks_of, walks_parser  # noqa: E402
from trajectory_speed import problem_of  # noqa: E402

from worldtrack.trajectory.environment import barrier_residuals, sample_field  # noqa: E402
from worldtrack.trajectory.estimate import TrajectoryOptions, build_environment  # noqa: E402
from worldtrack.trajectory.kernels import block_cholesky_solve, block_matvec, model_decrease  # noqa: E402
from worldtrack.trajectory.model import TimeGrid  # noqa: E402
from worldtrack.trajectory.objective import Problem, linearise  # noqa: E402
from worldtrack.trajectory.solver import LevenbergMarquardt  # noqa: E402
from worldtrack.trajectory.starts import shortest_path_start  # noqa: E402
from worldtrack.trajectory.windows import window_cuts, window_sums  # noqa: E402

#: Largest factor a window's step is scaled or extrapolated by.
MOST = 4.0


class VariantLM(LevenbergMarquardt):
    """The default Levenberg–Marquardt with the barrier, its (limited) step v changed by :meth:`change`
    (None: unchanged); a changed step that does not lower F is followed by the plain one."""

    def __init__(self, problem: Problem, X0: np.ndarray, options, **kw):
        super().__init__(problem, X0, options)
        self.kw, self.changed, self.fallbacks, self._plain = kw, 0, 0, False
        n = len(self.X)
        self.first = window_cuts(np.bincount(problem.observations.step, minlength=n) > 0)[:-1]
        self.owner = np.repeat(np.arange(len(self.first)), np.diff(np.r_[self.first, n]))
        self.scale = np.ones(len(self.first))
        self.cost, self.trial_cost, self.last = np.empty(n), np.empty(n), None
        self.lin = linearise(problem, self.X, out=self.lin, step_cost=self.cost)

    def change(self, v: np.ndarray, damping: np.ndarray) -> np.ndarray | None:
        return None

    def accepted(self, v: np.ndarray, delta: np.ndarray, lin, trial) -> None:
        """After an accepted step δ (from v) from ``lin`` to ``trial`` (``self.cost`` still at X)."""

    def _iterate(self) -> None:
        lin, options = self.lin, self.options
        step, self._pending = self._pending or self._step(lin), None
        if step is None:
            self.mu, self.nu = self.mu * self.nu, self.nu * 2
            return
        v, damping = step
        predicted = float(-np.sum(lin.g * v) + np.sum(damping * v ** 2))
        v, predicted = self._limit(lin, v, predicted)
        delta = None if self._plain else self.change(v, damping)
        self._plain, changed = False, delta is not None
        if changed:
            predicted = model_decrease(lin.D, lin.B, lin.g, delta)
            self.changed += 1
        else:
            delta = v
        trial = linearise(self.problem, self.X + delta, out=self._spare, step_cost=self.trial_cost)
        actual = lin.costs.total - trial.costs.total
        rho = actual / predicted if predicted > 0 else -1.0
        if changed and not (np.isfinite(trial.costs.total) and actual > 0):
            self.fallbacks, self._plain, self._pending, self.last = self.fallbacks + 1, True, step, None
            self.scale[:] = 1.0
            return
        if np.isfinite(trial.costs.total) and (rho > 0 or changed):
            self.accepted(v, delta, lin, trial)
            self.X, self.lin, self._spare = self.X + delta, trial, lin
            self.cost, self.trial_cost = self.trial_cost, self.cost
            rho = max(rho, 1e-3)
            self.mu *= max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3)
            self.nu = 2.0
            if rho > 0.75:
                self.move_limit = min(2.0 * self.move_limit, options.max_move)
            if actual <= self.tolerance * max(lin.costs.total, 1e-300) and not self._model_disagrees():
                self.message, self.converged = "objective settled", True
            elif np.abs(delta).max() <= options.step_size:
                self.message, self.converged = "step below tolerance", True
            else:
                self.message = "running"
            return
        self.mu, self.nu = self.mu * self.nu, self.nu * 2
        if self.mu > 1e12 or predicted <= 1e-14 * max(lin.costs.total, 1e-300):
            self.message, self.converged = "no further decrease possible", True

    def window(self, per_state: np.ndarray) -> np.ndarray:
        return window_sums(per_state, self.first)


class WindowScale(VariantLM):
    def change(self, v, damping):
        return v * self.scale[self.owner][:, None] if (self.scale > 1).any() else None

    def accepted(self, v, delta, lin, trial):
        predicted = self.window(-(2 * lin.g * delta + delta * block_matvec(lin.D, lin.B, delta)).sum(axis=1))
        actual = self.window(self.cost - self.trial_cost)
        small = np.abs(predicted) <= 1e-3 * max(float(predicted.sum()), 1e-300)
        rho = np.where(small, 1.0, actual / np.where(small, 1.0, predicted))
        self.scale = np.where(rho > 1.25, np.minimum(2 * self.scale, MOST),
                              np.where(rho < 0.75, np.maximum(1.0, self.scale / 2), self.scale))


class WindowExtrapolation(VariantLM):
    def change(self, v, damping):
        self.raw, last = v, self.last
        if last is None:
            return None
        vv, ll = self.window((v * v).sum(1)), self.window((last * last).sum(1))
        cos = self.window((v * last).sum(1)) / np.sqrt(np.maximum(vv * ll, 1e-300))
        q = np.sqrt(vv / np.maximum(ll, 1e-300))
        go = (cos > 0.95) & (q > 0.3) & (q < 0.97) & (vv > 1e-8)
        if not go.any():
            return None
        factor = np.ones(len(q))
        factor[go] = np.minimum(1.0 / (1.0 - q[go]), MOST)
        return v * factor[self.owner][:, None]

    def accepted(self, v, delta, lin, trial):
        self.last = v


class Projection(VariantLM):
    def change(self, v, damping):
        barrier = self.problem.environment.barrier
        p0 = self.X[:, [0, 2]]
        p1 = p0 + v[:, [0, 2]]
        d0, g0 = sample_field(barrier.field, p0)
        d1, g1 = sample_field(barrier.field, p1)
        g2 = (g1 ** 2).sum(axis=1)
        near = (np.minimum(d0, d1) < barrier.clearance + 0.3) & (g2 > 0.25)
        if not near.any():
            return None
        shift = np.where(near, (d0 + (g0 * (p1 - p0)).sum(axis=1) - d1) / np.where(near, g2, 1.0), 0.0)[:, None] * g1
        for _ in range(2 if self.kw.get("smooth", 1) > 1 else 0):     # twice a running mean: a smooth shift
            shift = uniform_filter1d(shift, self.kw["smooth"], axis=0, mode="nearest")
        out = v.copy()
        out[:, [0, 2]] += shift
        out[:, [1, 3]] += np.gradient(shift, self.problem.grid.dt, axis=0)
        return out


class Geodesic(VariantLM):
    def change(self, v, damping):
        env, dt, h = self.problem.environment, self.problem.grid.dt, self.kw["h"]
        b0 = barrier_residuals(self.X, env.barrier, env.weight, dt, only_active=False)
        bh = barrier_residuals(self.X + h * v, env.barrier, env.weight, dt, only_active=False)
        t = b0.step
        Jv = (b0.J[:, :6] * v[t]).sum(axis=1) + (b0.J[:, 6:] * v[t + 1]).sum(axis=1)
        rvv = 2.0 * ((bh.r - b0.r) / h - Jv) / h
        rhs = np.zeros_like(v)
        np.add.at(rhs, t, b0.J[:, :6] * rvv[:, None])
        np.add.at(rhs, t + 1, b0.J[:, 6:] * rvv[:, None])
        L, C, y, x = self._work
        if not block_cholesky_solve(self.lin.D, self.lin.B, damping, -rhs, L, C, y, x):
            return None
        return v + 0.5 * x if 2 * np.linalg.norm(x) <= 0.75 * np.linalg.norm(v) else None


VARIANTS = {"window scale": (WindowScale, {}), "window extrapolation": (WindowExtrapolation, {}),
            "projection": (Projection, {}), "projection, smoothed": (Projection, {"smooth": 31}), "geodesic h = 0.1": (Geodesic, {"h": 0.1}),
            "geodesic h = 1": (Geodesic, {"h": 1.0})}



def run(T: int, seed: int, repeats: int) -> list[list]:
    scene, obs, height = problem_of(T, seed)
    field = scene.distance_field(0.05)
    opts = TrajectoryOptions(height=height)
    grid = TimeGrid.covering(obs.time, 0.1)
    problem = Problem.build(obs, grid, opts.motion, build_environment(opts, field, 0.1))
    X0 = shortest_path_start(problem.observations, grid, height, field, opts.clearance)
    moves, X = [], X0
    ref = LevenbergMarquardt(problem, X0, opts.solver)
    while not ref.converged and ref.iterations < opts.solver.max_iterations:
        ref.run(1)
        moves.append(float(np.hypot(*(ref.X - X)[:, [0, 2]].T).max()))
        X = ref.X
    base_s, base = least_cpu(lambda: LevenbergMarquardt(problem, X0, opts.solver).run(), repeats)
    mechanism = [f"{ref.lin.barrier_d.min():.3f}", " ".join(f"{m:.3f}" for m in moves[-5:])]
    rows = [[T, seed, "default", base.iterations, "", f"{base_s * 1e3:.1f}", "", ""] + mechanism]
    for name, (cls, kw) in VARIANTS.items():
        def solve():
            lm = cls(problem, X0, opts.solver, **kw)
            return lm, lm.run()
        s, (lm, res) = least_cpu(solve, repeats)
        gap = float(np.hypot(*(res.X - base.X)[:, [0, 2]].T).max())
        rows.append([T, seed, name, res.iterations, f"{lm.changed} / {lm.fallbacks}", f"{s * 1e3:.1f}",
                     f"{res.costs.total / base.costs.total - 1:+.1e}", f"{gap:.3f}", "", ""])
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = walks_parser(__doc__, 2)
    args = ap.parse_args(argv)
    cpu, sizes, seeds, repeats = walks_of(args)
    t0 = time.perf_counter()
    rows = []
    for T in sizes:
        for seed in seeds:
            rows += run(T, seed, repeats)
            print(f"T = {T} seed {seed} ({time.perf_counter() - t0:.0f} s)", file=sys.stderr)
    text = f"({cpu}; CPU ms: the least of {repeats})\n\n" + markdown_table(
        ["T", "seed", "step", "iterations", "steps changed / fallbacks", "CPU ms", "F ÷ default − 1",
         "largest floor distance to the default m", "least sample distance at the stop m",
         "largest move, last five iterations m"], rows)
    print(text)
    save_result("trajectory_lm_variants", "Seed 002: four changes to the barrier's LM step against the default",
                text, args.quick, time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
