"""Pictures of seed 002's estimates: the floor plan with the uncertainty band, and the head height.

The plan shows what the estimate rests on and how sure it is: the room (walls, obstacles, what
each camera sees at head height), the observations (back-projected to the head's estimated height,
in their camera's colour), the estimate with a ±2σ band across its direction, the steps where
the barrier pushes, and optionally the estimate without the barrier and the ground truth.
"""

from __future__ import annotations

from pathlib import Path
from typing import Mapping

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import EllipseCollection  # noqa: E402

from worldtrack.scene.model import Scene  # noqa: E402
from worldtrack.viz.floorplan import CAMERA_COLOURS, draw_scene  # noqa: E402


def observation_points(obs, estimate, camera_ids: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """Where the observations put the head on the floor: each pixel back-projected to the estimated
    head height at its time. Returns points (N, 2) metres and each one's index in ``camera_ids``
    (for its colour)."""
    xy = np.full((len(obs), 2), np.nan)
    for k, cam in enumerate(obs.cameras):
        sel = obs.camera == k
        z = np.interp(obs.time[sel], estimate.times, estimate.positions[:, 2])
        xy[sel] = cam.backproject(obs.uv[sel], z)[:, :2]
    return xy, np.array([camera_ids.index(obs.cameras[k].id) for k in obs.camera], dtype=int)


def sigma_ellipses(xy: np.ndarray, cov: np.ndarray, k: float = 2.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Full axes (n,), (n,) in metres and angles (n,) in degrees of the k-σ ellipses of 2 × 2
    covariances ``cov`` (n, 2, 2) — what the band is drawn from."""
    vals, vecs = np.linalg.eigh(cov)
    vals = np.maximum(vals, 0.0)
    angle = np.degrees(np.arctan2(vecs[:, 1, 1], vecs[:, 0, 1]))
    return 2 * k * np.sqrt(vals[:, 1]), 2 * k * np.sqrt(vals[:, 0]), angle


def draw_estimate(ax: plt.Axes, xy: np.ndarray, cov: np.ndarray, colour, label: str,
                  barrier: np.ndarray | None = None) -> None:
    """One estimate on a floor plan: the ±2σ band (the union of every step's 2σ ellipse, in an
    opaque tint so that overlaps do not darken), the path, and where the barrier is active."""
    width, height, angle = sigma_ellipses(xy, cov)
    tint = np.clip(0.7 * np.ones(3) + 0.3 * np.asarray(matplotlib.colors.to_rgb(colour)), 0, 1)
    ax.add_collection(EllipseCollection(width, height, angle, units="xy", offsets=xy, offset_transform=ax.transData,
                                        facecolors=[tint], edgecolors="none", zorder=2))
    ax.plot(xy[:, 0], xy[:, 1], "-", color=colour, lw=1.6, zorder=8, label=label)
    ax.plot(xy[0, 0], xy[0, 1], "o", color=colour, ms=5, zorder=9)
    if barrier is not None and barrier.any():
        ax.plot(xy[barrier, 0], xy[barrier, 1], "x", color="crimson", ms=3, zorder=9)


def save_trajectory_plan(scene: Scene, path: str | Path, estimates: Mapping[int, object],
                         observations: Mapping[int, tuple[np.ndarray, np.ndarray]] | None = None,
                         truth: Mapping[int, np.ndarray] | None = None, without_barrier: bool = True,
                         coverage_height: float | None = None, title: str | None = None,
                         bounds: tuple[float, float, float, float] | None = None) -> Path:
    """Write the floor plan of one or more people's estimates.

    Parameters
    ----------
    estimates : {id: TrajectoryEstimate}
    observations : {id: (points (N, 2) metres, camera index (N,))} — back-projected observations
    truth : {id: (n, 2)} — ground truth, dashed
    without_barrier : draw each estimate without the barrier (the paper's comparison), dotted
    coverage_height : float — shade what each camera sees at this height (default: the floor)
    bounds : (x0, x1, y0, y1) to zoom on, metres
    """
    x0, x1, y0, y1 = scene.walkable.bounds
    w, h = x1 - x0 + 2, y1 - y0 + 2
    scale = 10.0 / max(w, h)
    fig, ax = plt.subplots(figsize=(max(5.0, w * scale), max(4.0, h * scale) + 0.8), dpi=110)
    draw_scene(ax, scene, show_coverage=coverage_height is None)
    if coverage_height is not None:
        _draw_coverage(ax, scene, coverage_height)
    people = plt.get_cmap("tab10").colors
    for k, (pid, est) in enumerate(sorted(estimates.items())):
        colour = people[(k + 3) % len(people)]
        if truth and pid in truth:
            ax.plot(truth[pid][:, 0], truth[pid][:, 1], "--", color="black", lw=0.9, zorder=7,
                    label="ground truth" if k == 0 else None)
        if without_barrier:
            nb = est.without_barrier
            ax.plot(nb[:, 0], nb[:, 2], ":", color=colour, lw=1.0, zorder=6,
                    label="without the barrier" if k == 0 else None)
        cov = est.position_covariance[:, :2, :2]
        draw_estimate(ax, est.positions[:, :2], cov, colour, f"person {pid} (start: {est.start})",
                      est.barrier_active)
        if observations and pid in observations:
            pts, cam = observations[pid]
            ax.scatter(pts[:, 0], pts[:, 1], s=6, c=[CAMERA_COLOURS[c % len(CAMERA_COLOURS)] for c in cam],
                       edgecolors="black", linewidths=0.2, zorder=10)
    if bounds is not None:
        ax.set_xlim(bounds[0], bounds[1])
        ax.set_ylim(bounds[2], bounds[3])
    ax.legend(loc="upper right", fontsize=7, framealpha=0.85)
    ax.set_title(title or f"{scene.name}: estimated head trajectories (band ±2σ, × barrier active, dots: seen)",
                 fontsize=9)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path)
    plt.close(fig)
    return path


def _draw_coverage(ax: plt.Axes, scene: Scene, z: float, margin: float = 0.5) -> None:
    from worldtrack.viz.floorplan import camera_floor_coverage
    x0, x1, y0, y1 = scene.walkable.bounds
    for k, cam in enumerate(scene.cameras.values()):
        xs, ys, seen = camera_floor_coverage(cam, (x0 - margin, x1 + margin, y0 - margin, y1 + margin), z=z)
        if seen.any():
            colour = CAMERA_COLOURS[k % len(CAMERA_COLOURS)]
            ax.contourf(xs, ys, seen.astype(float), levels=[0.5, 1.5], colors=[colour], alpha=0.15, zorder=1)
            ax.contour(xs, ys, seen.astype(float), levels=[0.5], colors=[colour], linewidths=1, zorder=1)


def save_height_plot(path: str | Path, estimates: Mapping[int, object],
                     truth: Mapping[int, tuple[np.ndarray, np.ndarray]] | None = None,
                     height_prior: Mapping[int, float] | None = None) -> Path:
    """Head height over time per person: estimate ± 2σ, observed steps marked, optional truth
    ``{id: (times, z)}`` and the height prior H."""
    people = sorted(estimates)
    fig, axes = plt.subplots(len(people), 1, figsize=(9, 2.4 * len(people) + 0.4), dpi=110, squeeze=False)
    colours = plt.get_cmap("tab10").colors
    for k, (pid, ax) in enumerate(zip(people, axes[:, 0])):
        est = estimates[pid]
        c = colours[(k + 3) % len(colours)]
        z, s = est.positions[:, 2], est.sigma[:, 2]
        ax.fill_between(est.times, z - 2 * s, z + 2 * s, color=c, alpha=0.2, lw=0)
        ax.plot(est.times, z, "-", color=c, lw=1.4, label="estimate ±2σ")
        seen = est.observed > 0
        ax.plot(est.times[seen], z[seen], ".", color="black", ms=2, label="observed steps")
        if truth and pid in truth:
            ax.plot(truth[pid][0], truth[pid][1], "--", color="black", lw=0.8, label="ground truth")
        if height_prior and pid in height_prior:
            ax.axhline(height_prior[pid], color="grey", lw=0.8, ls=":", label="height prior H")
        ax.set_ylabel(f"person {pid}\nhead height (m)")
        ax.grid(True, lw=0.3, alpha=0.5)
        ax.legend(loc="lower right", fontsize=7, ncol=4)
    axes[-1, 0].set_xlabel("time (s)")
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path)
    plt.close(fig)
    return path
