"""Seed 002's problem as a GTSAM factor graph — the peer our banded solver is checked and timed against.

Exactly the same problem and weights as :class:`worldtrack.trajectory.objective.Problem`:

- keys: the head position p_t (``Point3``) and velocity v_t (``Vector3``) of every step;
- motion (eq. 4): ``WnoaMotionFactorPoint3`` — GTSAM's white-noise-on-acceleration factor, whose
  error is our W·(x_{t+1} − A·x_t) with the same spectral densities (checked in ``check_same_objective``);
- observations (eq. 7): ``TriangulationFactorCal3DS2`` — projection of a point key through a fixed
  camera with OpenCV's k1, k2, p1, p2 (GTSAM's Cal3DS2 has no k3, so the benchmark's cameras have
  k3 = 0) and isotropic σ in pixels; on-grid time stamps only (τ = 0);
- the prior on the first velocity: ``PriorFactorVector`` on v_1, N(0, σ₁²·I) (none when σ₁ is None);
- height (e_v): ``PriorFactorPoint3`` on z alone (precisions 0, 0, λ/σ_v²);
- barrier (e_h), optional: one ``CustomFactor`` per barrier sample on (p_t, v_t, p_{t+1}, v_{t+1}),
  residual and Jacobian from our own barrier code (a Python callback per factor: GTSAM pays for it).

GTSAM's ``graph.error`` is ½·Σ‖whitened residual‖²; our objective is Σ‖·‖², so ours = 2·GTSAM's.
Needs ``pip install 'worldtrack[gtsam]'``; :func:`available` says whether it is there.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass

import numpy as np

from worldtrack.trajectory.environment import barrier_samples_reference
from worldtrack.trajectory.model import POS, VEL
from worldtrack.trajectory.objective import Problem


def available() -> bool:
    try:
        import gtsam  # noqa: F401
    except ImportError:
        return False
    return True


@dataclass
class PeerResult:
    X: np.ndarray          # (n, 6) in our state order
    objective: float       # Σ‖r‖² (our convention: 2 × GTSAM's error)
    build_s: float         # building the graph and initial values
    solve_s: float         # LevenbergMarquardtOptimizer.optimize()
    iterations: int


def _camera(cam):
    import gtsam
    k1, k2, p1, p2, k3 = cam.dist
    if k3 != 0:
        raise ValueError("GTSAM's Cal3DS2 has no k3: use cameras with k3 = 0")
    K = cam.K
    cal = gtsam.Cal3DS2(K[0, 0], K[1, 1], K[0, 1], K[0, 2], K[1, 2], k1, k2, p1, p2)
    pose = gtsam.Pose3(gtsam.Rot3(cam.R.T), cam.centre)          # camera → world
    return gtsam.PinholeCameraCal3DS2(pose, cal)


def build_graph(problem: Problem, X0: np.ndarray, with_barrier: bool = False):
    """(graph, initial values) of ``problem`` from our start X0 (n, 6)."""
    import gtsam
    from gtsam.symbol_shorthand import P, V
    grid, term = problem.grid, problem.observations
    if np.any(np.abs(term.tau) > 1e-9):
        raise ValueError("the GTSAM peer takes on-grid observations only")
    graph = gtsam.NonlinearFactorGraph()
    q = np.array([problem.motion.q_horizontal, problem.motion.q_horizontal, problem.motion.q_vertical])
    times = grid.times
    for t in range(grid.n - 1):
        graph.add(gtsam.WnoaMotionFactorPoint3(gtsam.StateData(P(t), V(t), float(times[t])),
                                               gtsam.StateData(P(t + 1), V(t + 1), float(times[t + 1])), q))
    if problem.motion.first_velocity_sigma is not None:
        noise = gtsam.noiseModel.Isotropic.Sigma(3, float(problem.motion.first_velocity_sigma))
        graph.add(gtsam.PriorFactorVector(V(0), np.zeros(3), noise))
    cams = [_camera(c) for c in term.obs.cameras]
    for i in range(len(term.obs)):
        noise = gtsam.noiseModel.Isotropic.Sigma(2, float(term.obs.sigma[i]))
        graph.add(gtsam.TriangulationFactorCal3DS2(cams[term.obs.camera[i]], term.obs.uv[i], noise, P(int(term.step[i]))))
    env = problem.environment
    if env.height is not None:
        noise = gtsam.noiseModel.Diagonal.Precisions(np.array([0.0, 0.0, env.weight / env.height.sigma ** 2]))
        target = np.array([0.0, 0.0, env.height.height])
        for t in range(grid.n):
            graph.add(gtsam.PriorFactorPoint3(P(t), target, noise))
    if with_barrier and env.barrier is not None:
        _add_barrier(graph, problem)
    values = gtsam.Values()
    for t in range(grid.n):
        values.insert(P(t), X0[t, POS].copy())
        values.insert(V(t), X0[t, VEL].copy())
    return graph, values


def _add_barrier(graph, problem: Problem) -> None:
    """One CustomFactor per barrier sample (t, α), its residual and Jacobian from our reference code."""
    import gtsam
    from gtsam.symbol_shorthand import P, V
    env, dt = problem.environment, problem.grid.dt
    b = env.barrier
    gain = np.sqrt(env.weight / b.substeps) / b.scale
    unit = gtsam.noiseModel.Unit.Create(1)

    def make(t: int, alpha: float):
        def error(this, values, jacobians):
            X = np.zeros((2, 6))
            X[0, POS], X[0, VEL] = values.atPoint3(P(t)), values.atVector(V(t))
            X[1, POS], X[1, VEL] = values.atPoint3(P(t + 1)), values.atVector(V(t + 1))
            r, J, _, _ = barrier_samples_reference(X, np.array([0]), np.array([alpha]), dt, b.field, b.clearance,
                                                   b.softness, gain)
            if jacobians is not None:
                J = J[0]
                jacobians[0] = J[POS][None, :]
                jacobians[1] = J[VEL][None, :]
                jacobians[2] = J[6 + POS][None, :]
                jacobians[3] = J[6 + VEL][None, :]
            return r
        return error

    for t, alpha in zip(*b.samples(problem.grid.n)):
        graph.add(gtsam.CustomFactor(unit, [P(int(t)), V(int(t)), P(int(t) + 1), V(int(t) + 1)],
                                     make(int(t), float(alpha))))


def solve(problem: Problem, X0: np.ndarray, with_barrier: bool = False, relative_tolerance: float = 1e-10,
          max_iterations: int = 100) -> PeerResult:
    """GTSAM's Levenberg–Marquardt on ``problem`` from X0; our state order back."""
    import gtsam
    from gtsam.symbol_shorthand import P, V
    t0 = time.perf_counter()
    graph, values = build_graph(problem, X0, with_barrier)
    t1 = time.perf_counter()
    params = gtsam.LevenbergMarquardtParams()
    params.setRelativeErrorTol(relative_tolerance)
    params.setAbsoluteErrorTol(0.0)
    params.setMaxIterations(max_iterations)
    optimizer = gtsam.LevenbergMarquardtOptimizer(graph, values, params)
    result = _with_large_stack(optimizer.optimize)
    t2 = time.perf_counter()
    X = np.zeros_like(X0)
    for t in range(problem.grid.n):
        X[t, POS] = result.atPoint3(P(t))
        X[t, VEL] = result.atVector(V(t))
    return PeerResult(X, 2.0 * graph.error(result), t1 - t0, t2 - t1, optimizer.iterations())


def _with_large_stack(fn, size: int = 1 << 30):
    """``fn()`` on a thread with a ``size``-byte stack: GTSAM eliminates a chain recursively, and at
    T = 100 000 that overflows the main thread's default 8 MB stack (a segmentation fault)."""
    out: dict = {}

    def target():
        try:
            out["value"] = fn()
        except BaseException as e:  # noqa: BLE001 (re-raised below, on the caller's thread)
            out["error"] = e

    old = threading.stack_size(size)
    try:
        worker = threading.Thread(target=target)
        worker.start()
        worker.join()
    finally:
        threading.stack_size(old)
    if "error" in out:
        raise out["error"]
    return out["value"]


def check_same_objective(problem: Problem, X: np.ndarray, with_barrier: bool = False) -> tuple[float, float]:
    """(ours, GTSAM's × 2) at the same trajectory: the two problems are the same problem."""
    from worldtrack.trajectory.objective import evaluate
    graph, values = build_graph(problem, X, with_barrier)
    ours = evaluate(problem, X)
    total = ours.total if with_barrier else ours.total - ours.barrier
    return total, 2.0 * graph.error(values)
