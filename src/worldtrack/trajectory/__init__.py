"""Seed 002: head trajectories across cameras that do not share views, by MAP estimation.

A person seen now by one camera, now by another, and between them by none: the trajectory that
best explains every head pixel (:mod:`.observation`), moves like a walker (:mod:`.model`), keeps
clear of walls and desks and carries the head at the person's height (:mod:`.environment`),
found by Levenberg–Marquardt on block-tridiagonal normal equations (:mod:`.objective`,
:mod:`.solver`) from several initial trajectories (:mod:`.starts`), with per-step covariances
(:mod:`.uncertainty`). :mod:`.smoother` is the Kalman + RTS baseline.

>>> from worldtrack.trajectory import Observations, TrajectoryOptions, estimate_trajectory
>>> # obs = Observations.from_rows(times_s, camera_ids, head_pixels, scene.cameras)
>>> # est = estimate_trajectory(obs, scene.distance_field(), TrajectoryOptions(height=1.75))
>>> # est.positions (n, 3) m, est.sigma (n, 3) m, est.start, est.costs, est.barrier_active
"""

from worldtrack.trajectory.environment import Barrier, EnvironmentModel, HeightPrior
from worldtrack.trajectory.estimate import TrajectoryEstimate, TrajectoryOptions, estimate_trajectory
from worldtrack.trajectory.model import MotionPrior, TimeGrid
from worldtrack.trajectory.observation import Observations
from worldtrack.trajectory.smoother import kalman_rts
from worldtrack.trajectory.solver import SolverOptions

__all__ = ["Barrier", "EnvironmentModel", "HeightPrior", "MotionPrior", "Observations", "SolverOptions", "TimeGrid",
           "TrajectoryEstimate", "TrajectoryOptions", "estimate_trajectory", "kalman_rts"]
