"""The look-ahead step limit (:mod:`worldtrack.trajectory.lookahead`, ``SolverOptions(look_ahead=…)``): each
state goes as far along its Gauss–Newton move as the floor lets it, smoothed in time, instead of the whole
path scaled to its worst state's 0.25 m."""

from dataclasses import replace

import numpy as np
import pytest

from worldtrack.scene.floor import FloorGrid
from worldtrack.trajectory import solver as solver_module
from worldtrack.trajectory.environment import Barrier, sample_field
from worldtrack.trajectory.lookahead import shape_step, state_shares, trace_reference
from worldtrack.trajectory.solver import LevenbergMarquardt

RES = 0.05
_X = np.arange(0.0, 6.0 + RES / 2, RES)


def _field(values_of_x) -> FloorGrid:
    """A field over [0, 6]² m that depends on x only."""
    return FloorGrid(np.zeros(2), RES, np.tile(values_of_x(_X), (len(_X), 1)))


def _shares(field, xy, move, clearance=0.2):
    """The compiled trace, one sample per state (substeps 1, states at rest, so each sample is its state)."""
    n = len(xy)
    X = np.zeros((n + 1, 6))
    X[:-1, 0], X[:-1, 2] = xy[:, 0], xy[:, 1]
    X[-1] = X[-2]
    delta = np.zeros_like(X)
    delta[:-1, 0], delta[:-1, 2] = move[:, 0], move[:, 1]
    out = np.empty(n)
    for k in range(n):                                          # one state at a time: no neighbour's min
        one = np.zeros((2, 6)); one[0], one[1] = X[k], X[k]
        step = np.zeros((2, 6)); step[0], step[1] = delta[k], delta[k]
        out[k] = state_shares(one, step, Barrier(field, clearance=clearance), 0.1)[0]
    return out


def test_a_move_stops_short_of_the_clearance_of_a_wall():
    field = _field(lambda x: 3.0 - x)                           # a wall beyond x = 3 m
    xy = np.array([[1.0, 1.0], [1.0, 1.0], [1.0, 1.0], [2.9, 1.0], [2.9, 1.0]])
    move = np.array([[1.9, 0.0], [-0.9, 0.0], [0.5, 0.3], [0.5, 0.0], [-1.0, 0.0]])
    alpha = _shares(field, xy, move)
    # towards the wall: stops before 2.8 m, within one clearance of it; away from the wall or short of
    # it: the whole move; from inside the clearance (d = 0.1 m) deeper: nothing; out of it: all
    assert 2.6 <= 1.0 + 1.9 * alpha[0] <= 2.8
    np.testing.assert_allclose(alpha[1:], [1.0, 1.0, 0.0, 1.0], atol=1e-12)


def test_a_move_the_first_stride_covers_is_whole_only_if_the_steepest_field_keeps_it_clear():
    """The end of a move within 0.7·(d − floor) is not looked up: still right where the field falls at 1.4 m/m
    (a bilinear distance field's steepest, √2, along a diagonal), and a move beyond that is traced."""
    field = _field(lambda x: 1.4 * (3.0 - x))                  # d = 2.8 at x = 1, floor 0.2 at x = 2.857 m
    xy = np.array([[1.0, 1.0], [1.0, 1.0]])
    alpha = _shares(field, xy, np.array([[1.8, 0.0], [2.4, 0.0]]))
    assert alpha[0] == 1.0                                     # 1.8 ≤ 0.7·2.6 m: whole, and 2.8 m keeps d = 0.28
    assert 1.0 + 2.4 * alpha[1] <= 2.86                        # 2.4 m (within d − floor = 2.6) is stopped


def test_the_compiled_trace_equals_its_reference_and_never_passes_an_obstacle(office_person):
    _, field, _ = office_person
    rng = np.random.default_rng(11)
    xy = rng.uniform([0.5, 0.5], [11.5, 7.5], size=(300, 2))
    move = rng.normal(scale=1.5, size=(300, 2))
    alpha = _shares(field, xy, move)
    np.testing.assert_allclose(alpha, trace_reference(field, xy, move, 0.2), atol=1e-12)
    assert 0.2 < np.mean(alpha < 1) < 0.8                       # some moves blocked, some not
    # walked every millimetre up to its share, no move enters an obstacle, and between its traced points (at
    # most a clearance apart) it comes no closer than its floor less 0.15 m; it stops within a clearance of
    # the first point closer than its floor
    for p, m, a in zip(xy, move, alpha):
        s = np.linspace(0.0, 1.0, int(np.hypot(*m) / 1e-3) + 2)[:, None]
        d = sample_field(field, p + s * m)[0]
        floor = min(0.2, d[0])
        walked = d[s[:, 0] <= a]
        assert np.all(walked >= floor - 0.15) and (floor < 0 or np.all(walked >= 0))
        if a < 1:
            first = s[np.argmax(d < floor), 0]
            assert (first - a) * np.hypot(*m) <= 0.2 + 1e-9


def test_a_thin_partition_is_never_jumped():
    field = _field(lambda x: np.abs(x - 3.025) - 0.025)        # a 5 cm partition at x = 3.00 … 3.05 m
    xy = np.column_stack([np.linspace(1.0, 2.7, 50), np.full(50, 3.0)])
    move = np.column_stack([np.linspace(0.5, 4.0, 50), np.zeros(50)])
    end = xy[:, 0] + _shares(field, xy, move) * move[:, 0]
    assert (xy[:, 0] + move[:, 0] > 3.0).sum() > 30
    assert np.all(end <= 2.8 + 1e-9)                            # short of the partition by its clearance


def test_on_a_clear_floor_the_step_is_the_whole_gauss_newton_step():
    field = _field(lambda x: 10.0 + 0 * x)
    rng = np.random.default_rng(3)
    X = np.column_stack([rng.uniform(1, 5, 40), rng.normal(size=40), rng.uniform(1, 5, 40), rng.normal(size=40),
                         np.full(40, 1.7), np.zeros(40)])
    delta = rng.normal(size=(40, 6))
    np.testing.assert_array_equal(shape_step(delta, X, Barrier(field, clearance=0.2, substeps=3), 0.1, 5, 0.1), delta)


def test_the_smoothed_shares_stay_within_each_states_own_look_ahead_and_the_velocities_follow():
    field = _field(lambda x: 3.0 - x)
    n, dt = 60, 0.1
    X = np.zeros((n, 6))
    X[:, 0], X[:, 2] = np.linspace(0.5, 2.7, n), 2.0
    delta = np.zeros((n, 6))
    delta[:, 0] = 1.0                                          # the same 1 m push towards the wall for all
    own = state_shares(X, delta, Barrier(field, clearance=0.2), dt)
    shaped = shape_step(delta, X, Barrier(field, clearance=0.2), 0.0, 4, dt)
    share = shaped[:, 0] / delta[:, 0]
    assert np.all(share <= own + 1e-12) and share.min() < share.max()
    # a translation scaled by α(t): the velocity change is the time derivative of the position change
    np.testing.assert_allclose(shaped[:, 1], np.gradient(shaped[:, 0], dt), atol=1e-12)
    np.testing.assert_array_equal(shaped[:, 3], 0.0)


@pytest.fixture(scope="module")
def office_problem(office_person):
    from worldtrack.trajectory.estimate import TrajectoryOptions, build_environment
    from worldtrack.trajectory.model import TimeGrid, frame_interval
    from worldtrack.trajectory.objective import Problem
    from worldtrack.trajectory.starts import straight_start
    obs, field, height = office_person
    options = TrajectoryOptions(height=height)
    dt = frame_interval(obs.time, obs.camera)
    grid = TimeGrid.covering(obs.time, dt)
    problem = Problem.build(obs, grid, options.motion, build_environment(options, field, dt))
    return problem, straight_start(problem.observations, grid, height), options


def test_the_look_ahead_takes_fewer_iterations_to_the_same_optimum(office_problem):
    problem, X0, options = office_problem
    ahead = LevenbergMarquardt(problem, X0, options.solver).run()
    fixed = LevenbergMarquardt(problem, X0, replace(options.solver, look_ahead=None)).run()
    assert ahead.iterations <= 0.6 * fixed.iterations            # measured 12 against 24
    assert ahead.costs.total == pytest.approx(fixed.costs.total, rel=1e-5)
    tight = replace(options.solver, look_ahead=None, barrier_relative_decrease=1e-12, max_iterations=300)
    a = LevenbergMarquardt(problem, ahead.X, tight).run()
    b = LevenbergMarquardt(problem, fixed.X, tight).run()
    assert a.costs.total == pytest.approx(b.costs.total, rel=1e-9)
    assert np.abs(a.X[:, [0, 2]] - b.X[:, [0, 2]]).max() < 1e-6


def test_a_shaped_step_that_is_no_descent_falls_back_to_the_move_limit(office_problem, monkeypatch):
    problem, X0, options = office_problem
    limited = []
    original = solver_module._limit_moves
    monkeypatch.setattr(solver_module, "shape_step", lambda delta, *a: -delta)      # uphill
    monkeypatch.setattr(solver_module, "_limit_moves", lambda *a: limited.append(1) or original(*a))
    lm = LevenbergMarquardt(problem, X0, options.solver)
    lm.run(1)
    assert limited == [1] and lm.lin.costs.total < LevenbergMarquardt(problem, X0, options.solver).lin.costs.total


def test_the_objective_settles_only_where_the_next_steps_model_agrees(office_problem, monkeypatch):
    problem, X0, options = office_problem
    loose = replace(options.solver, barrier_relative_decrease=0.05, max_iterations=30)

    def run(confirm, promise):
        lm = LevenbergMarquardt(problem, X0, replace(loose, confirm_stop=confirm))
        monkeypatch.setattr(lm, "_floor", lambda: lm.lin.costs.total * (1.0 - promise))   # what the model promises
        lm.run()
        return lm

    plain = run(False, 0.5)
    assert plain.converged and plain.message == "objective settled" and plain.iterations < 10
    agrees = run(True, 0.0)                                   # the model promises nothing more: the same stop
    assert agrees.iterations == plain.iterations and agrees.message == "objective settled"
    more = run(True, 0.5)                                     # the model promises half of F: it goes on
    assert more.iterations > plain.iterations and more.message != "objective settled"


def test_a_state_takes_the_least_share_of_the_samples_on_both_its_curves():
    field = _field(lambda x: 3.0 - x)
    X = np.array([[1.0, 0, 1.0, 0, 1.7, 0], [1.5, 0, 1.0, 0, 1.7, 0], [1.0, 0, 2.0, 0, 1.7, 0]])
    delta = np.zeros_like(X)
    delta[:2, 0] = 1.9                                         # both towards the wall; the third stays
    own = trace_reference(field, X[:, [0, 2]], delta[:, [0, 2]], 0.2)
    assert own[0] > own[1] + 0.2 and own[2] == 1.0
    shares = state_shares(X, delta, Barrier(field, clearance=0.2), 0.5)   # samples: the states only
    # the curve 1 → 2 is sampled at state 1 (its start) and state 2 (the last state): both take the least
    np.testing.assert_allclose(shares, [own[0], own[1], own[1]], atol=1e-12)


def test_traces_from_the_linearisations_distances_equal_traces_that_look_them_up(office_person):
    """The solver hands the look-ahead the distances its linearisation has at the samples: the same shares."""
    from worldtrack.trajectory.estimate import TrajectoryOptions, build_environment
    from worldtrack.trajectory.model import TimeGrid
    from worldtrack.trajectory.objective import Problem, linearise
    from worldtrack.trajectory.starts import straight_start
    obs, field, height = office_person
    grid = TimeGrid.covering(obs.time, 0.1)
    problem = Problem.build(obs, grid, TrajectoryOptions().motion, build_environment(TrajectoryOptions(), field, 0.1))
    X = straight_start(problem.observations, grid, height)
    delta = np.random.default_rng(3).normal(scale=0.8, size=X.shape)
    barrier = problem.environment.barrier
    looked_up = state_shares(X, delta, barrier, 0.1)
    assert 0.1 < np.mean(looked_up < 1) < 0.9
    np.testing.assert_array_equal(state_shares(X, delta, barrier, 0.1, linearise(problem, X).barrier_d), looked_up)
