"""Levenberg–Marquardt on the block-tridiagonal normal equations, solved by banded Cholesky.

Each iteration solves ``(H + μ·diag(H))·δ = −g`` with H = JᵀJ block-tridiagonal (6 × 6 blocks), a
symmetric band matrix with 11 super-diagonals, by banded Cholesky in O(T) time and memory: block
by block in a compiled kernel (the default), or through LAPACK (``scipy.linalg.solveh_banded``,
``?pbsv``, on the band storage), which the kernel is tested against. Damping and step control
follow Nielsen (1999): μ shrinks by max(1/3, 1 − (2ρ − 1)³) on a good step and grows by ν (2,
4, 8, …) on a rejected one, with ρ the ratio of the actual to the predicted decrease.

:func:`solve_dense` (:mod:`.dense`, re-exported here) is the readable reference: the same residuals stacked
into one vector with a dense Jacobian, handed to ``scipy.optimize.least_squares``. Tests check that both
reach the same optimum.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from worldtrack.trajectory.dense import dense_objective, jacobian_dense, residual_vector, solve_dense
from worldtrack.trajectory.kernels import BANDWIDTH, block_cholesky_solve, fill_banded, model_decrease
from worldtrack.trajectory.lookahead import shape_step
from worldtrack.trajectory.model import STATE
from worldtrack.trajectory.objective import Costs, Linearisation, Problem, evaluate, linearise



@dataclass(frozen=True)
class SolverOptions:
    """When Levenberg–Marquardt stops.

    Parameters
    ----------
    max_iterations : int
    relative_decrease : float — stop when an accepted step lowers F by less than this fraction
    barrier_relative_decrease : float — the same with a barrier: there the last iterations only slide
        paths through long unobserved gaps where F is flat (positions moving by centimetres where
        their uncertainty is metres), so a looser tolerance saves most of the iterations
    step_size : float — or when no state entry moves by more than this (m, m/s)
    initial_damping : float — μ of the first iteration (relative to diag(H)); the problem is nearly
        linear but badly conditioned (long gaps held only by the motion prior), so it starts tiny
    linear_solver : "block" or "lapack" — how each step's banded system is solved: the block Cholesky
        kernel (:func:`~worldtrack.trajectory.kernels.block_cholesky_solve`, the default: it reads the
        6 × 6 blocks where they are, 2.4× faster than LAPACK at T = 100 000 on one core) or LAPACK's
        band Cholesky ``scipy.linalg.solveh_banded`` (the reference it is tested against)
    max_move : float, metres — with a barrier, a step moves no floor position further than this
        (the step is shortened along its direction): the hinge's linearisation holds only near
        the current path, and a full Gauss–Newton step can carry a path through a thin wall. With
        ``shrink_on_reject`` it is the largest radius of a trust region: after a rejected step the next
        one moves no position by more than half of the rejected step's largest move
    look_ahead : float or None, seconds — with a barrier, a step whose largest move is beyond ``max_move``
        goes, state by state, as far along its Gauss–Newton move as the floor lets it (no point of the
        move closer to an obstacle than the clearance), made smooth over ± ``look_ahead`` seconds
        (:mod:`.lookahead`); where that is no descent direction, or with None, the ``max_move`` limit
        above. 34i: the limit alone shortens the whole path to its worst state's 0.25 m, which took
        ~10–20 iterations from the route start; the look-ahead 1.3–1.8× fewer on held-out walks
    confirm_stop : bool — with a barrier, "objective settled" also needs the next step's Gauss–Newton model
        to promise less than the tolerance (its step is kept, so going on costs nothing extra). The objective
        falls in stairs there (a path slides round a corner, then a flat stretch, then the next corner):
        34i saw a run stop on such a flat stretch 2.1e-4 above the optimum it was heading for
    shrink_on_reject : bool — with a barrier, answer a rejected step by that trust region (the same
        Gauss–Newton step, kept, shortened; the damping unchanged; the radius doubles back after a step
        with ρ > 0.75) instead of raising the damping μ by ν = 2, 4, 8, … Near an obstacle μ sits at
        1e-10 … 1e-18 of diag H, so the damping alone needed 4–6 rejections in a row to change the step
        at all; the trust region shortens it at once (34g: 17 → 13–14 iterations on the held-out walks
        where steps are rejected, the same optimum to 1e-15). Off by default: its other path reached
        another (lower) optimum for 2 of 69 people of zara01 (camera seed 4, walls + free space), so
        the default keeps the estimates of 34f. Inside the shrunk region (radius ≤ ``max_move``) the look-ahead
        is not used (34k: it let clear states take their whole move, so the radius did not bind and held-out walks
        stalled at the iteration limit); held-out walks with rejections, T = 10 000: 35 / 30 / 27 / 30 / 26 →
        24 / 21 / 24 / 25 / 22 iterations, the others unchanged
    outward_curvature : float or None — with a barrier, a sample that moved away from the obstacles in the last step takes
        this curvature factor in the next matrix instead of Newton's ≈ 2 (``barrier_terms``). Off (None): 34n, 18 walks, 1.0:
        iterations 1k 133 → 120, 10k 198 → 162, ±5 per walk (walk 3 21 → 25), F ≤ +4.5e-6 (``trajectory_outward.py``)
    finish_newton : bool — with ``outward_curvature``: once its run stops, go on from there with Newton's factor (the
        default matrix; one more linearisation) until the default rule stops, so the stop is one of the default model's
        (34o, ``trajectory_finish.py``: 1 iteration after the switch on 34 of 36 walks, 2 on the rest). With
        ``shrink_on_reject`` and factor 1.0, leader iterations dev + held-out 1k 194 → 161, 10k 255 → 198, never-used
        900–902 42 → 34, 40 → 43; F ≤ default·(1 + 1e-6) on 36/36. Off by default, as the factor is
    """

    max_iterations: int = 100
    relative_decrease: float = 1e-10
    barrier_relative_decrease: float = 1e-5
    step_size: float = 1e-7
    initial_damping: float = 1e-9
    linear_solver: str = "block"
    max_move: float = 0.25
    look_ahead: float | None = 2.0
    confirm_stop: bool = True
    shrink_on_reject: bool = False
    outward_curvature: float | None = None
    finish_newton: bool = False


@dataclass
class SolveResult:
    """The optimum found from one start.

    X : (n, 6) trajectory; costs : Costs; iterations : int; converged : bool; message : str;
    linearisation : the Gauss–Newton system at X (for covariances and the active barrier steps)
    """

    X: np.ndarray
    costs: Costs
    iterations: int
    converged: bool
    message: str
    linearisation: Linearisation


def to_banded(D: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Upper band storage ``ab[u + i − j, j] = H[i, j]`` (12, 6n) of the block-tridiagonal H."""
    ab = np.zeros((BANDWIDTH + 1, STATE * len(D)), order="F")   # LAPACK's layout: no copy, and
    fill_banded(D, B, ab)                                         # the kernel writes columns
    return ab


def solve_banded(ab: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Solve H·x = rhs, H SPD in upper band storage ``ab`` (overwritten); rhs and x are (n, 6)."""
    x = scipy.linalg.solveh_banded(ab, rhs.reshape(-1), lower=False, overwrite_ab=True, check_finite=False)
    return x.reshape(rhs.shape)


def solve_blocks(D: np.ndarray, B: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Solve H·x = rhs for the SPD block-tridiagonal H of (D, B); rhs and x are (n, 6)."""
    return solve_banded(to_banded(D, B), rhs)


class LevenbergMarquardt:
    """Levenberg–Marquardt on one problem from one start, resumable: ``run(k)`` does up to k more
    iterations (multi-start races stop the losers early), ``run()`` goes on until it converges.

    >>> # solver = LevenbergMarquardt(problem, X0); solver.run(5); result = solver.run()
    """

    def __init__(self, problem: Problem, X0: np.ndarray, options: SolverOptions = SolverOptions()):
        self.problem, self.options = problem, options
        self.X = np.array(X0, dtype=float)
        self.lin = linearise(problem, self.X)
        if not np.isfinite(self.lin.costs.total):
            raise ValueError("the start puts the head behind a camera")
        self.mu, self.nu = options.initial_damping, 2.0
        self.move_limit = options.max_move
        self._shrunk = False              # inside a trust region a rejection shrank (``shrink_on_reject``)
        self._finishing = False           # ``finish_newton``: the outward factor's run has stopped, Newton's goes on
        # buffers reused by every iteration: the trial's linearisation and the linear solver's work
        lin = self.lin
        self._spare = lin.copy()
        self._pending: tuple[np.ndarray, np.ndarray] | None = None     # the next step, if already solved
        self._rejected: tuple[np.ndarray, float] | None = None   # the last rejected step, its trial's F
        n = len(self.X)
        if options.linear_solver == "lapack":
            self._ab = np.zeros((BANDWIDTH + 1, self.X.size), order="F")
            self._rhs = np.empty(self.X.size)
        elif options.linear_solver == "block":
            self._work = (np.empty((n, STATE, STATE)), np.empty((n, STATE, STATE)), np.empty((n, STATE)),
                          np.empty((n, STATE)))
        else:
            raise ValueError(f"linear_solver: expected 'block' or 'lapack', got {options.linear_solver!r}")
        self.iterations, self.converged, self.message = 0, False, "not run"
        barrier = problem.environment.barrier is not None
        self.tolerance = options.barrier_relative_decrease if barrier else options.relative_decrease

    @property
    def result(self) -> SolveResult:
        return SolveResult(self.X, self.lin.costs, self.iterations, self.converged, self.message, self.lin)

    def run(self, iterations: int | None = None) -> SolveResult:
        """Iterate until converged, ``options.max_iterations`` in all, or ``iterations`` more."""
        left = self.options.max_iterations - self.iterations
        for _ in range(left if iterations is None else min(iterations, left)):
            if self.converged:
                break
            self.iterations += 1
            self._iterate()
        if not self.converged and self.iterations >= self.options.max_iterations:
            self.message = "iteration limit"
        return self.result

    def model_floor(self) -> float:
        """The objective at the minimum of the current Gauss–Newton model, F − (predicted decrease of the
        next step, before the step limit): where the local quadratic model says this start is heading
        (−inf if the damped system is not positive definite). The step is kept for the next iteration."""
        if self.converged:
            return self.lin.costs.total
        return self._floor()

    def _floor(self) -> float:
        """:meth:`model_floor` of the current linearisation (the step solved once and kept)."""
        if self._pending is None:
            self._pending = self._step(self.lin)
        if self._pending is None:
            return -np.inf
        delta, damping = self._pending
        return self.lin.costs.total - float(-np.sum(self.lin.g * delta) + np.sum(damping * delta ** 2))

    def _step(self, lin: Linearisation) -> tuple[np.ndarray, np.ndarray] | None:
        """The damped Gauss–Newton step δ (n, 6) and the damping μ·diag(H) (n, 6); None if H + damping
        is not positive definite."""
        damping = self.mu * np.maximum(np.diagonal(lin.D, axis1=1, axis2=2), 1e-12)   # Marquardt: μ·diag(H)
        if self.options.linear_solver == "block":
            L, C, y, x = self._work
            return (x.copy(), damping) if block_cholesky_solve(lin.D, lin.B, damping, -lin.g, L, C, y, x) else None
        ab = self._ab
        fill_banded(lin.D, lin.B, ab)
        ab[BANDWIDTH] += damping.ravel()
        np.negative(lin.g.ravel(), out=self._rhs)
        try:
            delta = scipy.linalg.solveh_banded(ab, self._rhs, lower=False, overwrite_ab=True, overwrite_b=True,
                                               check_finite=False)
        except np.linalg.LinAlgError:
            return None
        return delta.reshape(lin.g.shape), damping

    def _iterate(self) -> None:
        lin, options = self.lin, self.options
        step, self._pending = self._pending or self._step(lin), None
        if step is None:
            self.mu, self.nu = self.mu * self.nu, self.nu * 2
            return
        delta, damping = step
        # (H + μ·diag H)·δ = −g gives δᵀHδ = −gᵀδ − δᵀ(μ·diag H)δ, so −(2gᵀδ + δᵀHδ) is:
        predicted = float(-np.sum(lin.g * delta) + np.sum(damping * delta ** 2))
        barrier = self.problem.environment.barrier is not None
        if barrier:
            delta, predicted = self._limit(lin, delta, predicted)
        if self._still_rejected(delta):
            return self._raise_damping(lin, predicted)
        outward = None if options.outward_curvature is None or self._finishing else \
            (lin.barrier_d, float(options.outward_curvature))
        trial = linearise(self.problem, self.X + delta, out=self._spare, outward=outward)
        actual = lin.costs.total - trial.costs.total
        rho = actual / predicted if predicted > 0 else -1.0
        self._rejected = None
        if np.isfinite(trial.costs.total) and rho > 0:
            self.X, self.lin, self._spare = self.X + delta, trial, lin
            self.mu *= max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3)
            self.nu = 2.0
            if barrier and rho > 0.75:
                self.move_limit = min(2.0 * self.move_limit, options.max_move)
                self._shrunk = self._shrunk and self.move_limit < options.max_move
            if actual <= self.tolerance * max(lin.costs.total, 1e-300) and not self._model_disagrees():
                self.message, self.converged = "objective settled", True
            elif np.abs(delta).max() <= options.step_size:
                self.message, self.converged = "step below tolerance", True
            else:
                self.message = "running"
            if self.converged and options.finish_newton and options.outward_curvature is not None \
                    and not self._finishing:
                self._finish()
            return
        tried = float(np.hypot(delta[:, 0], delta[:, 2]).max()) if barrier else 0.0
        if barrier and options.shrink_on_reject and tried > 1e-3:
            # a trust region: the next try moves no state by more than half of this one's largest move (nor
            # beyond max_move: the look-ahead may have carried clear states further), with the same damping,
            # so the same Gauss–Newton step (kept: no second solve)
            self.move_limit, self._pending, self._shrunk = min(0.5 * tried, options.max_move), step, True
            return
        if np.isfinite(trial.costs.total):
            self._rejected = (delta, trial.costs.total)     # the trial's linearisation stays in self._spare
        self._raise_damping(lin, predicted)

    def _finish(self) -> None:
        """``finish_newton``: the outward factor's run stopped; the same X linearised with Newton's factor, and on."""
        self._finishing, self.converged, self.message, self._pending = True, False, "running", None
        self.lin, self._spare = linearise(self.problem, self.X, out=self._spare), self.lin

    def _raise_damping(self, lin: Linearisation, predicted: float) -> None:
        """A rejected step: μ grows by ν (2, 4, 8, …); stop where that can no longer help."""
        self.mu, self.nu = self.mu * self.nu, self.nu * 2
        if self.mu > 1e12 or predicted <= 1e-14 * max(lin.costs.total, 1e-300):
            self.message, self.converged = "no further decrease possible", True

    def _still_rejected(self, delta: np.ndarray) -> bool:
        """Whether the step δ (n, 6) after a rejection is the rejected δ₀ but for a change Δ so small that its trial
        must be rejected too (then it is not linearised: 34k saw the same step come back up to 6 times, μ at 1e-18 …
        1e-13 of diag H): max |Δ| ≤ 1 mm (m, m/s; the barrier's softness is 3 cm) and the rejected trial's rise
        F(X + δ₀) − F(X) above 10× the bound 2·Σ|g₀Δ| + ΔᵀH₀Δ of its Gauss–Newton model's change (g₀, H₀ at
        X + δ₀) plus 1e-12·F for rounding. The iterates are those of evaluating it."""
        if self._rejected is None:
            return False
        old, F_old = self._rejected
        change = delta - old
        if np.abs(change).max() > 1e-3:
            return False
        t = self._spare                                          # the linearisation at X + δ₀
        first = 2.0 * float(np.abs(t.g * change).sum())
        bound = first - model_decrease(t.D, t.B, t.g, change) - 2.0 * float(np.sum(t.g * change))   # + ΔᵀH₀Δ
        return F_old - self.lin.costs.total > 10.0 * bound + 1e-12 * abs(self.lin.costs.total)

    def _model_disagrees(self) -> bool:
        """With ``confirm_stop`` and a barrier: whether the next step's model still promises more than the
        tolerance (its step is kept for the next iteration)."""
        if not (self.options.confirm_stop and self.problem.environment.barrier is not None):
            return False
        F = self.lin.costs.total
        return F - self._floor() > self.tolerance * max(F, 1e-300)

    def _limit(self, lin: Linearisation, delta: np.ndarray, predicted: float) -> tuple[np.ndarray, float]:
        """The step with the barrier: as it is if no state moves beyond the move limit, else shaped by the
        look-ahead (if on and a descent direction), else :func:`_limit_moves`. Inside a trust region shrunk by a
        rejection (``shrink_on_reject``) the look-ahead is not used: it lets every state whose floor is clear take
        its whole move, so the smaller radius would not bind and the same step would be tried again and again."""
        move = np.hypot(delta[:, 0], delta[:, 2]).max()
        if move <= self.move_limit:
            return delta, predicted
        if self.options.look_ahead is not None and not self._shrunk:
            barrier, dt = self.problem.environment.barrier, self.problem.grid.dt
            window = int(round(self.options.look_ahead / dt))
            shaped = shape_step(delta, self.X, barrier, self.move_limit / move, window, dt, lin.barrier_d)
            decrease = model_decrease(lin.D, lin.B, lin.g, shaped)
            if decrease > 0:
                return shaped, decrease
        return _limit_moves(lin, delta, predicted, self.move_limit)


def levenberg_marquardt(problem: Problem, X0: np.ndarray, options: SolverOptions = SolverOptions()) -> SolveResult:
    """Minimise the objective of ``problem`` from X0 (n, 6) until it converges; O(n) per iteration."""
    return LevenbergMarquardt(problem, X0, options).run()


def _limit_moves(lin: Linearisation, delta: np.ndarray, predicted: float, max_move: float) -> tuple[np.ndarray, float]:
    """Shorten the steps that move a floor position by more than ``max_move`` (m), each on its own;
    if that is no longer a descent direction, shorten the whole step instead."""
    move = np.hypot(delta[:, 0], delta[:, 2])
    if move.max() <= max_move:
        return delta, predicted
    local = delta * np.minimum(1.0, max_move / np.maximum(move, 1e-300))[:, None]
    pred_local = model_decrease(lin.D, lin.B, lin.g, local)
    if pred_local > 0:
        return local, pred_local
    uniform = delta * (max_move / move.max())
    return uniform, model_decrease(lin.D, lin.B, lin.g, uniform)


__all__ = ["BANDWIDTH", "LevenbergMarquardt", "SolveResult", "SolverOptions", "dense_objective", "evaluate", "jacobian_dense",
           "levenberg_marquardt", "residual_vector", "solve_blocks", "solve_dense", "to_banded"]
