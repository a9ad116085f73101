"""The whole method end to end (seed 002): starts, MAP with the environment, the baseline."""

import numpy as np
import pytest

from worldtrack.errors import InputError
from worldtrack.trajectory.environment import inside_obstacles, sample_field
from worldtrack.trajectory.estimate import TrajectoryOptions, estimate_trajectory
from worldtrack.trajectory.model import TimeGrid
from worldtrack.trajectory.observation import Observations
from worldtrack.trajectory.smoother import constant_velocity, kalman_rts
from worldtrack.trajectory.starts import free_space_route, shortest_path_start, straight_start

from _trajectory_cases import observed_walk


def test_straight_start_passes_through_the_back_projected_observations():
    case = observed_walk(T=81, noise_px=0.0)
    X = straight_start(case.problem.observations, case.problem.grid, 1.7)
    seen = np.unique(case.problem.observations.step)
    # back-projected to 1.7 m while the head bobs ±1 cm: within a couple of centimetres
    assert np.abs(X[seen][:, [0, 2]] - case.truth[seen, :2]).max() < 0.03
    gap = np.setdiff1d(np.arange(len(X)), seen)
    assert np.allclose(np.diff(X[gap[1:-1], 0], 2), 0, atol=1e-9)     # straight at constant speed


def test_free_space_route_goes_round_a_wall_and_keeps_its_clearance(office):
    sc, _, _ = office
    field = sc.scene.distance_field(0.05)
    a, b = np.array([3.0, 4.0]), np.array([5.0, 4.0])                  # screen1 at x = 4 m, y 2.6–4.6 m
    route = free_space_route(field, a, b, clearance=0.2)
    d, _ = sample_field(field, route[1:-1])
    assert d.min() > 0.15 and route[:, 1].max() > 4.75                 # through the north passage
    length = np.sum(np.hypot(*np.diff(route, axis=0).T))
    assert 2.0 + 0.8 < length < 4.0


def test_free_space_route_finds_a_far_door_and_never_enters_a_wall():
    from worldtrack.trajectory.environment import field_from_walkable
    walk = np.ones((120, 60), dtype=bool)                               # x −3…2.9 m, y −6…5.9 m at 0.1 m
    walk[:90, 35] = False                                               # a thin wall at x = 0.5 m up to y = 3 m
    field = field_from_walkable(walk, (-3.0, -6.0), 0.1)
    a, b = np.array([0.0, 0.0]), np.array([1.0, 0.0])
    route = free_space_route(field, a, b, clearance=0.2)
    d, _ = sample_field(field, route)
    assert route[:, 1].max() > 3.0 and d.min() > 0                      # round the end, 3 m away, not through it
    closed = walk.copy()
    closed[:, 35] = False
    assert free_space_route(field_from_walkable(closed, (-3.0, -6.0), 0.1), a, b, 0.2) is None


def _office_estimate(office, **options):
    sc, tracks, pixels = office
    person = pixels.of(1)
    obs = Observations.from_rows(person.time, person.camera, person.uv, sc.scene.cameras, 2.0)
    field = sc.scene.distance_field(0.05)
    est = estimate_trajectory(obs, field, TrajectoryOptions(height=tracks[1].height, **options))
    truth = tracks[1].points[np.rint(est.times * sc.fps).astype(int)]
    return est, truth, field, obs


@pytest.mark.slow
def test_office_with_detours_map_beats_the_kalman_smoother_and_keeps_out_of_obstacles(office):
    est, truth, field, obs = _office_estimate(office)
    seen = est.observed > 0
    err = np.hypot(*(est.positions[:, :2] - truth[:, :2]).T)
    assert np.sqrt(np.mean(err[seen] ** 2)) < 0.03                      # 2 px, in view
    assert np.sqrt(np.mean((est.positions[seen, 2] - truth[seen, 2]) ** 2)) < 0.05
    assert not inside_obstacles(field, est.positions[:, :2]).any()
    grid = TimeGrid(est.times[0], est.times[1] - est.times[0], len(est.times))
    base = kalman_rts(obs, grid, 1.0, office[1][1].height)
    base_err = np.hypot(*(base.xy - truth[:, :2]).T)
    assert inside_obstacles(field, base.xy).sum() > 5                   # the baseline walks through screens
    between = ~seen
    assert np.sqrt(np.mean(err[between] ** 2)) < 0.7 * np.sqrt(np.mean(base_err[between] ** 2))
    assert est.start == "shortest"                                      # only it knows the passages
    assert est.results["shortest"].converged                            # the race's leader went on
    assert est.start_objectives["shortest"] < est.start_objectives["straight"]
    by_gap = estimate_trajectory(obs, field, TrajectoryOptions(height=office[1][1].height, race_by_gap=True))
    assert sum(v for k, v in by_gap.window_wins.items() if "shortest" in k) >= 1
    assert by_gap.costs["total"] <= est.costs["total"] * (1 + 1e-6)   # the race by gap: the same optimum here
    # without the barrier the MAP cuts through a screen, as the paper's figure shows
    assert inside_obstacles(field, est.without_barrier[:, [0, 2]]).any()
    # the uncertainty is larger between views than in them
    assert np.median(est.sigma[~seen, 0]) > 5 * np.median(est.sigma[seen, 0])


def test_unsynchronised_cameras_cost_no_accuracy():
    case = observed_walk(T=81, noise_px=0.5, seed=4)
    obs = case.obs
    shifted = np.where(obs.camera == 1, obs.time + 0.037, obs.time)     # camera b 37 ms late
    from _trajectory_cases import walk
    t, pts = walk(81)
    truth_at = np.column_stack([np.interp(shifted, t, pts[:, k]) for k in range(3)])
    uv = np.empty_like(obs.uv)
    for k, cam in enumerate(obs.cameras):
        sel = obs.camera == k
        uv[sel] = cam.project(truth_at[sel])
    moved = Observations(shifted, obs.camera, uv, obs.sigma, obs.cameras)
    est = estimate_trajectory(moved, None, TrajectoryOptions(dt=0.1))
    k = np.searchsorted(est.times, shifted[obs.camera == 1][0])
    assert abs(est.times[1] - est.times[0] - 0.1) < 1e-12
    truth = np.column_stack([np.interp(est.times, t, pts[:, j]) for j in range(3)])
    seen = est.observed > 0
    assert np.hypot(*(est.positions[seen, :2] - truth[seen, :2]).T).max() < 0.02
    assert k > 0


def test_the_kalman_smoother_equals_the_batch_least_squares_of_its_model():
    """RTS smoothing is the MAP of the linear-Gaussian model: solve that model densely and compare."""
    case = observed_walk(T=41, noise_px=1.0, seed=6)
    grid = TimeGrid(case.problem.grid.t0, 0.1, case.problem.grid.n)
    from worldtrack.trajectory.smoother import backproject_with_covariance
    q = 0.8
    base = kalman_rts(case.obs, grid, q, 1.7, initial_speed_sigma=2.0)
    xy, cov = backproject_with_covariance(case.obs, 1.7)
    n = grid.n
    F, Q = constant_velocity(0.1, q)
    rows, rhs = [], []
    Qi = np.linalg.cholesky(np.linalg.inv(Q)).T
    for k in range(n - 1):                                   # motion
        A = np.zeros((4, 4 * n))
        A[:, 4 * k:4 * k + 4] = -Qi @ F
        A[:, 4 * k + 4:4 * k + 8] = Qi
        rows.append(A)
        rhs.append(np.zeros(4))
    step, _ = grid.locate(case.obs.time)
    H = np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]])
    for i, k in enumerate(step):                             # measurements
        Ri = np.linalg.cholesky(np.linalg.inv(cov[i])).T
        A = np.zeros((2, 4 * n))
        A[:, 4 * k:4 * k + 4] = Ri @ H
        rows.append(A)
        rhs.append(Ri @ xy[i])
    first = 0                                                # the filter's prior at the first time
    P0 = np.diag([cov[first, 0, 0], 4.0, cov[first, 1, 1], 4.0])
    Pi = np.linalg.cholesky(np.linalg.inv(P0)).T
    A = np.zeros((4, 4 * n))
    A[:, :4] = Pi
    rows.append(A)
    rhs.append(Pi @ np.array([xy[first, 0], 0.0, xy[first, 1], 0.0]))
    sol = np.linalg.lstsq(np.vstack(rows), np.concatenate(rhs), rcond=None)[0].reshape(n, 4)
    np.testing.assert_allclose(base.xy, sol[:, [0, 2]], atol=1e-7)


def test_options_are_checked():
    with pytest.raises(InputError, match="starts"):
        TrajectoryOptions(starts=("wiggle",))
    with pytest.raises(InputError, match="Huber"):
        TrajectoryOptions(robust=-1.0)


def test_shortest_start_equals_straight_where_nothing_is_in_the_way():
    from worldtrack.scene.floor import FloorGrid
    case = observed_walk(T=81, noise_px=0.0)
    a = straight_start(case.problem.observations, case.problem.grid, 1.7)
    open_floor = FloorGrid(np.array([-5.0, -5.0]), 0.1, np.full((120, 120), 5.0))
    b = shortest_path_start(case.problem.observations, case.problem.grid, 1.7, open_floor, 0.2)
    np.testing.assert_array_equal(a, b)


def test_without_a_wall_near_the_map_there_is_no_race_and_the_same_optimum():
    """A wall 1.5 m beside the walk: the MAP without the barrier keeps clear of it, so the default
    estimate only polishes that start, and lands where running every start to convergence does."""
    from worldtrack.trajectory.environment import field_from_walkable
    walkable = np.ones((80, 120), dtype=bool)        # x −1…4.95 m, y −2…1.95 m
    walkable[70:, :] = False                         # a wall from y = 1.5 m
    case = observed_walk(T=81, noise_px=2.0)
    field = field_from_walkable(walkable, (-1.0, -2.0), 0.05)
    raced = estimate_trajectory(case.obs, field, TrajectoryOptions(dt=0.1))
    every = estimate_trajectory(case.obs, field, TrajectoryOptions(dt=0.1, race_iterations=None))
    assert set(raced.results) == {"map"} and set(every.results) == {"straight", "map", "shortest"}
    assert raced.costs["total"] <= min(every.start_objectives.values()) * (1 + 1e-5)
    np.testing.assert_allclose(raced.positions, every.positions, atol=5e-3)
    walkable[46:, :] = False                         # the wall at y = 0.3 m: within the barrier's reach
    near = estimate_trajectory(case.obs, field_from_walkable(walkable, (-1.0, -2.0), 0.05), TrajectoryOptions(dt=0.1))
    assert set(near.results) == {"straight", "map", "shortest"}
    by_gap = estimate_trajectory(case.obs, field_from_walkable(walkable, (-1.0, -2.0), 0.05),
                                 TrajectoryOptions(dt=0.1, race_by_gap=True))
    assert by_gap.window_wins and "map" not in by_gap.results          # the race by gap ran
    assert by_gap.costs["total"] <= near.costs["total"] * (1 + 1e-6)


def test_without_environment_the_map_is_solved_once_and_is_the_estimate():
    case = observed_walk(T=81, noise_px=2.0)
    est = estimate_trajectory(case.obs, None, TrajectoryOptions(dt=0.1))
    assert est.results["straight"] is est.results["map"]
    np.testing.assert_array_equal(est.X, est.without_barrier)


def test_the_first_velocity_prior_is_its_own_term_and_holds_a_person_seen_once():
    """‖ẋ_1/σ₁‖² is added to the motion cost, exactly; a person seen once and then, 8 s later,
    walking across the line to them: the paper's flat start lets the first velocity take whatever
    bends the path most smoothly, a tight prior holds it at rest."""
    from dataclasses import replace
    from worldtrack.trajectory.model import MotionPrior
    from worldtrack.trajectory.objective import evaluate
    from _trajectory_cases import ceiling_cameras
    cams = ceiling_cameras()
    t = np.r_[0.0, np.arange(8.0, 10.01, 0.1)]
    pts = np.column_stack([np.r_[0.0, np.full(len(t) - 1, 4.0)], np.r_[0.0, (t[1:] - 8.0) * 0.8 - 0.8],
                           np.full(len(t), 1.7)])
    obs = Observations.from_points(t, np.r_[["a"], ["b"] * (len(t) - 1)], pts, cams)
    flat = TrajectoryOptions(dt=0.1, motion=MotionPrior(first_velocity_sigma=None))
    est_flat = estimate_trajectory(obs, None, flat)
    est_tight = estimate_trajectory(obs, None, replace(flat, motion=MotionPrior(first_velocity_sigma=0.01)))
    est = estimate_trajectory(obs, None, TrajectoryOptions(dt=0.1))                # default σ₁ = 2 m/s
    speed = lambda e: float(np.hypot(*e.velocities[0, :2]))  # noqa: E731
    assert speed(est_flat) > 0.2 and speed(est_tight) < 0.01
    assert speed(est_tight) < speed(est) < speed(est_flat)
    from worldtrack.trajectory.objective import Problem
    from worldtrack.trajectory.environment import EnvironmentModel, HeightPrior
    grid = TimeGrid.covering(obs.time, 0.1)
    env = EnvironmentModel(None, HeightPrior(1.7, 0.05), 1.0)
    with_prior = Problem.build(obs, grid, MotionPrior(first_velocity_sigma=0.5), env)
    without = Problem.build(obs, grid, MotionPrior(first_velocity_sigma=None), env)
    X = est_flat.X
    difference = evaluate(with_prior, X).motion - evaluate(without, X).motion
    assert difference == pytest.approx(float(np.sum(X[0, [1, 3, 5]] ** 2)) / 0.25, rel=1e-12)
    with pytest.raises(InputError, match="first_velocity_sigma"):
        MotionPrior(first_velocity_sigma=0.0)
