"""X* = argmin of eq. 9 from several starts, keeping the lowest objective (seed 002, section 2.4).

:func:`estimate_trajectory` is the whole method for one person: the time grid from the
observations' time stamps, the three starts of :mod:`.starts`, banded Levenberg–Marquardt from
each, the winner, its per-step covariance, each term's cost and where the barrier pushes.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from worldtrack.errors import InputError
from worldtrack.scene.floor import FloorGrid
from worldtrack.trajectory.coarse import coarse_grid, refine, subsample
from worldtrack.trajectory.environment import Barrier, EnvironmentModel, HeightPrior, sample_field
from worldtrack.trajectory.model import POS, VEL, MotionPrior, TimeGrid, frame_interval
from worldtrack.trajectory.objective import Problem, linearise
from worldtrack.trajectory.observation import Observations
from worldtrack.trajectory.solver import LevenbergMarquardt, SolveResult, SolverOptions, levenberg_marquardt
from worldtrack.trajectory.starts import (ROUTE_TIMINGS, START_NAMES, anchor_points, shortest_path_start,
                                         straight_start)
from worldtrack.trajectory.uncertainty import marginal_covariances
from worldtrack.trajectory.settle import run_settling
from worldtrack.trajectory.windows import race_by_gap


@dataclass(frozen=True)
class TrajectoryOptions:
    """Everything :func:`estimate_trajectory` can be told; the defaults suit walking adults.

    Parameters
    ----------
    dt : float or None, seconds — grid step; None: the cameras' frame interval (:func:`frame_interval`)
    motion : MotionPrior — eq. 4's noise (m²/s³)
    height : float, metres — the person's head height for e_v and the starts
    height_sigma : float, metres — e_v's spread
    fit_height : bool — the head height is not known: with feet pixels (see :class:`~.observation.Observations`)
        the MAP is first solved with e_v loosened to ``fit_height_sigma`` around ``height``, the person's
        head height H is taken as the mean estimated head height over the observed steps (weighted by the
        inverse of each step's height variance: near a camera's nadir the height is barely seen), and the MAP
        is solved again with H. Without feet pixels the height cannot be seen (one head pixel per camera
        cannot tell height from distance) and ``height`` is used as given
    fit_height_sigma : float, metres — e_v's spread in the first of those two solves
    clearance : float, metres — the barrier starts this far from obstacles and walls
    barrier_scale : float, metres — a penetration of this much costs 1 per sample
    substeps : int or None — barrier samples per step; None: enough for 2.5 m/s (:meth:`Barrier.substeps_for`)
    weight : float — λ, the environment's weight
    robust : float or None — Huber threshold for the reprojection errors, in σ
    starts : tuple of str — a subset of ``("straight", "map", "shortest")``
    environment : bool — False: no barrier at all (the paper's comparison without e_h)
    race_iterations : int or None — every start gets this many iterations; only the one with the
        lowest objective then goes on to convergence (None: every start converges, as the paper).
        A start leaves the race earlier, even before its first iteration, once the minimum of its
        Gauss–Newton model is above the objective another start already has (``_race``).
        With a race, when the MAP without the barrier keeps so clear of every obstacle that its
        barrier cost is below the solver's tolerance, it is the optimum within that tolerance and
        is the only start run; when the leader converges to a path with a step inside an obstacle
        (a local optimum: five iterations do not always rank the starts), every start converges
    race_by_gap : bool — with a race, choose the start gap by gap instead (:mod:`.windows`): each window
        between two observed runs takes the start with the lowest objective there, the windows converge
        on their own, then the whole is polished (``race_iterations`` is then not used; if the result
        has a step inside an obstacle every start converges, as above). About 25–30 % less time than the
        race at T ≥ 10 000 steps, the same routes, but it may settle in another of the shallow minima a
        few centimetres apart in long gaps: objective within ±4e-5 relative of every start's (lower as
        often as not), not the same to 1e-6 — hence not the default
    coarse_steps : int or None — with a race, solve the MAP with the barrier coarse to fine
        (:mod:`.coarse`): the race on every step until one start is left (the same ranking as the default),
        then that leader on every ``coarse_steps``-th step of the grid (the same model re-derived for the
        longer step) until an iteration lowers F by less than ``coarse_tolerance``, brought back to every
        step by the motion prior's interpolation and polished there by Levenberg–Marquardt with ``solver``.
        Off by default (None): 34h measured it (``benchmarks/trajectory_coarse.py``, CPU medians on walks of
        T = 1 000 … 100 000) from 40 % slower (T = 1 000, m = 4) to 36 % faster (T = 100 000, m = 8) — the
        polish still needs the slow last iterations that slide paths along obstacles — and the polish may
        settle in a neighbouring one of the shallow minima: walks within −1.9e-4 … +2.2e-5 of the default's
        objective, up to 0.45 m apart in long gaps; on ETH/UCY (1 153 people × 2 obstacle maps) the same
        objective within 1e-6 for all but one zara01 person (camera seed 4, walls + free space), whose
        other minimum moved that row's between-views RMSE 0.303 → 0.348 m
    coarse_tolerance : float — the relative decrease that ends the coarse solve
    settle_windows : bool — with a race, the leader's iterations go on the windows still moving only, once
        windows with half of the steps have settled (:mod:`.settle`); off by default
    route_timing : str — how the ``shortest`` start walks each route: ``"constant"`` speed (the default) or
        ``"cubic"``, the motion prior's timing from the MAP without the barrier's velocities at the gap's ends
        (:func:`~.starts.cubic_timing`). 34m (``benchmarks/trajectory_slides.py``, the walks of
        ``trajectory_speed.py``): leader iterations at T = 10 000 21/28/35 → 17/19/31 (dev walks 3/42/90),
        26/19/28/10/10/21 → 18/19/19/10/10/14 (held-out 200–202, 400–402), 24/9/25 → 20/9/27 (never-used
        500–502), but it stops elsewhere on the flat slides: objective −4.6e-5 … +2.2e-5 of the default's (4 of 12
        above +1e-6), and at T = 1 000 walk 3 in a neighbouring minimum +2.0e-4 higher; office (``trajectory_office.py --route-timing cubic``) between views
        0.778 → 0.781 m, in view, obstacles and crossings unchanged — hence opt-in
    solver : SolverOptions
    """

    dt: float | None = None
    motion: MotionPrior = field(default_factory=MotionPrior)
    height: float = 1.70
    height_sigma: float = 0.05
    fit_height: bool = False
    fit_height_sigma: float = 1.0
    clearance: float = 0.2
    barrier_scale: float = 0.02
    substeps: int | None = None
    weight: float = 1.0
    robust: float | None = None
    starts: tuple[str, ...] = START_NAMES
    environment: bool = True
    race_iterations: int | None = 5
    race_by_gap: bool = False
    coarse_steps: int | None = None
    coarse_tolerance: float = 1e-3
    settle_windows: bool = False
    route_timing: str = "constant"
    solver: SolverOptions = field(default_factory=SolverOptions)

    def __post_init__(self) -> None:
        unknown = [s for s in self.starts if s not in START_NAMES]
        if unknown or not self.starts:
            raise InputError(f"starts: expected some of {', '.join(START_NAMES)}, got {', '.join(self.starts) or 'none'}")
        if self.robust is not None and not self.robust > 0:
            raise InputError(f"robust: expected a positive Huber threshold in sigmas, got {self.robust}")
        if not self.weight > 0:
            raise InputError(f"weight: expected λ > 0, got {self.weight}")
        if self.route_timing not in ROUTE_TIMINGS:
            raise InputError(f"route_timing: expected one of {', '.join(ROUTE_TIMINGS)}, got {self.route_timing!r}")
        if self.coarse_steps is not None and (int(self.coarse_steps) != self.coarse_steps or self.coarse_steps < 2):
            raise InputError(f"coarse_steps: expected an integer ≥ 2 or None, got {self.coarse_steps}")


@dataclass
class TrajectoryEstimate:
    """The MAP trajectory of one person and what it rests on.

    Attributes
    ----------
    times : (n,) seconds
    X : (n, 6) states (u, u̇, v, v̇, w, ẇ) in m and m/s
    covariance : (n, 6, 6) — diagonal blocks of the inverse Gauss–Newton matrix at X
    costs : dict — each term of the objective at X, and the total
    start : str — the start whose optimum won; with the race by gap, the starts that won a window
        joined by "+", most windows first (all of them when every window is a tie)
    start_objectives : dict str → float — the final objective of every start that was run (a start that
        left the race: its objective then; with the race by gap: ``start`` → the final objective)
    observed : (n,) int — observations at each step
    barrier_active : (n,) bool — steps where the barrier pushes (a sample inside the clearance)
    without_barrier : (n, 6) — the MAP without the barrier (start ``map``), for comparison
    results : dict str → SolveResult — per start that was run (without a barrier ``straight`` and
        ``map`` are one solve)
    height : float, metres — the head height H of e_v (fitted with ``fit_height``)
    window_wins : dict str → int — with the race by gap: how many windows each start won (windows
        where the starts' objectives differ; starts tying at the lowest joined by "+")
    """

    times: np.ndarray
    X: np.ndarray
    covariance: np.ndarray
    costs: dict[str, float]
    start: str
    start_objectives: dict[str, float]
    observed: np.ndarray
    barrier_active: np.ndarray
    without_barrier: np.ndarray
    results: dict[str, SolveResult]
    height: float = float("nan")
    window_wins: dict[str, int] = field(default_factory=dict)

    @property
    def positions(self) -> np.ndarray:
        """(n, 3) head positions, metres."""
        return self.X[:, POS]

    @property
    def velocities(self) -> np.ndarray:
        """(n, 3) head velocities, m/s."""
        return self.X[:, VEL]

    @property
    def position_covariance(self) -> np.ndarray:
        """(n, 3, 3) covariance of the head position, m²."""
        return self.covariance[:, POS[:, None], POS[None, :]]

    @property
    def sigma(self) -> np.ndarray:
        """(n, 3) standard deviation of x, y, z, metres."""
        return np.sqrt(np.maximum(np.diagonal(self.position_covariance, axis1=1, axis2=2), 0.0))

    def columns(self) -> dict[str, np.ndarray]:
        """The columns of ``trajectory.csv``."""
        p, v, s = self.positions, self.velocities, self.sigma
        C = self.position_covariance
        rho = C[:, 0, 1] / np.maximum(s[:, 0] * s[:, 1], 1e-300)
        return {"t": self.times, "x": p[:, 0], "y": p[:, 1], "z": p[:, 2], "vx": v[:, 0], "vy": v[:, 1],
                "vz": v[:, 2], "sigma_x": s[:, 0], "sigma_y": s[:, 1], "sigma_z": s[:, 2], "rho_xy": rho,
                "observed": self.observed, "barrier": self.barrier_active.astype(int)}


def build_environment(options: TrajectoryOptions, field: FloorGrid | None, dt: float) -> EnvironmentModel:
    """The environment model the options describe for a grid step ``dt`` (s)."""
    height = HeightPrior(options.height, options.height_sigma)
    if field is None or not options.environment:
        return EnvironmentModel(None, height, options.weight)
    substeps = options.substeps or Barrier.substeps_for(dt, options.clearance)
    barrier = Barrier(field, options.clearance, options.barrier_scale, substeps)
    return EnvironmentModel(barrier, height, options.weight)


def estimate_trajectory(obs: Observations, field: FloorGrid | None = None,
                        options: TrajectoryOptions = TrajectoryOptions()) -> TrajectoryEstimate:
    """The MAP trajectory of one person from their head pixels (seed 002).

    Parameters
    ----------
    obs : Observations — one person's head pixels, in time order
    field : FloorGrid or None — signed distance to obstacles and walls (``Scene.distance_field()``);
        None: no barrier
    options : TrajectoryOptions

    Examples
    --------
    >>> from worldtrack.geometry.camera import Camera
    >>> cams = {c: Camera.look_at(c, 320, 240, position=(x, 0, 3), target=(x, 0.3, 0), hfov_deg=60)
    ...         for c, x in (("a", 0.0), ("b", 4.0))}
    >>> t = np.arange(0, 4.01, 0.1); path = np.column_stack([t, 0 * t, 0 * t + 1.7])   # 1 m/s along x
    >>> seen = (np.abs(t - 0) < 0.6) | (np.abs(t - 4) < 0.6)
    >>> ids = np.where(t < 2, "a", "b")[seen]
    >>> obs = Observations.from_points(t[seen], ids, path[seen], cams)
    >>> est = estimate_trajectory(obs)
    >>> float(np.abs(est.positions[:, 0] - t).max()) < 0.01      # the gap is bridged at 1 m/s
    True
    """
    if options.fit_height and obs.has_feet.any():
        loose = estimate_trajectory(obs, field, replace(options, fit_height=False, height_sigma=options.fit_height_sigma))
        seen = loose.observed > 0
        height = float(np.average(loose.positions[seen, 2], weights=loose.sigma[seen, 2] ** -2.0))
        return estimate_trajectory(obs, field, replace(options, fit_height=False, height=height))
    dt = options.dt or frame_interval(obs.time, obs.camera)
    grid = TimeGrid.covering(obs.time, dt)
    env = build_environment(options, field, dt)
    problem = Problem.build(obs, grid, options.motion, env, options.robust)
    free = problem.with_environment(env.without_barrier())
    anchors = anchor_points(problem.observations, options.height)
    straight = straight_start(problem.observations, grid, options.height, anchors)
    without = levenberg_marquardt(free, straight, options.solver)
    if env.barrier is None:          # "straight" and "map": the same problem from the same start
        results, wins = {name: without for name in options.starts if name != "shortest"} or {"map": without}, {}
    else:
        results, wins = _barrier_starts(problem, straight, without, options, anchors)
    objectives = {name: r.costs.total for name, r in results.items()}
    best = min(objectives, key=objectives.get)
    win = results[best]
    observed = np.bincount(problem.observations.step, minlength=grid.n)
    lin = win.linearisation if options.solver.outward_curvature is None else linearise(problem, win.X)
    covariance = marginal_covariances(lin.D, lin.B)      # Newton's curvature, not the outward factor's
    return TrajectoryEstimate(grid.times, win.X, covariance, win.costs.as_dict(), best, objectives, observed,
                              win.linearisation.barrier_steps, without.X, results, options.height, wins)


def _barrier_starts(problem: Problem, straight: np.ndarray, without: SolveResult, options: TrajectoryOptions,
                    anchors: tuple[np.ndarray, np.ndarray]) -> tuple[dict[str, SolveResult], dict[str, int]]:
    """Levenberg–Marquardt with the barrier from each start: the race by gap, the race (every start
    ``options.race_iterations``, then only the leader to convergence) or every start to convergence.
    Returns the result per start (or per winning starts) and the windows each start won."""
    made: dict[str, LevenbergMarquardt] = {}       # runs already set up (linearised) at their start
    if options.race_iterations is not None and "map" in options.starts:
        made["map"] = polish = LevenbergMarquardt(problem, without.X, options.solver)
        if polish.lin.costs.barrier <= options.solver.barrier_relative_decrease * polish.lin.costs.total:
            # F(X) ≥ F_free(X) ≥ F_free(X_free) = F(X_free) − barrier(X_free) for every X: no start
            # beats the MAP without the barrier by more than its barrier cost, here below the
            # tolerance the solver stops at, so there is no race (walls far from the path)
            return {"map": polish.run()}, {}
    starts = {"straight": straight, "map": without.X}
    barrier = problem.environment.barrier
    if "shortest" in options.starts:
        starts["shortest"] = shortest_path_start(problem.observations, problem.grid, options.height, barrier.field,
                                                 options.clearance, max(barrier.field.resolution, 0.1), anchors,
                                                 options.route_timing, without.X[:, [VEL[0], VEL[1]]])
    if options.race_iterations is not None and options.race_by_gap:
        result, wins, _ = race_by_gap(problem, {name: starts[name] for name in options.starts}, without.X,
                                      options.solver)
        if sample_field(barrier.field, result.X[:, [POS[0], POS[1]]])[0].min() >= 0:
            count = {name: sum(v for label, v in wins.items() if name in label.split("+")) for name in options.starts}
            won = sorted((name for name in count if count[name]), key=lambda name: -count[name]) or list(options.starts)
            return {"+".join(won): result}, wins
        options = replace(options, race_iterations=None)       # a step inside an obstacle: every start converges
    runs = {name: made.get(name) or LevenbergMarquardt(problem, starts[name], options.solver) for name in options.starts}
    if options.race_iterations is None:
        for run in runs.values():
            run.run()
    else:                                        # only the leader goes on to convergence
        _race(runs, options.race_iterations, until_one=bool(options.coarse_steps))
        name = min(runs, key=lambda name: runs[name].lin.costs.total)
        coarse = 0
        if options.coarse_steps and not runs[name].converged:
            runs[name], coarse = _coarse_to_fine(problem, runs[name].X, options)
        leader = runs[name]
        run_settling(leader) if options.settle_windows else leader.run()
        if coarse:
            leader.message += f" (after {coarse} iterations on every {options.coarse_steps}th step)"
        if sample_field(problem.environment.barrier.field, leader.X[:, [POS[0], POS[1]]])[0].min() < 0:
            for run in runs.values():            # the leader ended inside an obstacle: a local optimum the
                run.run()                        # barrier could not push out of; every start converges
    return {name: run.result for name, run in runs.items()}, {}


def _coarse_to_fine(problem: Problem, X: np.ndarray, options: TrajectoryOptions) -> tuple[LevenbergMarquardt, int]:
    """The race's leader X (n, 6) solved on every ``options.coarse_steps``-th step (:mod:`.coarse`) until an
    iteration lowers F by less than ``options.coarse_tolerance``, brought back to every step: the run that
    polishes it (not yet run) and the coarse iterations."""
    m = int(options.coarse_steps)
    grid = coarse_grid(problem.grid, m)
    env = build_environment(options, problem.environment.barrier.field, grid.dt)
    coarse = Problem.build(problem.observations.obs, grid, problem.motion, env, problem.robust)
    solver = replace(options.solver, barrier_relative_decrease=options.coarse_tolerance)
    run = LevenbergMarquardt(coarse, subsample(X, m, grid.n), solver)
    run.run()
    return LevenbergMarquardt(problem, refine(run.X, problem.motion, grid.dt, m, problem.grid.n), options.solver), \
        run.iterations


def _race(runs: dict[str, LevenbergMarquardt], iterations: int, until_one: bool = False) -> None:
    """Every start ``iterations`` iterations, round by round; a start leaves the race as soon as the
    minimum of its Gauss–Newton model (:meth:`~.solver.LevenbergMarquardt.model_floor`) is above the
    objective some start already has — even the decrease its local model promises would leave it behind
    (the model's minimum foretells where a start is heading: 34f's traces put the winner's within
    1–3 % of its optimum from the first iteration on). The leader's own iterations are not changed.
    ``until_one``: stop as soon as a single start is left in the race (coarse to fine takes it from there)."""
    racing = list(runs.values())
    for k in range(iterations + 1):
        best = min(run.lin.costs.total for run in runs.values())
        racing = [run for run in racing if run.model_floor() <= best]    # the holder of ``best`` stays
        if k == iterations or (until_one and len(racing) == 1):
            break
        for run in racing:
            run.run(1)


def with_height(options: TrajectoryOptions, height: float) -> TrajectoryOptions:
    """The same options for a person of another head height (m)."""
    return replace(options, height=float(height))
