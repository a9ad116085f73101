"""The race per unobserved gap (beyond the paper): the route is chosen gap by gap, not for the whole track.

Between views the route (which side of a desk, which door) is decided in each long gap on its own:
a gap is tied to the rest of the trajectory only through the observed steps at its two ends, which
the pixels pin down. So the trajectory is cut at the middle of every run of at least ``MIN_RUN``
observed steps (:func:`window_cuts`), and each piece between two cuts — a *window*: one gap and a few
observed steps at each end — is treated on its own, its two end states held at the MAP without the
barrier:

1. each start is spliced in with those ends held; its objective in a window is the sum of the terms
   that touch the window's states (:func:`window_sums`); the lowest wins the window, and the winners
   are spliced into one start;
2. Levenberg–Marquardt on all windows at once (:class:`WindowedLM`), each window with its own damping,
   its own step limit and its own stopping test: the normal matrix falls apart into independent
   blocks at the held ends. Windows that have converged drop out and the rest are packed end to end
   into a shorter problem (:func:`pack`), so an iteration costs the steps still moving, not T;
3. the whole trajectory is polished by the ordinary solver from there to the same tolerance (the held
   ends move to their optimum; usually 1–2 iterations).

The losing starts cost one evaluation each instead of iterations over the whole track, and a window
converges in the iterations it needs rather than in those of the slowest gap.

Measured (``benchmarks/results/tuning_trajectory_solver.md``, issue 34e): 25–30 % less time than the
whole-trajectory race at T ≥ 10 000 steps, the same routes, but the objective has shallow minima a few
centimetres apart in long gaps and this path may settle in a neighbour (within ±4e-5 relative of every
start converging, lower as often as not), and on the office's head + feet estimate it found worse optima.
So it is an option (``TrajectoryOptions(race_by_gap=True)``), not the default.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from worldtrack.trajectory.kernels import block_cholesky_solve, block_matvec
from worldtrack.trajectory.model import STATE, TimeGrid
from worldtrack.trajectory.objective import Linearisation, Problem, linearise
from worldtrack.trajectory.observation import ObservationTerm
from worldtrack.trajectory.solver import LevenbergMarquardt, SolveResult, SolverOptions

#: A run of this many observed steps pins the path well enough to cut the trajectory in its middle.
MIN_RUN = 3
#: The windows still moving are packed into a new problem once they are fewer than this share of its steps.
REPACK = 0.7


def window_cuts(observed: np.ndarray, min_run: int = MIN_RUN) -> np.ndarray:
    """Steps where the trajectory is cut: 0, the middle of every run of ≥ ``min_run`` observed steps
    (``observed`` (n,) bool), and n − 1; window w runs from ``cuts[w]`` to ``cuts[w + 1]``.

    >>> window_cuts(np.array([1, 1, 0, 0, 0, 1, 1, 1, 0, 0, 1], bool)).tolist()
    [0, 6, 10]
    """
    n = len(observed)
    edges = np.flatnonzero(np.diff(np.r_[0, np.asarray(observed, np.int8), 0]))
    first, last = edges[::2], edges[1::2] - 1
    middles = ((first + last) // 2)[last - first + 1 >= min_run]
    return np.unique(np.r_[0, middles, n - 1])


def window_sums(step_cost: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """Per window, the sum of the per-step costs from its first step up to the next window's first
    (the last window: to the end): every term that touches the window's inner states, plus terms of
    its held first state, the same for every start."""
    return np.add.reduceat(step_cost, starts)


@dataclass
class Packed:
    """Some windows laid end to end as one problem (each window's end states repeated).

    problem : Problem on the packed grid; index : (m,) real step of each packed step;
    offsets : (k + 1,) first packed step of each window, then m; held : (m,) bool — held end states;
    seams : (j,) packed steps whose terms reach into the next window (held last states: their terms
        are constants, left out of the window's objective so that its relative stop is the window's own)
    """

    problem: Problem
    index: np.ndarray
    offsets: np.ndarray
    held: np.ndarray
    seams: np.ndarray


def pack(problem: Problem, cuts: np.ndarray, windows: np.ndarray) -> Packed:
    """The windows ``windows`` (indices into the cuts' windows, increasing) as one problem. The terms
    between one window's last state and the next one's first touch only held states: constants."""
    n = problem.grid.n
    lo, hi = cuts[windows], cuts[windows + 1]
    offsets = np.r_[0, np.cumsum(hi - lo + 1)]
    index = _ranges(lo, hi + 1)
    held = np.zeros(len(index), dtype=bool)
    held[offsets[:-1][lo > 0]] = True
    seams = offsets[1:][hi < n - 1] - 1
    held[seams] = True

    def packed_term(term: ObservationTerm | None) -> ObservationTerm | None:
        if term is None:
            return None
        first, last = np.searchsorted(term.step, lo, "left"), np.searchsorted(term.step, hi, "right")
        rows = _ranges(first, last)
        if len(rows) == 0:
            return None
        shift = np.repeat(offsets[:-1] - lo, last - first)
        return ObservationTerm(term.obs.subset(rows), term.step[rows] + shift, term.tau[rows], term.floor)

    motion = problem.motion if lo[0] == 0 else replace(problem.motion, first_velocity_sigma=None)
    grid = TimeGrid(problem.grid.t0, problem.grid.dt, max(len(index), 2))
    packed = Problem(grid, packed_term(problem.observations), motion, problem.environment, problem.robust,
                     packed_term(problem.feet))
    return Packed(packed, index, offsets, held, seams)


def _ranges(first: np.ndarray, stop: np.ndarray) -> np.ndarray:
    """The ranges first[i] … stop[i] − 1 one after the other (no Python loop)."""
    length = stop - first
    return np.repeat(first - np.r_[0, np.cumsum(length)[:-1]], length) + np.arange(length.sum())


def _hold(lin: Linearisation, held: np.ndarray) -> None:
    """In place: the held states' rows of the normal equations become δ = 0 (identity, no coupling)."""
    k = np.flatnonzero(held)
    lin.D[k] = np.eye(STATE)
    lin.g[k] = 0.0
    lin.B[k[k < len(lin.B)]] = 0.0
    lin.B[k[k > 0] - 1] = 0.0


class WindowedLM:
    """Levenberg–Marquardt on packed windows, each with its own μ, step limit, acceptance and stop.

    ``mu``, ``nu`` (k,): each window's damping state to start from (carried over when repacking);
    ``carried``: (linearisation, per-step costs) at X0 when the windows come from an earlier packing
    (:meth:`remaining`), so that repacking costs no new linearisation.
    """

    def __init__(self, packed: Packed, X0: np.ndarray, options: SolverOptions, mu: np.ndarray, nu: np.ndarray,
                 carried: tuple[Linearisation, np.ndarray] | None = None):
        self.packed, self.options = packed, options
        self.X = np.array(X0, dtype=float)
        m, k = len(self.X), len(packed.offsets) - 1
        if carried is None:
            self.cost = np.empty(m)
            self.lin = linearise(packed.problem, self.X, step_cost=self.cost)
            _hold(self.lin, packed.held)
            self.cost[packed.seams] = 0.0
        else:
            self.lin, self.cost = carried
        self._spare_cost = np.empty(m)
        lin = self.lin
        self._spare = lin.copy()
        self.F = window_sums(self.cost, packed.offsets[:-1])
        self.owner = np.repeat(np.arange(k), np.diff(packed.offsets))
        self.mu, self.nu = mu.copy(), nu.copy()
        self.done = np.zeros(k, dtype=bool)
        self._work = tuple(np.empty(s) for s in ((m, STATE, STATE), (m, STATE, STATE), (m, STATE), (m, STATE)))

    def remaining(self) -> tuple[np.ndarray, tuple[Linearisation, np.ndarray]]:
        """The windows not yet converged: their packed states and their rows of the normal equations and
        costs, in the order :func:`pack` lays them out (a window's rows touch only its own states)."""
        rows = np.flatnonzero(~self.done[self.owner])
        lin = self.lin
        B = np.zeros((max(len(rows) - 1, 1), STATE, STATE))
        inner = rows[:-1] < len(lin.B)
        B[:len(rows) - 1][inner] = lin.B[rows[:-1][inner]]
        return self.X[rows], (Linearisation(lin.costs, lin.g[rows], lin.D[rows], B, lin.barrier_steps[rows]),
                              self.cost[rows])

    def _sums(self, per_state: np.ndarray) -> np.ndarray:
        return window_sums(per_state.sum(axis=1), self.packed.offsets[:-1])

    def _limited_step(self, delta: np.ndarray, damping: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The step with the solver's limit applied window by window (no floor position moves more than
        ``max_move``: each state shortened on its own, or, where that is no descent direction, the whole
        window's step), and each window's predicted decrease −(2gᵀδ + δᵀHδ)."""
        lin = self.lin
        move = np.hypot(delta[:, 0], delta[:, 2])
        worst = np.maximum.reduceat(move, self.packed.offsets[:-1])
        big = worst > self.options.max_move
        if not big.any():                          # (H + μ·diag H)·δ = −g: then −gᵀδ + δᵀ(μ·diag H)δ
            return delta, self._sums(-lin.g * delta + damping * delta * delta)
        local = delta * np.minimum(1.0, self.options.max_move / np.maximum(move, 1e-300))[:, None]
        pred_local = self._sums(-(2.0 * lin.g * local + local * block_matvec(lin.D, lin.B, local)))
        uniform = big & ~(pred_local > 0)
        if not uniform.any():
            return local, pred_local
        s = np.where(big, self.options.max_move / np.maximum(worst, 1e-300), 1.0)
        g_delta = self._sums(lin.g * delta)
        d_H_delta = self._sums(delta * block_matvec(lin.D, lin.B, delta))
        scale = s[self.owner]
        rows = uniform[self.owner]
        local[rows] = delta[rows] * scale[rows, None]
        return local, np.where(uniform, -(2.0 * s * g_delta + s * s * d_H_delta), pred_local)

    def iterate(self) -> None:
        """One step in every window not yet converged."""
        lin, owner, active = self.lin, self.owner, ~self.done
        damping = self.mu[owner][:, None] * np.maximum(np.diagonal(lin.D, axis1=1, axis2=2), 1e-12)
        L, C, y, x = self._work
        if not block_cholesky_solve(lin.D, lin.B, damping, -lin.g, L, C, y, x):
            self.mu[active], self.nu[active] = self.mu[active] * self.nu[active], self.nu[active] * 2
            return
        delta = x.copy()
        delta[self.done[owner]] = 0.0
        delta, predicted = self._limited_step(delta, damping)
        trial = linearise(self.packed.problem, self.X + delta, out=self._spare, step_cost=self._spare_cost)
        _hold(trial, self.packed.held)
        self._spare_cost[self.packed.seams] = 0.0
        F_trial = window_sums(self._spare_cost, self.packed.offsets[:-1])
        actual = self.F - F_trial
        rho = np.where(predicted > 0, actual / np.where(predicted > 0, predicted, 1.0), -1.0)
        accept = active & np.isfinite(F_trial) & (rho > 0)
        rejected = active & ~accept
        if rejected.any():                         # their rows stay as they were (done windows: δ = 0, the same)
            keep = rejected[owner]
            trial.D[keep], trial.g[keep], trial.barrier_steps[keep] = lin.D[keep], lin.g[keep], lin.barrier_steps[keep]
            trial.B[keep[:-1]] = lin.B[keep[:-1]]
            self._spare_cost[keep] = self.cost[keep]
            delta[keep] = 0.0
        self.X += delta
        self.lin, self._spare, self.cost, self._spare_cost = trial, lin, self._spare_cost, self.cost
        small = np.maximum.reduceat(np.abs(delta).max(axis=1), self.packed.offsets[:-1]) <= self.options.step_size
        settled = accept & ((actual <= self.options.barrier_relative_decrease * np.abs(self.F)) | small)
        stuck = rejected & ((self.mu > 1e12) | (predicted <= 1e-14 * np.abs(self.F)))
        self.mu = np.where(accept, self.mu * np.maximum(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3), self.mu)
        self.mu[rejected] *= self.nu[rejected]
        self.nu = np.where(accept, 2.0, np.where(rejected, self.nu * 2.0, self.nu))
        self.F = np.where(accept, F_trial, self.F)
        self.done |= settled | stuck


def solve_windows(problem: Problem, X: np.ndarray, cuts: np.ndarray, options: SolverOptions) -> tuple[np.ndarray, float]:
    """Every window of ``cuts`` to convergence with its ends held (step 2 of the module's notes).

    Returns the trajectory and the work done, in iterations over the whole trajectory
    (Σ packed steps per iteration ÷ n)."""
    X = np.array(X, dtype=float)
    windows = np.arange(len(cuts) - 1)
    mu = np.full(len(windows), options.initial_damping)
    nu = np.full(len(windows), 2.0)
    work, iterations, carried, X_packed = 0.0, 0, None, None
    while len(windows) and iterations < options.max_iterations:
        packed = pack(problem, cuts, windows)
        lm = WindowedLM(packed, X[packed.index] if carried is None else X_packed, options, mu, nu, carried)
        size = len(packed.index)
        while not lm.done.all() and iterations < options.max_iterations:
            lm.iterate()
            iterations += 1
            work += size
            moving = np.diff(packed.offsets)[~lm.done].sum()
            if moving < REPACK * size:                # pack the windows still moving into a shorter problem
                break
        X[packed.index] = lm.X                    # held states are written back unchanged
        if not lm.done.all():
            X_packed, carried = lm.remaining()
        windows, mu, nu = windows[~lm.done], lm.mu[~lm.done], lm.nu[~lm.done]
    return X, work / problem.grid.n


def race_by_gap(problem: Problem, starts: dict[str, np.ndarray], without: np.ndarray,
                options: SolverOptions) -> tuple[SolveResult, dict[str, int], float]:
    """Steps 1–3 of the module's notes from ``starts`` (name → (n, 6)), ends held at ``without`` (the MAP
    without the barrier). Returns the polished optimum, how many windows each start won (of the windows
    where the starts' objectives differ; starts that tie at the lowest are joined by "+", e.g.
    "shortest+straight" where nothing blocks the straight line), and the windowed work in iterations
    over the whole trajectory."""
    n = problem.grid.n
    cuts = window_cuts(np.bincount(problem.observations.step, minlength=n) > 0)
    cost = np.empty(n)
    names = list(starts)
    table = []
    spliced = {}
    for name in names:
        X = np.array(starts[name], dtype=float)
        X[cuts] = without[cuts]
        linearise(problem, X, step_cost=cost)
        table.append(window_sums(cost, cuts[:-1]))
        spliced[name] = X
    table = np.array(table)
    best = np.argmin(table, axis=0)
    owner = np.repeat(best, np.diff(np.r_[cuts[:-1], n]))
    X0 = np.array(without, dtype=float)
    for k, name in enumerate(names):
        pick = owner == k
        X0[pick] = spliced[name][pick]
    X0[cuts] = without[cuts]
    low = table.min(axis=0)
    tie = table <= low + 1e-9 * np.abs(low)                   # (starts, windows): at the window's lowest
    wins: dict[str, int] = {}
    for w in np.flatnonzero(~tie.all(axis=0)):                 # the windows where the starts differ
        label = "+".join(name for k, name in enumerate(names) if tie[k, w])
        wins[label] = wins.get(label, 0) + 1
    X1, work = solve_windows(problem, X0, cuts, options)
    return LevenbergMarquardt(problem, X1, options).run(), wins, work
