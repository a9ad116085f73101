"""Small seed-002 problems shared by the trajectory tests (imported as ``_trajectory_cases``: pytest
puts this folder on the path; a helper in ``conftest.py`` would clash with other folders' conftests)."""

from dataclasses import dataclass

import numpy as np

from worldtrack.geometry.camera import Camera
from worldtrack.trajectory.environment import Barrier, EnvironmentModel, HeightPrior
from worldtrack.trajectory.model import MotionPrior, TimeGrid
from worldtrack.trajectory.objective import Problem
from worldtrack.trajectory.observation import Observations


def ceiling_cameras(distortion: bool = True) -> dict[str, Camera]:
    """Two cameras 3 m up, 4 m apart along x, looking down with a little tilt; lens distortion."""
    dist = (-0.21, 0.06, 0.0015, -0.001, 0.01) if distortion else None
    return {c: Camera.look_at(c, 320, 240, position=(x, 0.0, 3.0), target=(x, 0.4, 0.0), hfov_deg=70, dist=dist)
            for c, x in (("a", 0.0), ("b", 4.0))}


def walk(T: int = 81, dt: float = 0.1, height: float = 1.7, curve: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Times (T,) and head points (T, 3) of a walk along x at 0.5·(T−1)·dt/4 m/s, bending by ``curve`` m."""
    t = np.arange(T) * dt
    s = t / t[-1]
    x = 4.0 * s
    y = curve * np.sin(np.pi * s)
    z = height + 0.01 * np.sin(2 * np.pi * 1.8 * t)
    return t, np.column_stack([x, y, z])


@dataclass
class Case:
    """A problem with its truth: problem, ground-truth head points (n, 3), observations."""

    problem: Problem
    truth: np.ndarray
    obs: Observations


def observed_walk(T: int = 81, noise_px: float = 2.0, seed: int = 0, barrier_field=None, curve: float = 0.0,
                  robust: float | None = None, feet: bool = False, height: float = 1.7) -> Case:
    """The walk seen by camera a near its start and by camera b near its end, nothing between; with
    ``feet`` also the pixel of the floor point below the head (every third row left out: unseen)."""
    cams = ceiling_cameras()
    t, pts = walk(T, curve=curve, height=height)
    ids = np.where(pts[:, 0] < 2.0, "a", "b")
    centre = np.where(ids == "a", 0.0, 4.0)
    seen = np.abs(pts[:, 0] - centre) < 0.7
    rng = np.random.default_rng(seed)
    obs = Observations.from_points(t[seen], ids[seen], pts[seen], cams)
    feet_uv = None
    if feet:
        floor = pts[seen] * [1.0, 1.0, 0.0]
        feet_uv = np.empty((len(floor), 2))
        for k, cam in enumerate(obs.cameras):
            sel = obs.camera == k
            feet_uv[sel] = cam.project(floor[sel]) + rng.normal(0, noise_px, (int(sel.sum()), 2))
        feet_uv[::3] = np.nan
    obs = Observations(obs.time, obs.camera, obs.uv + rng.normal(0, noise_px, obs.uv.shape), obs.sigma, obs.cameras,
                       feet_uv, None if feet_uv is None else np.full(len(obs.time), 1.5))
    grid = TimeGrid.covering(obs.time, 0.1)
    barrier = Barrier(barrier_field, clearance=0.2, substeps=2) if barrier_field is not None else None
    env = EnvironmentModel(barrier, HeightPrior(1.7, 0.05), 1.0)
    problem = Problem.build(obs, grid, MotionPrior(1.0, 0.02), env, robust)
    k = np.rint((grid.times - t[0]) / 0.1).astype(int)
    return Case(problem, pts[k], obs)
