"""The slides benchmark's pieces measure what they say: the along/across split and the field curvature term
of the barrier's model (benchmarks/trajectory_slides.py)."""

import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from trajectory_slides import along_across, curvature_blocks, field_hessian, sample_points  # noqa: E402

from worldtrack.scene.floor import FloorGrid  # noqa: E402
from worldtrack.trajectory.environment import Barrier, EnvironmentModel, sample_field  # noqa: E402


def test_along_across_splits_a_shift_by_the_direction_of_travel():
    ref = np.zeros((5, 6))
    ref[:, 1] = 1.0                               # travelling along x
    X = ref.copy()
    X[:, 0] += 0.3
    X[:, 2] += 0.4
    along, across = along_across(X, ref, np.ones(5, dtype=bool))
    assert np.isclose(along, 0.3) and np.isclose(across, 0.4)


def _point_obstacle_problem() -> SimpleNamespace:
    """What :func:`curvature_blocks` reads of a problem (its environment and grid step, 0.1 s): one obstacle, a
    point at the origin (the field: distance − 0.05 m)."""
    h = 0.02
    xs = np.arange(-1.0, 1.0 + h / 2, h)
    gx, gy = np.meshgrid(xs, xs)
    field = FloorGrid(np.array([xs[0], xs[0]]), h, np.hypot(gx, gy) - 0.05)
    env = EnvironmentModel(Barrier(field, clearance=0.2, scale=0.02, substeps=1), None, 1.0)
    return SimpleNamespace(environment=env, grid=SimpleNamespace(dt=0.1))


def test_curvature_term_predicts_the_barrier_change_of_a_tangential_move():
    # three states at rest 0.3 m from the point obstacle; the middle one moves 5 cm across ∇d (tangentially)
    X = np.zeros((3, 6))
    X[:, 0], X[:, 4] = 0.3, 1.7
    X[:, 2] = [-0.05, 0.0, 0.05]
    problem = _point_obstacle_problem()
    b = problem.environment.barrier
    gain = b.gain(1.0)
    delta = np.zeros_like(X)
    delta[1, 2] = 0.05

    def cost(Y):
        d = sample_field(b.field, sample_points(Y, b, 0.1)[2])[0]
        return float(np.sum((gain * b.softness * np.logaddexp(0.0, (b.clearance - d) / b.softness)) ** 2))

    actual = cost(X + delta) - cost(X)
    D, B = curvature_blocks(problem, X, field_hessian(b.field, smooth=0.0), 1.0)
    quad = sum(float(delta[t] @ D[t] @ delta[t]) for t in range(3)) + \
        2 * sum(float(delta[t] @ B[t] @ delta[t + 1]) for t in range(2))
    assert actual < 0 and quad < 0     # the move goes away from the point: cost falls
    # Gauss–Newton sees no change (the move is across ∇d); the curvature term's second-order change is most of it
    assert 0.5 < quad / actual < 1.5
