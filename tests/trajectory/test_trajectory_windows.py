"""The race per gap (:mod:`worldtrack.trajectory.windows`): per-step costs, windows, packing, the windowed solver."""

import numpy as np
import pytest

from worldtrack.trajectory.estimate import TrajectoryOptions, build_environment
from worldtrack.trajectory.model import TimeGrid, frame_interval
from worldtrack.trajectory.objective import Problem, linearise
from worldtrack.trajectory.observation import Observations
from worldtrack.trajectory.solver import LevenbergMarquardt, levenberg_marquardt
from worldtrack.trajectory.starts import shortest_path_start, straight_start
from worldtrack.trajectory.windows import pack, race_by_gap, solve_windows, window_cuts, window_sums


@pytest.fixture(scope="module")
def office_problem(office):
    """The office person's problem with the barrier, its starts, the MAP without the barrier and the cuts."""
    sc, tracks, pixels = office
    person = pixels.of(1)
    obs = Observations.from_rows(person.time, person.camera, person.uv, sc.scene.cameras, 2.0)
    field = sc.scene.distance_field(0.05)
    options = TrajectoryOptions(height=tracks[1].height)
    dt = frame_interval(obs.time, obs.camera)
    grid = TimeGrid.covering(obs.time, dt)
    problem = Problem.build(obs, grid, options.motion, build_environment(options, field, dt))
    straight = straight_start(problem.observations, grid, options.height)
    free = levenberg_marquardt(problem.with_environment(problem.environment.without_barrier()), straight).X
    shortest = shortest_path_start(problem.observations, grid, options.height, field, options.clearance)
    cuts = window_cuts(np.bincount(problem.observations.step, minlength=grid.n) > 0)
    assert len(cuts) >= 4                                               # several gaps between views
    return problem, {"straight": straight, "map": free, "shortest": shortest}, cuts


def test_the_step_costs_add_up_to_the_objective_and_a_window_sees_only_its_states(office_problem):
    problem, starts, cuts = office_problem
    X = starts["shortest"].copy()
    cost = np.empty(len(X))
    total = linearise(problem, X, step_cost=cost).costs.total
    assert cost.sum() == pytest.approx(total, rel=1e-12)
    before = window_sums(cost, cuts[:-1])
    w = 1
    X[cuts[w] + 1:cuts[w + 1], 0] += 0.3                                # move window 1's inner states only
    linearise(problem, X, step_cost=cost)
    changed = np.flatnonzero(np.abs(window_sums(cost, cuts[:-1]) - before) > 1e-12 * np.abs(before))
    assert changed.tolist() == [w]


def test_packed_windows_equal_the_trajectory_up_to_constants(office_problem):
    problem, starts, cuts = office_problem
    windows = np.array([0, 2, len(cuts) - 2])                          # the first, one inside, the last
    packed = pack(problem, cuts, windows)
    assert packed.held.sum() == 2 * len(windows) - 2                   # the trajectory's own ends are free
    assert np.array_equal(packed.index[packed.offsets[:-1]], cuts[windows])
    X1 = starts["shortest"].copy()
    X2 = X1.copy()
    inner = np.ones(len(X1), dtype=bool)
    inner[cuts] = False
    X2[inner, 2] += 0.2
    X2[inner, 3] -= 0.1
    real, packed_sums = [], []
    for X in (X1, X2):
        cost, small = np.empty(len(X)), np.empty(len(packed.index))
        linearise(problem, X, step_cost=cost)
        linearise(packed.problem, X[packed.index], step_cost=small)
        small[packed.seams] = 0.0
        real.append(window_sums(cost, cuts[:-1])[windows])
        packed_sums.append(window_sums(small, packed.offsets[:-1]))
    np.testing.assert_allclose(packed_sums[1] - packed_sums[0], real[1] - real[0], rtol=1e-9, atol=1e-9)


def test_the_windowed_solver_holds_the_cuts_and_leaves_the_polish_nothing_to_do(office_problem):
    problem, starts, cuts = office_problem
    options = TrajectoryOptions().solver
    X0 = starts["shortest"].copy()
    X0[cuts] = starts["map"][cuts]
    X, work = solve_windows(problem, X0, cuts, options)
    np.testing.assert_array_equal(X[cuts[1:-1]], X0[cuts[1:-1]])          # the first and last state are free
    polish = LevenbergMarquardt(problem, X, options)
    before = polish.lin.costs.total
    after = polish.run()
    assert after.iterations <= 3 and before - after.costs.total < 1e-4 * before
    start = LevenbergMarquardt(problem, X0, options).lin.costs.total
    assert before < 0.5 * start and work > 1


def test_the_race_by_gap_reaches_the_optimum_of_every_start(office_problem):
    problem, starts, cuts = office_problem
    options = TrajectoryOptions().solver
    result, wins, _ = race_by_gap(problem, starts, starts["map"], options)
    every = min(levenberg_marquardt(problem, X, options).costs.total for X in starts.values())
    assert result.costs.total <= every * (1 + 1e-6)
    assert sum(v for k, v in wins.items() if "shortest" in k) >= 1
    assert {name for label in wins for name in label.split("+")} <= set(starts)
