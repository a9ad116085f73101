"""The opt-in cubic timing of the shortest-path start's routes (``TrajectoryOptions.route_timing``)."""

import numpy as np
import pytest

from worldtrack.errors import InputError
from worldtrack.trajectory.estimate import TrajectoryOptions, build_environment, estimate_trajectory
from worldtrack.trajectory.model import TimeGrid, frame_interval
from worldtrack.trajectory.objective import Problem
from worldtrack.trajectory.starts import cubic_timing, shortest_path_start, walk_route


def test_cubic_timing_meets_both_ends_and_leaves_from_rest_slowly():
    s = cubic_timing(3.0, 3.0, 0.0, 1.0, 31)
    assert s[0] == 0.0 and s[-1] == 3.0 and np.all(np.diff(s) >= 0)
    assert s[1] < 0.25 * 0.1                       # from rest: well below the 0.1 m per step of constant speed
    assert abs((s[-1] - s[-2]) / 0.1 - 1.0) < 0.1      # arrives at 1 m/s
    assert np.allclose(cubic_timing(2.0, 2.0, 1.0, 1.0, 5), [0.0, 0.5, 1.0, 1.5, 2.0])   # the mean speed: constant


def test_walk_route_reads_the_end_speeds_along_the_route():
    route = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0]])           # 4 m, a corner
    fast_then_slow = walk_route(route, 4.0, np.array([2.0, 0.0]), np.array([0.0, 0.5]), 41)
    across = walk_route(route, 4.0, np.array([0.0, 2.0]), np.array([0.0, 0.5]), 41)     # v0 across the route: 0
    np.testing.assert_allclose(fast_then_slow[[0, -1]], route[[0, -1]])
    assert np.hypot(*(fast_then_slow[1] - route[0])) > 0.15          # leaves at ~2 m/s (0.2 m in 0.1 s)
    assert np.hypot(*(across[1] - route[0])) < 0.05                  # leaves from (nearly) rest
    d = np.hypot(*np.diff(fast_then_slow, axis=0).T)
    assert d[-1] < d[0] / 2                                           # arrives slowly


def test_the_cubic_start_walks_the_same_routes_with_other_timing(office_person):
    obs, field, height = office_person
    options = TrajectoryOptions(height=height)
    dt = frame_interval(obs.time, obs.camera)
    grid = TimeGrid.covering(obs.time, dt)
    problem = Problem.build(obs, grid, options.motion, build_environment(options, field, dt))
    constant = shortest_path_start(problem.observations, grid, height, field, options.clearance)
    with pytest.raises(InputError, match="route timing"):
        shortest_path_start(problem.observations, grid, height, field, options.clearance, timing="cubic")
    still = np.zeros((grid.n, 2))
    cubic = shortest_path_start(problem.observations, grid, height, field, options.clearance, 0.1, None, "cubic", still)
    moved = np.hypot(*(cubic[:, [0, 2]] - constant[:, [0, 2]]).T) > 1e-6
    assert moved.any()                                                # the timing differs in the routed gaps ...
    first, last = np.flatnonzero(moved)[[0, -1]]
    np.testing.assert_array_equal(cubic[:first - 1], constant[:first - 1])    # ... and nowhere else
    np.testing.assert_array_equal(cubic[last + 2:], constant[last + 2:])
    # from rest at both ends of each route: slower than constant speed at its ends
    step_c = np.hypot(*np.diff(constant[:, [0, 2]], axis=0).T)
    step_k = np.hypot(*np.diff(cubic[:, [0, 2]], axis=0).T)
    assert step_k[first - 1] < step_c[first - 1] and step_k[last] < step_c[last]


def test_route_timing_is_checked_and_reaches_the_start(office_person):
    with pytest.raises(InputError, match="route_timing"):
        TrajectoryOptions(route_timing="wiggle")
    obs, field, height = office_person
    every = dict(height=height, race_iterations=None, starts=("shortest",))
    default = estimate_trajectory(obs, field, TrajectoryOptions(**every))
    cubic = estimate_trajectory(obs, field, TrajectoryOptions(route_timing="cubic", **every))
    assert default.results["shortest"].iterations != cubic.results["shortest"].iterations or \
        not np.array_equal(default.X, cubic.X)
