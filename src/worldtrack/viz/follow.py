"""Pictures of following one target (seed 001): annotated camera frames and the plan-view plot.

* :func:`draw_follow_step` — the colour image with every candidate's silhouette tinted (the target
  red, the others in their track colour, unassigned grey), each candidate's D (eq. 3) over its
  head, a box round the chosen one, the target's prediction as a cross, and a header line with
  time, α, |W| and whether the target was found.
* :func:`plot_follow` — the floor plan: the scene, the target's filtered path (solid where found,
  dotted where coasting), the other people, the robot's path and, when given, the true target.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from worldtrack.geometry.camera import Camera
from worldtrack.viz.overlay import id_colour

TARGET_BGR = (40, 40, 230)
NOBODY_BGR = (160, 160, 160)


def _owner_colour(owner: int) -> tuple[int, int, int]:
    if owner == 1:
        return TARGET_BGR
    return id_colour(owner) if owner > 1 else NOBODY_BGR


def draw_follow_step(image: np.ndarray, step, camera: Camera, label: str = "") -> np.ndarray:
    """A copy of ``image`` (H, W, 3) BGR annotated with one :class:`~worldtrack.follow.tracker.FollowStep`."""
    out = image.copy()
    sil = step.silhouettes
    n = len(step.candidates)
    scale = max(out.shape[1] / 320.0, 0.5)
    if n:
        colours = np.array([NOBODY_BGR] + [_owner_colour(int(o)) for o in step.owner], np.float32)
        tint = colours[sil]
        inside = sil > 0
        out[inside] = (0.55 * out[inside] + 0.45 * tint[inside]).astype(np.uint8)
        for i in range(n):
            ys, xs = np.nonzero(sil == i + 1)
            if len(ys) == 0:
                continue
            x0, y0, x1, y1 = xs.min(), ys.min(), xs.max(), ys.max()
            colour = _owner_colour(int(step.owner[i]))
            if i == step.chosen:
                cv2.rectangle(out, (int(x0), int(y0)), (int(x1), int(y1)), TARGET_BGR, max(1, int(2 * scale)))
            text = f"D{step.D[i]:.2f}" if np.isfinite(step.D[i]) and step.D[i] < 10 else "D>10"
            cv2.putText(out, text, (int(x0), max(int(y0) - 3, 9)), cv2.FONT_HERSHEY_SIMPLEX, 0.33 * scale,
                        colour, 1, cv2.LINE_AA)
    uv, depth = camera.project(np.array([[step.xy[0], step.xy[1], 0.0]]), return_depth=True)
    if depth[0] > 0.1 and np.all(np.isfinite(uv)):
        u, v = (int(round(c)) for c in uv[0])
        cv2.drawMarker(out, (u, v), TARGET_BGR if step.found else (0, 200, 255), cv2.MARKER_CROSS,
                       int(10 * scale), max(1, int(scale)))
    head = f"{label} t={step.t:.2f}s a={step.alpha:.2f} |W|={step.w_steps:.0f} " + ("FOUND" if step.found else "lost")
    cv2.putText(out, head, (3, int(11 * scale)), cv2.FONT_HERSHEY_SIMPLEX, 0.33 * scale, (255, 255, 255), 1,
                cv2.LINE_AA)
    return out


def plot_follow(path: str | Path, scene, target_xy: np.ndarray, found: np.ndarray, robot_xy: np.ndarray,
                others: dict | None = None, truth_xy: np.ndarray | None = None, title: str = "") -> Path:
    """Write the plan-view plot (PNG).

    Parameters
    ----------
    target_xy : (T, 2) filtered target positions, metres; found : (T,) bool
    robot_xy : (T, 2) the camera's floor position per frame
    others : {id: (K, 2) positions} of the other people tracked, optional
    truth_xy : (T, 2) the true target's positions (NaN where absent), optional
    """
    from worldtrack.viz.floorplan import draw_scene, plt

    fig, ax = plt.subplots(figsize=(8, 6.5))
    if scene is not None:
        draw_scene(ax, scene, show_coverage=False)
    for pid, xy in (others or {}).items():
        ax.plot(xy[:, 0], xy[:, 1], ".", ms=1.5, color=np.array(id_colour(pid)[::-1]) / 255, alpha=0.6)
    if truth_xy is not None:
        ax.plot(truth_xy[:, 0], truth_xy[:, 1], "-", color="0.55", lw=3, alpha=0.5, label="true target")
    ax.plot(robot_xy[:, 0], robot_xy[:, 1], "-", color="tab:blue", lw=1.2, label="robot (camera)")
    t = np.asarray(target_xy, float)
    f = np.asarray(found, bool)
    ax.plot(np.where(f, t[:, 0], np.nan), np.where(f, t[:, 1], np.nan), "-", color="tab:red", lw=1.5,
            label="target (found)")
    ax.plot(np.where(~f, t[:, 0], np.nan), np.where(~f, t[:, 1], np.nan), ":", color="tab:orange", lw=1.5,
            label="target (coasting)")
    if len(t):
        ax.plot(*t[0], "o", color="tab:red", ms=6)
    ax.set_aspect("equal")
    ax.set_xlabel("X (m)")
    ax.set_ylabel("Y (m)")
    ax.set_title(title or "worldtrack follow: plan view")
    ax.legend(loc="upper right", fontsize=7)
    out = Path(path)
    fig.savefig(out, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return out
