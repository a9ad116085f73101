"""The barrier's step limit as a trust region (``SolverOptions(shrink_on_reject=True)``, an option): a rejected
step halves the largest move allowed and keeps its Gauss–Newton step and its damping (no second solve, no
runaway damping); the default raises the damping instead."""

from dataclasses import replace

import numpy as np
import pytest

from worldtrack.trajectory.estimate import TrajectoryOptions, build_environment
from worldtrack.trajectory.model import TimeGrid, frame_interval
from worldtrack.trajectory.objective import Problem
from worldtrack.trajectory.observation import Observations
from worldtrack.trajectory.solver import LevenbergMarquardt
from worldtrack.trajectory.starts import straight_start


@pytest.fixture(scope="module")
def office_problem(office):
    sc, tracks, pixels = office
    person = pixels.of(1)
    obs = Observations.from_rows(person.time, person.camera, person.uv, sc.scene.cameras, 2.0)
    options = TrajectoryOptions(height=tracks[1].height)
    dt = frame_interval(obs.time, obs.camera)
    grid = TimeGrid.covering(obs.time, dt)
    problem = Problem.build(obs, grid, options.motion, build_environment(options, sc.scene.distance_field(0.05), dt))
    return problem, straight_start(problem.observations, grid, options.height), options


def _first_rejection(lm: LevenbergMarquardt, most: int = 30):
    """Iterate until a step is rejected; (μ, raw step, largest move tried) before it, or None."""
    for _ in range(most):
        X, mu = lm.X, lm.mu
        lm.model_floor()                                  # the raw step, kept for the next iteration
        raw = lm._pending[0].copy()
        tried = min(lm.move_limit, float(np.hypot(raw[:, 0], raw[:, 2]).max()))
        lm.run(1)
        if lm.X is X and not lm.converged:
            return mu, raw, tried
    return None


def test_a_rejected_step_halves_the_move_limit_and_keeps_its_step_and_damping(office_problem):
    problem, X0, options = office_problem
    # a limit of 20 m: the first full Gauss–Newton steps run the straight start's paths through the desks
    lm = LevenbergMarquardt(problem, X0, replace(options.solver, max_move=20.0, shrink_on_reject=True))
    rejected = _first_rejection(lm)
    assert rejected is not None
    mu, raw, tried = rejected
    assert lm.mu == mu                                      # the damping did not grow
    assert lm.move_limit == pytest.approx(0.5 * tried, rel=1e-12)
    np.testing.assert_array_equal(lm._pending[0], raw)      # the same step is tried again, shorter
    solves = []
    step = lm._step
    lm._step = lambda lin: solves.append(1) or step(lin)
    lm.run(1)
    assert solves == []                                     # ... without solving for it again


def test_without_the_trust_region_a_rejection_raises_the_damping_instead(office_problem):
    problem, X0, options = office_problem
    lm = LevenbergMarquardt(problem, X0, replace(options.solver, max_move=20.0, shrink_on_reject=False))
    mu, _, _ = _first_rejection(lm)
    assert lm.mu == pytest.approx(2.0 * mu) and lm.move_limit == 20.0


def test_the_trust_region_reaches_the_same_optimum(office_problem):
    problem, X0, options = office_problem
    tight = replace(options.solver, barrier_relative_decrease=1e-12, max_iterations=300)
    a = LevenbergMarquardt(problem, X0, replace(tight, shrink_on_reject=True)).run()
    b = LevenbergMarquardt(problem, X0, replace(tight, shrink_on_reject=False)).run()
    assert a.converged and b.converged
    assert a.costs.total == pytest.approx(b.costs.total, rel=1e-9)
    assert np.abs(a.X[:, [0, 2]] - b.X[:, [0, 2]]).max() < 1e-4




def test_inside_a_shrunk_trust_region_no_state_moves_beyond_it_with_the_look_ahead_on(office_problem):
    # 34k: the look-ahead (on by default since 34i) lets every state whose floor is clear take its whole move,
    # so after a rejection the halved radius did not bind and the same step was tried until the iteration limit
    problem, X0, options = office_problem
    lm = LevenbergMarquardt(problem, X0, replace(options.solver, shrink_on_reject=True))
    assert lm.options.look_ahead is not None
    lm.model_floor()
    raw = lm._pending[0]
    moves = np.hypot(raw[:, 0], raw[:, 2])
    full, _ = lm._limit(lm.lin, raw, 1.0)                               # the full radius: the look-ahead shapes it
    assert np.hypot(full[:, 0], full[:, 2]).max() > options.solver.max_move
    lm.move_limit, lm._shrunk = 0.5 * min(moves.max(), options.solver.max_move), True   # as after a rejection
    step, predicted = lm._limit(lm.lin, raw, 1.0)
    assert np.hypot(step[:, 0], step[:, 2]).max() <= lm.move_limit * (1 + 1e-12)
    assert predicted > 0

def test_a_rejected_step_longer_than_max_move_leaves_a_radius_within_max_move(office_problem):
    # 34k: the look-ahead may carry clear states beyond max_move; half of such a rejected move was still beyond
    # it, the look-ahead came back and tried the same step again
    problem, X0, options = office_problem
    lm = LevenbergMarquardt(problem, X0, replace(options.solver, shrink_on_reject=True))
    lm.model_floor()
    damping = lm._pending[1]
    bad = np.zeros_like(X0)
    bad[:, 0] = 0.9                                                     # everybody 0.9 m to the side: F rises
    lm._pending = (bad, damping)
    lm._limit = lambda lin, delta, predicted: (delta, 1.0)            # as if the look-ahead took it whole
    lm.run(1)
    del lm._limit
    assert lm.X is not None and np.array_equal(lm.X, X0)                # rejected
    assert lm.move_limit == options.solver.max_move and lm._shrunk      # not 0.45 m
    step, _ = lm._limit(lm.lin, lm._pending[0], 1.0)
    assert np.hypot(step[:, 0], step[:, 2]).max() <= options.solver.max_move * (1 + 1e-12)
