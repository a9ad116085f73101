"""Floor plans: walls, obstacles, entry regions, cameras and what they see, and trajectories.

Matplotlib only (Agg backend); the functions draw on an ``Axes`` so callers can compose figures.
"""

from __future__ import annotations

from pathlib import Path
from typing import Mapping

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Polygon as MplPolygon  # noqa: E402

from worldtrack.geometry.camera import Camera  # noqa: E402
from worldtrack.scene.model import Box, Scene  # noqa: E402

CAMERA_COLOURS = plt.get_cmap("tab10").colors


def camera_floor_coverage(camera: Camera, bounds: tuple[float, float, float, float],
                          resolution: float = 0.05, z: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Which floor cells a camera sees at height ``z`` (image border and lens included).

    Returns
    -------
    xs : (nx,) ndarray, ys : (ny,) ndarray, seen : (ny, nx) bool ndarray
    """
    from worldtrack.scene.floor import grid_resolution

    resolution = grid_resolution(bounds, resolution, max_cells=1_000_000)
    x0, x1, y0, y1 = bounds
    xs = np.arange(x0, x1 + resolution / 2, resolution)
    ys = np.arange(y0, y1 + resolution / 2, resolution)
    gx, gy = np.meshgrid(xs, ys)
    pts = np.column_stack([gx.ravel(), gy.ravel(), np.full(gx.size, z)])
    seen = camera.in_image(camera.project(pts)).reshape(gx.shape)
    return xs, ys, seen


def draw_scene(ax: plt.Axes, scene: Scene, show_coverage: bool = True, margin: float = 0.5) -> None:
    """Draw the floor, obstacles, entry regions and cameras of ``scene`` on ``ax`` (metres)."""
    x0, x1, y0, y1 = scene.walkable.bounds
    for poly in scene.walkable.polygons:
        ax.add_patch(MplPolygon(poly.outer, closed=True, facecolor="#f4f1ea", edgecolor="#333333", lw=2, zorder=0))
        for hole in poly.holes:
            ax.add_patch(MplPolygon(hole, closed=True, facecolor="white", edgecolor="#333333", lw=1.5, zorder=1))
    for reg in scene.entry_regions:
        ax.add_patch(MplPolygon(reg.polygon, closed=True, facecolor="#9fd89f", edgecolor="green",
                                alpha=0.6, hatch="//", zorder=2))
        c = reg.polygon.mean(axis=0)
        ax.text(c[0], c[1], reg.name, ha="center", va="center", fontsize=8, color="darkgreen", zorder=6)
    for ob in scene.obstacles:
        fp = ob.footprint
        is_box = isinstance(ob, Box)
        ax.add_patch(MplPolygon(fp, closed=True, facecolor="#8b5a2b" if is_box else "#555555",
                                edgecolor="black", alpha=0.75, lw=1 if is_box else 3, zorder=3))
        c = fp.mean(axis=0)
        ax.text(c[0], c[1], f"{ob.name}\n{ob.top:.2f} m", ha="center", va="center", fontsize=7,
                color="white" if is_box else "black", zorder=6)
    bounds = (x0 - margin, x1 + margin, y0 - margin, y1 + margin)
    for k, cam in enumerate(scene.cameras.values()):
        colour = CAMERA_COLOURS[k % len(CAMERA_COLOURS)]
        if show_coverage:
            xs, ys, seen = camera_floor_coverage(cam, bounds)
            if seen.any():
                ax.contourf(xs, ys, seen.astype(float), levels=[0.5, 1.5], colors=[colour], alpha=0.15, zorder=1)
                ax.contour(xs, ys, seen.astype(float), levels=[0.5], colors=[colour], linewidths=1, zorder=1)
        c = cam.centre
        d = cam.floor_direction
        ax.plot(c[0], c[1], marker="^", ms=10, color=colour, mec="black", zorder=7)
        ax.annotate("", xy=(c[0] + 0.6 * d[0], c[1] + 0.6 * d[1]), xytext=(c[0], c[1]),
                    arrowprops=dict(arrowstyle="->", color=colour, lw=2), zorder=7)
        ax.text(c[0], c[1] - 0.25, f"{cam.id} ({c[2]:.2f} m)", ha="center", va="top", fontsize=8, zorder=7)
    all_x = [x0, x1] + [c.centre[0] for c in scene.cameras.values()]
    all_y = [y0, y1] + [c.centre[1] for c in scene.cameras.values()]
    ax.set_xlim(min(all_x) - margin, max(all_x) + margin)
    ax.set_ylim(min(all_y) - margin, max(all_y) + margin)
    ax.set_aspect("equal")
    ax.set_xlabel("X (m)")
    ax.set_ylabel("Y (m)")
    ax.grid(True, lw=0.3, alpha=0.5)


def draw_trajectories(ax: plt.Axes, paths: Mapping[int, np.ndarray], style: str = "-",
                      label_prefix: str = "", lw: float = 1.5) -> None:
    """Draw one polyline per id: ``paths[id]`` is (T, 2) floor positions in metres."""
    cmap = plt.get_cmap("tab20")
    for tid, xy in sorted(paths.items()):
        xy = np.asarray(xy, dtype=float)
        if len(xy) == 0:
            continue
        colour = cmap((int(tid) - 1) % 20)
        ax.plot(xy[:, 0], xy[:, 1], style, color=colour, lw=lw, zorder=8)
        ax.plot(xy[-1, 0], xy[-1, 1], "o", color=colour, ms=4, zorder=8)
        ax.text(xy[0, 0], xy[0, 1], f"{label_prefix}{tid}", fontsize=7, color=colour, zorder=9)


def save_floorplan(scene: Scene, path: str | Path, title: str | None = None,
                   paths: Mapping[int, np.ndarray] | None = None,
                   reference_paths: Mapping[int, np.ndarray] | None = None,
                   area: np.ndarray | None = None) -> Path:
    """Write a floor-plan PNG of ``scene``, optionally with trajectories.

    Parameters
    ----------
    paths : {id: (T, 2)} — e.g. tracker output, drawn solid
    reference_paths : {id: (T, 2)} — e.g. ground truth, drawn dashed and thin
    area : (M, 2) metres — the tracking area (e.g. the one evaluation uses), outlined
    """
    x0, x1, y0, y1 = scene.walkable.bounds
    w, h = x1 - x0 + 2, y1 - y0 + 2
    scale = 9.0 / max(w, h)
    fig, ax = plt.subplots(figsize=(max(4.0, w * scale), max(4.0, h * scale) + 0.6), dpi=110)
    draw_scene(ax, scene)
    if area is not None:
        ring = np.vstack([area, area[:1]])
        ax.plot(ring[:, 0], ring[:, 1], color="#1f4e9c", lw=1.5, ls="-.", zorder=4, label="tracking area")
    if reference_paths:
        draw_trajectories(ax, reference_paths, style="--", label_prefix="gt", lw=1.0)
    if paths:
        draw_trajectories(ax, paths)
    ax.set_title(title or f"{scene.name}: floor plan")
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path)
    plt.close(fig)
    return path
