"""The timing step of benchmarks/trajectory_timing_steps.py keeps what it says: a state slides along the path
(position on the curve, velocity on its tangent) and its constraints pass exactly the moves of the timing."""

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from trajectory_timing_steps import PathCurve, slide, timing_constraints  # noqa: E402

DT, R = 0.1, 2.0


def _circle(n: int = 40, speed: float = 1.0) -> np.ndarray:
    """States (n, 6) walking anticlockwise round a circle of radius R (m) centred at the origin."""
    theta = np.arange(n) * speed * DT / R
    X = np.zeros((n, 6))
    X[:, 0], X[:, 2] = R * np.cos(theta), R * np.sin(theta)
    X[:, 1], X[:, 3] = -speed * np.sin(theta), speed * np.cos(theta)
    X[:, 4] = 1.7
    return X


def test_constraints_pass_a_timing_move_and_stop_a_sideways_one():
    X = _circle()
    curve = PathCurve(X, DT)
    tangent, speed, kappa, rows = timing_constraints(X, curve, np.zeros(len(X), dtype=bool), DT)
    k = 20
    assert np.isclose(kappa[k], 1 / R, rtol=1e-3) and np.isclose(speed[k], 1.0)
    normal = np.array([-tangent[k, 1], tangent[k, 0]])
    ds, dsdot = 0.1, 0.2                         # slide 10 cm on and speed up by 0.2 m/s
    step = np.zeros(6)
    step[[0, 2]] = ds * tangent[k]
    step[[1, 3]] = dsdot * tangent[k] + speed[k] * kappa[k] * ds * normal
    assert np.allclose(rows[k] @ step, 0.0, atol=1e-6)
    side = np.zeros(6)
    side[[0, 2]] = 0.1 * normal
    assert np.abs(rows[k] @ side).max() > 0.09
    _, _, _, held = timing_constraints(X, curve, np.arange(len(X)) == k, DT)
    assert not held[k].any()                     # a free state has no constraint


def test_slide_keeps_states_on_the_curve_with_tangent_velocities():
    X = _circle()
    curve = PathCurve(X, DT)
    tangent, speed, _, _ = timing_constraints(X, curve, np.zeros(len(X), dtype=bool), DT)
    moving = np.zeros(len(X), dtype=bool)
    moving[10:30] = True
    assert np.allclose(slide(X, np.zeros_like(X), curve, tangent, speed, moving), X, atol=1e-12)
    delta = np.zeros_like(X)
    delta[:, [0, 2]] = 0.3 * tangent             # 30 cm along the tangent line: off the circle by ~2 cm
    delta[:, [1, 3]] = 0.1 * tangent
    Y = slide(X, delta, curve, tangent, speed, moving)
    radius = np.hypot(Y[:, 0], Y[:, 2])
    assert np.allclose(radius[moving], R, atol=2e-4)             # the slid states stay on the circle
    assert np.all(radius[~moving] > R + 0.02)                    # the others took the straight step
    v, p = Y[moving][:, [1, 3]], Y[moving][:, [0, 2]]
    assert np.allclose(np.hypot(v[:, 0], v[:, 1]), 1.1)          # ṡ + t̂·δv
    assert np.allclose((v * p).sum(axis=1), 0.0, atol=1e-3)      # velocity along the circle's tangent
