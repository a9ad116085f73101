"""Levenberg–Marquardt on the windows still moving (34b, an option: ``TrajectoryOptions(settle_windows=True)``).

With the barrier the last iterations of the leading start are spent on a few paths creeping along obstacles
(~1.5 cm per iteration against the softplus's exponential tail), each window at its own rate, while every
iteration linearises and solves the whole trajectory. Here, once most of the trajectory has *settled*, the
iterations go on the unsettled windows only, with the settled states held, and a full iteration confirms.

The windows are those of :mod:`.windows` (the trajectory cut in the middle of every run of observed steps). A
window has settled when the Gauss–Newton model of the next step promises it less than its share of the stop
test: −g_wᵀδ_w + δ_wᵀ(μ·diag H)δ_w ≤ tol · F · n_w / n (tol the solver's relative decrease with a barrier, n_w
its steps). Summed over the windows that is the solver's own test (``confirm_stop``), so when every window has
settled the whole has. Once windows holding ``share`` of the steps have settled:

1. the unsettled windows (neighbours merged into one range) are packed into one problem (:func:`.windows.pack`),
   each range's first and last state held where it borders a settled window (δ = 0 there);
2. Levenberg–Marquardt runs on it with the same options, from the run's damping, to the solver's stop test
   with the *whole* objective's threshold tol · F (the terms of held states are constants, so each iteration's
   decrease is the whole trajectory's): O(active steps) per iteration; it settles in turn (the restriction
   nests, the held states of every level held);
3. the whole trajectory is linearised again and the ordinary iterations go on from there (the first one
   confirms the stop or, if the held states must still move, continues; the restriction may happen again).

Measured (34b, ``benchmarks/trajectory_settle.py``, CPU at load ~7): at T = 10 000 0.71–0.91 of the default's
CPU on the dev walks 3/42/90 and held-out 200–202, 0.73–0.94 on never-used 300–302, but 1.01–1.14 at T = 1 000
(the packing costs more than it saves); the estimate's ratio to no environment stays above 3. The optimum is
not the default's: F −2.0e-5 … +4.0e-6 relative at T = 10 000 (lower on 7 of 9 walks), floors up to 0.96 m
apart on the flat slides where the default itself stops ~1e-5 above the tight optimum and up to 2.3 m from
it; office (20 people): −1.1e-4 … +5.4e-6 of every start's optimum; ETH/UCY: every row unchanged. Hence off.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from worldtrack.trajectory.objective import Linearisation, linearise
from worldtrack.trajectory.solver import LevenbergMarquardt, SolveResult
from worldtrack.trajectory.windows import _hold, pack, window_cuts, window_sums

#: The restriction starts once the settled windows hold this share of the steps.
SHARE = 0.5


class HeldLM(LevenbergMarquardt):
    """Levenberg–Marquardt with some states held: their rows of the normal equations are δ = 0."""

    def __init__(self, problem, X0, options, held: np.ndarray):
        self.held = held
        super().__init__(problem, X0, options)

    def _step(self, lin: Linearisation):
        _hold(lin, self.held)
        return super()._step(lin)


@dataclass
class Settling:
    """How a run went: restricted phases, their iterations, and their work in whole-trajectory iterations."""

    phases: int = 0
    iterations: int = 0
    work: float = 0.0


def settled_windows(run: LevenbergMarquardt, cuts: np.ndarray) -> np.ndarray:
    """(k,) bool: the windows of ``cuts`` whose share of the next step's model decrease is below their share of
    the stop test (module notes); the step is solved once and kept for the next iteration."""
    if run._floor() == -np.inf:
        return np.zeros(len(cuts) - 1, dtype=bool)
    delta, damping = run._pending
    lin, n = run.lin, len(run.X)
    decrease = window_sums((-lin.g * delta + damping * delta * delta).sum(axis=1), cuts[:-1])
    length = np.diff(np.r_[cuts[:-1], n])
    return decrease <= run.tolerance * max(lin.costs.total, 1e-300) * length / n


def restricted_cuts(cuts: np.ndarray, active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The cuts with those between two active windows removed, and the indices of the merged active ranges.

    >>> c, w = restricted_cuts(np.array([0, 5, 9, 14, 20]), np.array([True, True, False, True]))
    >>> c.tolist(), w.tolist()
    ([0, 9, 14, 20], [0, 2])
    """
    inner = np.r_[False, active[:-1] & active[1:], False]      # a cut between two active windows
    merged = cuts[~inner]
    first = np.r_[True, ~(active[:-1] & active[1:])]            # windows that begin a merged range
    return merged, np.flatnonzero(active[first])


def restrict(run: LevenbergMarquardt, cuts: np.ndarray, active: np.ndarray, share: float = SHARE,
             nested: bool = True) -> tuple[int, float]:
    """Steps 1–3 of the module's notes on ``run`` (changed in place). Returns the restricted iterations and their
    work in whole-trajectory iterations."""
    merged, ranges = restricted_cuts(cuts, active)
    packed = pack(run.problem, merged, ranges)
    F = run.lin.costs.total
    held = packed.held | run.held[packed.index] if isinstance(run, HeldLM) else packed.held
    options = replace(run.options, max_iterations=run.options.max_iterations - run.iterations)
    sub = HeldLM(packed.problem, run.X[packed.index], options, held)
    sub.tolerance = run.tolerance * F / max(sub.lin.costs.total, 1e-300)   # the whole objective's threshold
    sub.mu, sub.nu = run.mu, run.nu
    _, log = run_settling(sub, share) if nested else (sub.run(), None)
    X = run.X.copy()
    X[packed.index] = sub.X                                    # held states are written back unchanged
    whole = linearise(run.problem, X, out=run._spare)
    run.X, run.lin, run._spare = X, whole, run.lin
    run.mu, run.nu, run._pending, run._rejected = sub.mu, sub.nu, None, None
    run.iterations += sub.iterations
    inner, inner_work = (log.iterations, log.work) if log else (0, 0.0)     # nested phases, in sub-problem iterations
    return sub.iterations, (sub.iterations - inner + inner_work) * len(packed.index) / len(X)


def run_settling(run: LevenbergMarquardt, share: float = SHARE, nested: bool = True) -> tuple[SolveResult, Settling]:
    """``run.run()`` with the restriction to unsettled windows (module notes) once windows holding ``share`` of
    the steps have settled; without a barrier, or with fewer than two windows, the ordinary run."""
    n = len(run.X)
    cuts = window_cuts(np.bincount(run.problem.observations.step, minlength=n) > 0)
    log = Settling()
    if run.problem.environment.barrier is None or len(cuts) < 3:
        return run.run(), log
    length = np.diff(np.r_[cuts[:-1], n])
    while not run.converged and run.iterations < run.options.max_iterations:
        X = run.X
        run.run(1)
        if run.converged or run.X is X:                         # stopped, or a rejected step: go on as ever
            continue
        settled = settled_windows(run, cuts)
        if settled.all() or length[settled].sum() < share * n:
            continue
        iterations, work = restrict(run, cuts, ~settled, share, nested)
        log.phases, log.iterations, log.work = log.phases + 1, log.iterations + iterations, log.work + work
    if not run.converged and run.iterations >= run.options.max_iterations:
        run.message = "iteration limit"
    return run.result, log
