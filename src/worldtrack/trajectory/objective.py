"""The objective of eq. 9 and its Gauss–Newton normal equations in block-tridiagonal form.

    F(X) = Xᵀ·Λ_X·X + ‖ẋ_1/σ₁‖²  +  Σ_(t,i)∈o ρ(‖(π_i(x_t) − y_t^i)/σ‖)  −  λ·Σ_t (e_h + e_v)

(ρ(e) = e², or Huber's e² / 2ke − k² with ``robust = k``; ‖ẋ_1/σ₁‖² is the prior on the first
velocity of :class:`~.model.MotionPrior`, counted in the motion cost). Every residual touches one state
(observations, height) or two neighbouring states (motion, barrier samples), so JᵀJ is
block-tridiagonal with 6 × 6 blocks: ``D[t]`` on the diagonal, ``B[t] = H[t, t+1]`` above it.
Assembly is vectorised over all steps; no Python loop runs over time.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from worldtrack.trajectory.barrier_terms import Hinge, Normal, add_barrier_terms
from worldtrack.trajectory.environment import (EnvironmentModel, barrier_residuals, height_residuals)
from worldtrack.trajectory.kernels import add_motion_terms
from worldtrack.trajectory.model import (STATE, VEL, MotionPrior, TimeGrid, first_velocity_residuals, motion_blocks,
                                        motion_residuals)
from worldtrack.trajectory.observation import ObservationTerm, Observations

_W = 4  # index of the head height w in the state


@dataclass(frozen=True, eq=False)
class Problem:
    """One person's MAP problem: grid, observations, motion prior, environment, robust loss.

    Parameters
    ----------
    grid : TimeGrid
    observations : ObservationTerm
    motion : MotionPrior
    environment : EnvironmentModel
    robust : float or None — Huber threshold in σ (e.g. 3.0); None = plain squares
    feet : ObservationTerm or None — the feet pixels (floor points below the head), if any
    """

    grid: TimeGrid
    observations: ObservationTerm
    motion: MotionPrior
    environment: EnvironmentModel
    robust: float | None = None
    feet: ObservationTerm | None = None

    @classmethod
    def build(cls, obs: Observations, grid: TimeGrid, motion: MotionPrior, environment: EnvironmentModel,
              robust: float | None = None) -> "Problem":
        feet = obs.feet()
        return cls(grid, ObservationTerm.on_grid(obs, grid), motion, environment, robust,
                   None if feet is None else ObservationTerm.on_grid(feet, grid, floor=True))

    def with_environment(self, environment: EnvironmentModel) -> "Problem":
        return Problem(self.grid, self.observations, self.motion, environment, self.robust, self.feet)

    @property
    def pixel_terms(self) -> tuple[ObservationTerm, ...]:
        """The head pixels and, when given, the feet pixels."""
        return (self.observations,) if self.feet is None else (self.observations, self.feet)

    @cached_property
    def A(self) -> np.ndarray:
        return self.motion.transition(self.grid.dt)

    @cached_property
    def W(self) -> np.ndarray:
        return self.motion.whitener(self.grid.dt)

    @cached_property
    def motion_normal(self) -> tuple[np.ndarray, np.ndarray]:
        """Λ_X as blocks (D, B), with the first velocity's prior on D[0] — constant, computed once."""
        D, B = motion_blocks(self.A, self.W, self.grid.n)
        D[0, VEL, VEL] += self.motion.first_velocity_gain ** 2
        return D, B

    @cached_property
    def barrier_sample_points(self) -> tuple[np.ndarray, np.ndarray]:
        """(step t, fraction α) of every barrier sample (:meth:`~.environment.Barrier.samples`), computed once."""
        return self.environment.barrier.samples(self.grid.n)

    @cached_property
    def observation_groups(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """Per pixel term: (first row of each run of equal steps, that step); rows are in time order."""
        out = []
        for term in self.pixel_terms:
            step = term.step
            starts = np.flatnonzero(np.r_[True, step[1:] != step[:-1]])
            out.append((starts, step[starts]))
        return out


@dataclass
class Costs:
    """Each term of the objective at a trajectory (sums of squared whitened residuals)."""

    motion: float
    observation: float
    barrier: float
    height: float

    @property
    def total(self) -> float:
        return self.motion + self.observation + self.barrier + self.height

    def as_dict(self) -> dict[str, float]:
        return {"motion": self.motion, "observation": self.observation, "barrier": self.barrier,
                "height": self.height, "total": self.total}


@dataclass
class Linearisation:
    """Costs, half-gradient g = Jᵀ·Wr (n, 6) and Gauss–Newton blocks D (n, 6, 6), B (n − 1, 6, 6);
    with a barrier also its samples' residuals r (M,) and distances d (M,) (m) in the order of
    :attr:`Problem.barrier_sample_points` (kept so that a later ``linearise(..., out=)`` writes into them
    instead of allocating, and for the look-ahead's traces)."""

    costs: Costs
    g: np.ndarray
    D: np.ndarray
    B: np.ndarray
    barrier_steps: np.ndarray
    barrier_r: np.ndarray | None = None
    barrier_d: np.ndarray | None = None

    def copy(self) -> "Linearisation":
        """A copy with its own arrays (a solver's spare, overwritten by the next trial)."""
        own = lambda a: None if a is None else a.copy()  # noqa: E731
        return Linearisation(self.costs, self.g.copy(), self.D.copy(), self.B.copy(), self.barrier_steps.copy(),
                             own(self.barrier_r), own(self.barrier_d))


def huber(e: np.ndarray, k: float | None) -> tuple[np.ndarray, np.ndarray]:
    """ρ(e) and the IRLS weight ρ'(e)/(2e) for residual norms e ≥ 0 (k None: e² and 1)."""
    if k is None:
        return e * e, np.ones_like(e)
    big = e > k
    rho = np.where(big, 2 * k * e - k * k, e * e)
    weight = np.where(big, k / np.where(big, e, 1.0), 1.0)
    return rho, weight


def evaluate(problem: Problem, X: np.ndarray) -> Costs:
    """The objective's terms at X (n, 6); ``inf`` observation cost if a head goes behind a camera."""
    rm = motion_residuals(X, problem.A, problem.W)
    rv = first_velocity_residuals(X, problem.motion.first_velocity_gain)
    obs_cost = 0.0
    for term in problem.pixel_terms:
        r, _, depth = term.residuals(X, with_jacobian=False)
        rho, _ = huber(np.hypot(r[:, 0], r[:, 1]), problem.robust)
        obs_cost += float(rho.sum()) if np.all(depth > 1e-3) else np.inf
    env = problem.environment
    barrier = height = 0.0
    if env.barrier is not None:
        br = barrier_residuals(X, env.barrier, env.weight, problem.grid.dt)
        barrier = float(br.r @ br.r)
    if env.height is not None:
        rh, _ = height_residuals(X, env.height, env.weight)
        height = float(rh @ rh)
    return Costs(float(np.sum(rm * rm) + rv @ rv), obs_cost, barrier, height)


def _add_pixel_term(term: ObservationTerm, starts: np.ndarray, steps: np.ndarray, robust: float | None,
                    X: np.ndarray, D: np.ndarray, g: np.ndarray, step_cost: np.ndarray | None) -> float:
    """In place: one pixel term's JᵀWJ into D and JᵀWr into g (each row on one state; rows come in
    runs of equal steps, time order), its cost per step into ``step_cost`` (if given); returns its
    cost (inf if a point goes behind a camera)."""
    r, J, depth = term.residuals(X)
    rho, w = huber(np.hypot(r[:, 0], r[:, 1]), robust)
    JtJ = np.einsum("nki,nkj->nij", J, J * w[:, None, None])
    Jtr = np.einsum("nki,nk->ni", J, r * w[:, None])
    D[steps] += np.add.reduceat(JtJ, starts, axis=0)
    g[steps] += np.add.reduceat(Jtr, starts, axis=0)
    if step_cost is not None:
        step_cost[steps] += np.add.reduceat(np.where(depth > 1e-3, rho, np.inf), starts)
    return float(rho.sum()) if np.all(depth > 1e-3) else np.inf


#: ``d_before`` of :func:`~.barrier_terms.add_barrier_terms` when no sample takes the outward factor.
_NONE = np.empty(0)


def _add_barrier(problem: Problem, X: np.ndarray, normal: Normal, barrier_steps: np.ndarray,
                 out: Linearisation | None, outward: tuple[np.ndarray, float] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """In place: the barrier's samples into the blocks and gradient (one compiled pass,
    :func:`~.barrier_terms.add_barrier_terms`; the steps with a sample inside the clearance marked in
    ``barrier_steps``). Returns the samples' residuals (M,), those beyond the barrier's reach 0, and their
    distances (M,), written into ``out``'s if it has them. ``outward``: (the distances (M,) at the last
    linearisation, the curvature factor of the samples that moved away since), see
    :func:`~.barrier_terms.add_barrier_terms`."""
    env = problem.environment
    barrier, f = env.barrier, env.barrier.field
    step, alpha = problem.barrier_sample_points
    if out is not None and out.barrier_r is not None and len(out.barrier_r) == len(step):
        r, d = out.barrier_r, out.barrier_d
    else:
        r, d = np.empty(len(step)), np.empty(len(step))
    before, factor = outward if outward is not None else (_NONE, 0.0)
    hinge = Hinge(float(barrier.clearance), float(barrier.softness), barrier.gain(env.weight), float(factor))
    add_barrier_terms(X, step, alpha, problem.grid.dt, f.values, np.asarray(f.origin, dtype=float), float(f.resolution),
                      hinge, normal, r, d, barrier_steps, before)
    return r, d


def linearise(problem: Problem, X: np.ndarray, out: Linearisation | None = None,
              step_cost: np.ndarray | None = None, outward: tuple[np.ndarray, float] | None = None) -> Linearisation:
    """Costs, gradient and the block-tridiagonal Gauss–Newton matrix at X (n, 6).

    ``out``: a linearisation of the same problem whose arrays are overwritten (an iteration's
    tens of megabytes are then allocated once, not every time). ``step_cost`` (n,): if given, filled
    with the objective split by step (the motion and barrier terms between t and t + 1 on t, the
    first velocity's prior on 0, observations and height on their step); it sums to the total.
    ``outward``: (barrier distances (M,) of the last linearisation, factor) — the barrier's samples that moved away
    from the obstacles since take that curvature factor in D (``SolverOptions.outward_curvature``; the costs and g
    are the same).
    """
    n = problem.grid.n
    D0, B0 = problem.motion_normal
    if out is None:
        D, B, g, barrier_steps = np.empty_like(D0), np.empty_like(B0), np.empty((n, STATE)), np.empty(n, dtype=bool)
    else:
        D, B, g, barrier_steps = out.D, out.B, out.g, out.barrier_steps
    np.copyto(D, D0)                                 # Λ_X, then the other terms on top
    np.copyto(B, B0)
    g.fill(0.0)
    barrier_steps.fill(False)
    motion_cost = add_motion_terms(X, problem.A, problem.W, g)
    gain = problem.motion.first_velocity_gain
    rv = first_velocity_residuals(X, gain)
    g[0, VEL] += gain * rv
    motion_cost += float(rv @ rv)
    if step_cost is not None:
        step_cost.fill(0.0)
        step_cost[:-1] = np.einsum("ij,ij->i", *(2 * (motion_residuals(X, problem.A, problem.W),)))
        step_cost[0] += float(rv @ rv)
    obs_cost = 0.0
    for term, (starts, steps) in zip(problem.pixel_terms, problem.observation_groups):
        obs_cost += _add_pixel_term(term, starts, steps, problem.robust, X, D, g, step_cost)
    env = problem.environment
    barrier_cost = height_cost = 0.0
    r = d = None
    if env.barrier is not None:
        r, d = _add_barrier(problem, X, Normal(D, B, g), barrier_steps, out, outward)
        barrier_cost = float(r @ r)
        if step_cost is not None:
            step_cost += np.bincount(problem.barrier_sample_points[0], r * r, minlength=n)
    if env.height is not None:
        rh, gain = height_residuals(X, env.height, env.weight)
        D[:, _W, _W] += gain * gain
        g[:, _W] += gain * rh
        height_cost = float(rh @ rh)
        if step_cost is not None:
            step_cost += rh * rh
    costs = Costs(motion_cost, obs_cost, barrier_cost, height_cost)
    return Linearisation(costs, g, D, B, barrier_steps, r, d)
