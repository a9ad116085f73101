"""The race between starts and the free-space route start: the model floor that lets a start leave the race
early, and the compiled kernels of the route search against their references."""

import numpy as np
import pytest

from worldtrack.synth import make_scenario
from worldtrack.trajectory import kernels, starts
from worldtrack.trajectory.environment import sample_field
from worldtrack.trajectory.estimate import TrajectoryOptions, build_environment, estimate_trajectory
from worldtrack.trajectory.model import TimeGrid, frame_interval
from worldtrack.trajectory.objective import Problem
from worldtrack.trajectory.solver import LevenbergMarquardt, solve_blocks
from worldtrack.trajectory.starts import shortest_path_start, straight_start


def _problem(obs, field, height):
    options = TrajectoryOptions(height=height)
    dt = frame_interval(obs.time, obs.camera)
    grid = TimeGrid.covering(obs.time, dt)
    return Problem.build(obs, grid, options.motion, build_environment(options, field, dt)), options


def test_the_model_decrease_kernel_equals_its_reference():
    rng = np.random.default_rng(4)
    A = rng.normal(size=(30, 6, 6))
    D, B = np.einsum("nij,nkj->nik", A, A) + 6 * np.eye(6), rng.normal(size=(29, 6, 6))
    g, x = rng.normal(size=(30, 6)), rng.normal(size=(30, 6))
    assert kernels.model_decrease(D, B, g, x) == pytest.approx(kernels.model_decrease_reference(D, B, g, x), rel=1e-12)


def test_the_model_floor_is_the_objective_less_the_next_steps_predicted_decrease(office_person):
    problem, options = _problem(*office_person)
    X0 = straight_start(problem.observations, problem.grid, options.height)
    lm = LevenbergMarquardt(problem, X0, options.solver)
    lin = lm.lin
    damping = lm.mu * np.diagonal(lin.D, axis1=1, axis2=2)
    Dd = lin.D.copy()
    Dd[:, np.arange(6), np.arange(6)] += damping
    delta = solve_blocks(Dd, lin.B, -lin.g)                  # LAPACK: the step of the Gauss–Newton model
    floor = lm.model_floor()
    assert lin.costs.total - floor == pytest.approx(kernels.model_decrease(lin.D, lin.B, lin.g, delta), rel=1e-6)
    assert floor < lin.costs.total
    fresh = LevenbergMarquardt(problem, X0, options.solver)     # the floor's step is the next iteration's
    np.testing.assert_array_equal(lm.run(2).X, fresh.run(2).X)


@pytest.mark.slow
def test_a_start_leaves_the_race_early_and_the_winner_and_its_path_are_those_of_the_whole_race(office_person,
                                                                                                   monkeypatch):
    obs, field, height = office_person
    pruned = estimate_trajectory(obs, field, TrajectoryOptions(height=height))
    monkeypatch.setattr(LevenbergMarquardt, "model_floor", lambda self: -np.inf)       # no start ever leaves
    whole = estimate_trajectory(obs, field, TrajectoryOptions(height=height))
    assert pruned.start == whole.start == "shortest"
    np.testing.assert_array_equal(pruned.X, whole.X)
    iterations = {name: r.iterations for name, r in pruned.results.items()}
    assert iterations["straight"] < 5 and iterations["map"] < 5                     # they left early
    assert sum(iterations.values()) < sum(r.iterations for r in whole.results.values())
    assert pruned.start_objectives["straight"] > pruned.costs["total"]


def test_the_compiled_field_lookup_equals_sample_field():
    field = make_scenario("non-overlapping", frames=2, seed=0, people=1, layout="detours").scene.distance_field(0.05)
    xy = np.random.default_rng(6).uniform([-3, -3], [20, 12], size=(5000, 2))     # inside and beyond the grid
    d = kernels.field_values(field.values, np.asarray(field.origin, float), float(field.resolution), xy)
    np.testing.assert_array_equal(d, sample_field(field, xy)[0])


def test_the_compiled_route_search_equals_scipys_dijkstra(office_person):
    _, field, _ = office_person
    rng = np.random.default_rng(7)
    free = []
    while len(free) < 12:                                   # pairs of points in free space, far apart
        p = rng.uniform([0, 0], [16, 8], size=2)
        if sample_field(field, p[None])[0][0] > 0.3:
            free.append(p)
    length = lambda r: float(np.hypot(*np.diff(r, axis=0).T).sum())     # noqa: E731
    for a, b in zip(free[::2], free[1::2]):
        lo, hi = np.minimum(a, b) - 2.0, np.maximum(a, b) + 2.0
        fast = starts._route_in_box(field, a, b, 0.2, 0.1, lo, hi)
        ref = starts._route_in_box(field, a, b, 0.2, 0.1, lo, hi, reference=True)
        assert (fast is None) == (ref is None)
        if fast is not None:
            assert length(fast) == pytest.approx(length(ref), abs=1e-9)
            np.testing.assert_allclose(fast, ref)          # no ties on these rasters: the same cells


def test_which_gaps_are_blocked_in_one_lookup_equals_the_gap_by_gap_reference(office_person):
    _, field, _ = office_person
    rng = np.random.default_rng(11)
    a = rng.uniform([0, 0], [16, 8], size=(300, 2))
    b = a + rng.normal(0.0, 1.5, size=(300, 2)) * rng.uniform(0, 1, size=(300, 1)) ** 3   # short and long gaps
    b[:5] = a[:5]                                                                          # and zero-length ones
    b[5:125] = a[5:125] + np.column_stack([0.025 * np.arange(1, 121), np.zeros(120)])     # 2 … 121 samples each
    pts, first = starts._gap_samples(field, a, b)
    reference = [a[g] + np.linspace(0.0, 1.0, max(2, int(np.ceil(np.linalg.norm(b[g] - a[g]) / 0.025)) + 1))[:, None]
                 * (b[g] - a[g]) for g in range(len(a))]
    np.testing.assert_array_equal(pts, np.vstack(reference))                               # the same points, bit for bit
    np.testing.assert_array_equal(first, np.cumsum([0] + [len(r) for r in reference[:-1]]))
    blocked = starts._blocked_gaps(field, a, b, 0.2)
    assert blocked.tolist() == [starts._blocked(field, p, q, 0.2) for p, q in zip(a, b)]
    assert 30 < blocked.sum() < 270                                                        # both answers occur
    assert starts._blocked_gaps(field, a[:0], b[:0], 0.2).shape == (0,)


def test_the_route_start_goes_round_what_blocks_the_straight_line(office_person):
    obs, field, height = office_person
    problem, options = _problem(obs, field, height)
    X = shortest_path_start(problem.observations, problem.grid, height, field, options.clearance)
    d, _ = sample_field(field, X[:, [0, 2]])
    straight = straight_start(problem.observations, problem.grid, height)
    assert sample_field(field, straight[:, [0, 2]])[0].min() < 0 < d.min()
