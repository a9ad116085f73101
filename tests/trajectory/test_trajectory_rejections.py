"""A run of rejections (34b): a step that comes back after a rejection changed only by the raised damping is not
linearised again when its trial is sure to be rejected too; the iterates are those of evaluating it."""

from dataclasses import replace

import numpy as np
import pytest

from worldtrack.trajectory.estimate import TrajectoryOptions, build_environment
from worldtrack.trajectory.model import TimeGrid, frame_interval
from worldtrack.trajectory.objective import Problem
from worldtrack.trajectory.solver import LevenbergMarquardt
from worldtrack.trajectory.starts import straight_start


class Counting(LevenbergMarquardt):
    """Counts the skipped trials."""
    skipped = 0

    def _still_rejected(self, delta):
        same = super()._still_rejected(delta)
        self.skipped += same
        return same


class Evaluating(LevenbergMarquardt):
    """Linearises every trial (the solver before 34b)."""

    def _still_rejected(self, delta):
        return False


@pytest.fixture(scope="module")
def problem_and_start(office_person):
    obs, field, height = office_person
    options = TrajectoryOptions(height=height)
    dt = frame_interval(obs.time, obs.camera)
    grid = TimeGrid.covering(obs.time, dt)
    problem = Problem.build(obs, grid, options.motion, build_environment(options, field, dt))
    # μ starts at 1e-18 of diag H (as near an obstacle late in a run): raising it hardly changes the step, so
    # rejected steps come back all but unchanged
    return problem, straight_start(problem.observations, grid, height), replace(options.solver, initial_damping=1e-18)


def test_skipping_unchanged_rejected_steps_gives_the_same_iterates(problem_and_start):
    problem, X0, options = problem_and_start
    skipping = Counting(problem, X0, options)
    a = skipping.run()
    b = Evaluating(problem, X0, options).run()
    assert skipping.skipped >= 3                       # 7 when written
    assert a.iterations == b.iterations and a.message == b.message
    np.testing.assert_array_equal(a.X, b.X)            # bit for bit


def _after_a_rejection(problem_and_start) -> LevenbergMarquardt:
    problem, X0, options = problem_and_start
    lm = LevenbergMarquardt(problem, X0, options)
    for _ in range(40):
        X = lm.X
        lm.run(1)
        if lm.X is X and lm._rejected is not None:
            return lm
    pytest.fail("no rejection")


def test_a_step_is_skipped_only_if_its_trial_must_rise_too(problem_and_start):
    lm = _after_a_rejection(problem_and_start)
    delta, F_trial = lm._rejected
    F = lm.lin.costs.total
    assert F_trial > F
    assert lm._still_rejected(delta.copy())
    assert lm._still_rejected(delta + 1e-9)
    assert not lm._still_rejected(delta + 2e-3)                 # beyond 1 mm: changed
    lm._rejected = (delta, F + 1e-12 * F)                        # a rise within rounding: evaluate it
    assert not lm._still_rejected(delta + 1e-9)
    lm._rejected = (delta, F - 1.0)                              # a trial that fell: never skipped
    assert not lm._still_rejected(delta)
