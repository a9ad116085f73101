"""Levenberg–Marquardt on the windows still moving (:mod:`worldtrack.trajectory.settle`, an option): the settled
windows' states do not move, the restricted solve is the whole problem's with those states held, and the run
reaches the default's optimum on the office."""

from dataclasses import replace

import numpy as np
import pytest

from worldtrack.trajectory.estimate import TrajectoryOptions, build_environment, estimate_trajectory
from worldtrack.trajectory.model import TimeGrid, frame_interval
from worldtrack.trajectory.objective import Problem
from worldtrack.trajectory.settle import HeldLM, restrict, restricted_cuts
from worldtrack.trajectory.solver import LevenbergMarquardt
from worldtrack.trajectory.starts import straight_start
from worldtrack.trajectory.windows import window_cuts

#: windows of the office person: 0–4, 4–44, 44–133, 133–175, 175–179; the second and the fourth still move
ACTIVE = np.array([False, True, False, True, False])


@pytest.fixture(scope="module")
def midway(office_person):
    """The office problem, its windows, and a run 6 iterations from the straight start (paths still moving)."""
    obs, field, height = office_person
    options = TrajectoryOptions(height=height)
    dt = frame_interval(obs.time, obs.camera)
    grid = TimeGrid.covering(obs.time, dt)
    problem = Problem.build(obs, grid, options.motion, build_environment(options, field, dt))
    cuts = window_cuts(np.bincount(problem.observations.step, minlength=grid.n) > 0)
    assert len(cuts) == len(ACTIVE) + 1
    run = LevenbergMarquardt(problem, straight_start(problem.observations, grid, height), options.solver)
    run.run(6)
    assert not run.converged
    return problem, cuts, run.X.copy(), options


def _free(cuts: np.ndarray, n: int) -> np.ndarray:
    """(n,) the states the restriction may move: inside the active windows (their cut with a settled one held)."""
    free = np.zeros(n, dtype=bool)
    for w in np.flatnonzero(ACTIVE):
        free[cuts[w] + (cuts[w] > 0):cuts[w + 1]] = True
    return free


def test_the_restriction_moves_no_settled_state(midway):
    problem, cuts, X0, options = midway
    run = LevenbergMarquardt(problem, X0, options.solver)
    restrict(run, cuts, ACTIVE)
    free = _free(cuts, len(X0))
    np.testing.assert_array_equal(run.X[~free], X0[~free])           # settled windows and their cuts: untouched
    for w in np.flatnonzero(ACTIVE):                                 # the others went on, each of them
        assert np.abs(run.X[cuts[w] + 1:cuts[w + 1]] - X0[cuts[w] + 1:cuts[w + 1]]).max() > 1e-6
    assert run.lin.costs.total < LevenbergMarquardt(problem, X0, options.solver).lin.costs.total


def test_the_restricted_solve_is_the_whole_problem_with_the_settled_states_held(midway):
    problem, cuts, X0, options = midway
    tight = replace(options.solver, barrier_relative_decrease=1e-13, max_iterations=300)
    run = LevenbergMarquardt(problem, X0, tight)
    restrict(run, cuts, ACTIVE, nested=False)
    whole = HeldLM(problem, X0, tight, ~_free(cuts, len(X0))).run()
    assert run.lin.costs.total == pytest.approx(whole.costs.total, rel=1e-9)
    assert np.abs(run.X[:, [0, 2]] - whole.X[:, [0, 2]]).max() < 1e-6


def test_restricted_cuts_merge_neighbouring_active_windows():
    cuts, ranges = restricted_cuts(np.array([0, 4, 44, 133, 175, 179]), np.array([True, True, False, True, True]))
    assert cuts.tolist() == [0, 44, 133, 179] and ranges.tolist() == [0, 2]


def test_settling_reaches_the_default_optimum_on_the_office(office_person):
    obs, field, height = office_person
    options = TrajectoryOptions(height=height)
    a = estimate_trajectory(obs, field, options)
    b = estimate_trajectory(obs, field, replace(options, settle_windows=True))
    assert b.costs["total"] <= a.costs["total"] * (1 + 1e-6)
    assert np.hypot(*(a.positions[:, :2] - b.positions[:, :2]).T).max() < 0.01
