"""The opt-in ``SolverOptions.outward_curvature`` (34n) on the office person: the same optimum within the slides'
tolerance, and the covariance of Newton's matrix at the estimate, not of the solver's modified one."""

from dataclasses import replace

import numpy as np
import pytest

from worldtrack.trajectory.estimate import TrajectoryOptions, build_environment, estimate_trajectory
from worldtrack.trajectory.model import TimeGrid, frame_interval
from worldtrack.trajectory.objective import Problem, linearise
from worldtrack.trajectory.solver import LevenbergMarquardt, SolverOptions
from worldtrack.trajectory.uncertainty import marginal_covariances


def test_outward_curvature_reaches_the_default_optimum_with_newtons_covariance(office_person):
    obs, field, height = office_person
    options = TrajectoryOptions(height=height)
    default = estimate_trajectory(obs, field, options)
    opted = estimate_trajectory(obs, field, replace(options, solver=SolverOptions(outward_curvature=1.3)))
    assert opted.start == default.start
    assert abs(opted.costs["total"] / default.costs["total"] - 1) < 1e-5
    assert np.hypot(*(opted.positions[:, :2] - default.positions[:, :2]).T).max() < 0.05
    dt = frame_interval(obs.time, obs.camera)
    problem = Problem.build(obs, TimeGrid.covering(obs.time, dt), options.motion, build_environment(options, field, dt))
    plain = linearise(problem, opted.X)
    np.testing.assert_allclose(opted.covariance, marginal_covariances(plain.D, plain.B), rtol=1e-9, atol=1e-15)
    # the solver's own last linearisation has the outward factor in it: a different matrix
    solver_lin = opted.results[opted.start].linearisation
    assert np.abs(solver_lin.D - plain.D).max() > 1e-6 * np.abs(plain.D).max()


def test_finish_newton_ends_on_newtons_matrix_at_or_below_the_default_optimum(office_person):
    """``finish_newton``: after the outward factor's run stops, the run goes on with Newton's factor, so it ends on
    the plain linearisation, no higher than the default's stop (bar: 1e-6), and after more iterations than without."""
    obs, field, height = office_person
    options = TrajectoryOptions(height=height)
    default = estimate_trajectory(obs, field, options)
    outward = SolverOptions(outward_curvature=1.3)
    alone = estimate_trajectory(obs, field, replace(options, solver=outward))
    finished = estimate_trajectory(obs, field, replace(options, solver=replace(outward, finish_newton=True)))
    assert finished.start == default.start
    assert finished.costs["total"] <= default.costs["total"] * (1 + 1e-6)
    assert finished.results[finished.start].iterations > alone.results[alone.start].iterations
    dt = frame_interval(obs.time, obs.camera)
    problem = Problem.build(obs, TimeGrid.covering(obs.time, dt), options.motion, build_environment(options, field, dt))
    plain = linearise(problem, finished.X)
    solver_lin = finished.results[finished.start].linearisation
    np.testing.assert_allclose(solver_lin.D, plain.D, rtol=1e-12, atol=1e-12 * np.abs(plain.D).max())


def test_finish_newton_solves_its_first_step_on_newtons_matrix(office_person):
    """The switch re-linearises at the outward run's stop: from there the matrix is Newton's, and so is the step."""
    obs, field, height = office_person
    options = TrajectoryOptions(height=height)
    default = estimate_trajectory(obs, field, options)
    dt = frame_interval(obs.time, obs.camera)
    problem = Problem.build(obs, TimeGrid.covering(obs.time, dt), options.motion, build_environment(options, field, dt))
    X0 = default.results[default.start].X + 0.3            # a start the solver must walk back from
    solver = LevenbergMarquardt(problem, X0, SolverOptions(outward_curvature=1.3, finish_newton=True))
    while not solver._finishing and not solver.converged:
        solver.run(1)
    assert solver._finishing and not solver.converged
    plain = linearise(problem, solver.X)
    np.testing.assert_allclose(solver.lin.D, plain.D, rtol=1e-12, atol=1e-12 * np.abs(plain.D).max())
    fresh = LevenbergMarquardt(problem, solver.X, SolverOptions())
    fresh.mu = solver.mu
    assert solver.model_floor() == pytest.approx(fresh.model_floor(), rel=1e-12)   # the step of Newton's model
    before = solver.iterations
    solver.run()
    assert solver.converged and solver.iterations > before
