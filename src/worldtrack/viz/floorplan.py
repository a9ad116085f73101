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


def _margin(scene: Scene, margin: float | None) -> float:
    """The space around the floor (m): ``margin``, or 4 % of the floor's larger side (≥ 0.5 m)."""
    if margin is not None:
        return margin
    x0, x1, y0, y1 = scene.walkable.bounds
    return max(0.5, 0.04 * max(x1 - x0, y1 - y0))


def draw_scene(ax: plt.Axes, scene: Scene, show_coverage: bool = True, margin: float | None = None) -> None:
    """Draw the floor, obstacles, entry regions and cameras of ``scene`` on ``ax`` (metres).

    Every kind of thing drawn gets one legend entry (the floor, obstacles, entry regions, the
    floor each camera sees); camera names sit beside their marker on a light box, inside the axes.
    """
    x0, x1, y0, y1 = scene.walkable.bounds
    margin = _margin(scene, margin)
    for k, poly in enumerate(scene.walkable.polygons):
        ax.add_patch(MplPolygon(poly.outer, closed=True, facecolor="#f4f1ea", edgecolor="#333333", lw=2, zorder=0,
                                label="walkable floor" if k == 0 else None))
        for hole in poly.holes:
            ax.add_patch(MplPolygon(hole, closed=True, facecolor="white", edgecolor="#333333", lw=1.5, zorder=1))
    for k, reg in enumerate(scene.entry_regions):
        ax.add_patch(MplPolygon(reg.polygon, closed=True, facecolor="#9fd89f", edgecolor="green",
                                alpha=0.6, hatch="//", zorder=2, label="entry region" if k == 0 else None))
        c = reg.polygon.mean(axis=0)
        ax.text(c[0], c[1], reg.name, ha="center", va="center", fontsize=8, color="darkgreen", zorder=6)
    for k, ob in enumerate(scene.obstacles):
        fp = ob.footprint
        is_box = isinstance(ob, Box)
        ax.add_patch(MplPolygon(fp, closed=True, facecolor="#8b5a2b" if is_box else "#555555",
                                edgecolor="black", alpha=0.75, lw=1 if is_box else 3, zorder=3,
                                label="obstacle (name, top)" if k == 0 else None))
        c = fp.mean(axis=0)
        ax.text(c[0], c[1], f"{ob.name}\n{ob.top:.2f} m", ha="center", va="center", fontsize=7,
                color="white" if is_box else "black", zorder=6)
    bounds = (x0 - margin, x1 + margin, y0 - margin, y1 + margin)
    extent = max(x1 - x0, y1 - y0)
    for k, cam in enumerate(scene.cameras.values()):
        colour = CAMERA_COLOURS[k % len(CAMERA_COLOURS)]
        if show_coverage:
            xs, ys, seen = camera_floor_coverage(cam, bounds)
            if seen.any():
                ax.contourf(xs, ys, seen.astype(float), levels=[0.5, 1.5], colors=[colour], alpha=0.15, zorder=1)
                ax.contour(xs, ys, seen.astype(float), levels=[0.5], colors=[colour], linewidths=1, zorder=1)
            ax.fill([], [], color=colour, alpha=0.3, label=f"floor {cam.id} sees")   # legend entry only
        c = cam.centre
        d = cam.floor_direction
        ax.plot(c[0], c[1], marker="^", ms=10, color=colour, mec="black", zorder=7)
        ax.annotate("", xy=(c[0] + 0.06 * extent * d[0], c[1] + 0.06 * extent * d[1]), xytext=(c[0], c[1]),
                    arrowprops=dict(arrowstyle="->", color=colour, lw=2), zorder=7)
        ax.annotate(f"{cam.id} ({c[2]:.2f} m up)", (c[0], c[1]), xytext=(0, -12), textcoords="offset points",
                    ha="center", va="top", fontsize=8, zorder=9,
                    bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.75))
    all_x = [x0, x1] + [c.centre[0] for c in scene.cameras.values()]
    all_y = [y0, y1] + [c.centre[1] for c in scene.cameras.values()]
    # Room below the lowest camera for its name, inside the axes (never over the tick labels).
    ax.set_xlim(min(all_x) - margin, max(all_x) + margin)
    ax.set_ylim(min(all_y) - 2.5 * margin, max(all_y) + margin)
    ax.set_aspect("equal")
    ax.set_xlabel("X (m)")
    ax.set_ylabel("Y (m)")
    ax.grid(True, lw=0.3, alpha=0.5)


def draw_trajectories(ax: plt.Axes, paths: Mapping[int, np.ndarray], style: str = "-",
                      label_prefix: str = "", lw: float = 1.5, legend: str | None = None,
                      side: str = "right") -> None:
    """Draw one polyline per id: ``paths[id]`` is (T, 2) floor positions in metres.

    Each track is named once, at its start (a hollow circle; a dot marks its end); a name that
    would sit on an earlier one moves up until it is clear, so 35 ids stay readable.
    ``legend`` is the legend entry for the whole set (e.g. "tracks"). ``side`` ("right" or "left")
    is where the names sit beside the starts: ground truth on one side and tracks on the other keep
    a track's name clear of the true path it starts on.
    """
    cmap = plt.get_cmap("tab20")
    placed: list[tuple[float, float]] = []
    x_lo, x_hi = ax.get_xlim()
    step = 0.025 * (x_hi - x_lo)
    for n, (tid, xy) in enumerate(sorted(paths.items())):
        xy = np.asarray(xy, dtype=float)
        if len(xy) == 0:
            continue
        colour = cmap((int(tid) - 1) % 20)
        ax.plot(xy[:, 0], xy[:, 1], style, color=colour, lw=lw, zorder=8, label=legend if n == 0 else None)
        ax.plot(xy[0, 0], xy[0, 1], "o", mfc="none", mec=colour, ms=5, zorder=8)
        ax.plot(xy[-1, 0], xy[-1, 1], "o", color=colour, ms=3, zorder=8)
        x, y = xy[0]
        while any(abs(x - px) < 2 * step and abs(y - py) < step for px, py in placed):
            y += step
        placed.append((x, y))
        ax.annotate(f"{label_prefix}{tid}", (x, y), xytext=(4 if side == "right" else -4, 1),
                    textcoords="offset points", fontsize=7, color=_darker(colour), zorder=9, va="bottom",
                    ha="left" if side == "right" else "right",
                    bbox=dict(boxstyle="round,pad=0.1", fc="white", ec="none", alpha=0.6))


def _darker(colour: tuple, scale: float = 0.6) -> tuple:
    """An RGBA colour with its RGB scaled down: names in tab20's pale shades stay readable on white."""
    r, g, b, *a = colour
    return (r * scale, g * scale, b * scale, *a)


def save_floorplan(scene: Scene, path: str | Path, title: str | None = None,
                   paths: Mapping[int, np.ndarray] | None = None,
                   reference_paths: Mapping[int, np.ndarray] | None = None,
                   area: np.ndarray | None = None) -> Path:
    """Write a floor-plan PNG of ``scene``, optionally with trajectories, with a legend beside it.

    Parameters
    ----------
    paths : {id: (T, 2)} — e.g. tracker output, drawn solid
    reference_paths : {id: (T, 2)} — e.g. ground truth, drawn dashed and thin
    area : (M, 2) metres — the tracking area (e.g. the one evaluation uses), outlined
    """
    x0, x1, y0, y1 = scene.walkable.bounds
    w, h = x1 - x0 + 2, y1 - y0 + 2
    scale = 9.0 / max(w, h)
    fig, ax = plt.subplots(figsize=(max(4.0, w * scale) + 2.2, max(4.0, h * scale) + 0.6), dpi=110)
    draw_scene(ax, scene)
    if area is not None:
        ring = np.vstack([area, area[:1]])
        ax.plot(ring[:, 0], ring[:, 1], color="#1f4e9c", lw=1.5, ls="-.", zorder=4, label="tracking area")
    if reference_paths:
        draw_trajectories(ax, reference_paths, style="--", label_prefix="gt", lw=1.0, legend="ground truth (gtN)",
                          side="left")
    if paths:
        draw_trajectories(ax, paths, legend="tracks (id at ○ start, ● end)")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    ax.set_title(title or f"{scene.name}: floor plan")
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, bbox_inches="tight")
    plt.close(fig)
    return path
