"""Make the calibration examples: the 1999 paper's procedure on the kato-lab cameras (paper 000, §6.2).

The paper builds a 0.3 × 0.3 × 1.1 m box with markers, puts it at known places on the floor, clicks
the markers in the image and fits the camera to 30 pairs. This script does the same with the
cameras of ``examples/scenes/kato_lab.yaml`` resized to 640×480 (``Camera.scaled(4)``):

* markers at the box's 8 corners and at mid-height (Z = 0.55 m) on its 4 vertical edges;
* the box at a few floor positions and turns, all inside the room;
* a marker is kept only if the camera sees it (in the image, 5 px from the border, and not hidden
  by the box itself or the room's desk and shelf), so the back-bottom corners drop out as they
  would for a person clicking markers;
* Gaussian noise of 0.5 px on the image points (seed 0); world points exact, in millimetres.

Writes, next to this script::

    lab_cam1_points.csv   cam1, oblique, no lens distortion
    lab_cam2_points.csv   cam2, straight down, wide angle with barrel distortion (k1 = −0.25,
                          k2 = 0.05): fit it with and without ``--distortion``

Run from the repository root: ``python examples/calibration/make_points.py``. The output is the
same on every run.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from worldtrack.geometry.camera import Camera
from worldtrack.geometry.raycast import ray_box
from worldtrack.scene import load_scene
from worldtrack.scene.model import Box

HERE = Path(__file__).resolve().parent
SCENE = HERE.parent / "scenes" / "kato_lab.yaml"
SEED = 0
NOISE_PX = 0.5
BOX_SIZE = np.array([0.3, 0.3, 1.1])       # metres: the paper's calibration box
MARKER_HEIGHTS = (0.0, 0.55, 1.1)          # metres: bottom corners, mid-height, top corners

# (x, y, yaw_deg) of the box's centre on the floor for each placement.
PLACEMENTS = {
    "cam1": [(-0.9, 1.4, 0.0), (-2.4, 0.9, 20.0), (0.3, 0.8, -15.0), (-2.3, 3.5, 10.0)],
    "cam2": [(-2.6, -1.2, 0.0), (0.4, -1.0, 30.0), (-2.7, 3.6, -20.0), (0.6, 3.6, 0.0), (-1.6, 1.0, 45.0)],
}


def box_markers(x: float, y: float, yaw_deg: float) -> np.ndarray:
    """(12, 3) marker positions, metres: the 4 vertical edges at the three marker heights."""
    hx, hy = BOX_SIZE[:2] / 2
    edges = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]])
    c, s = np.cos(np.radians(yaw_deg)), np.sin(np.radians(yaw_deg))
    xy = edges @ np.array([[c, s], [-s, c]]) + (x, y)
    return np.array([[px, py, z] for z in MARKER_HEIGHTS for px, py in xy])


def visible(cam: Camera, points: np.ndarray, boxes: list[tuple[np.ndarray, np.ndarray, float]]) -> np.ndarray:
    """(N,) bool: in the image (5 px margin) and not hidden by any of the boxes."""
    uv = cam.project(points)
    ok = cam.in_image(uv, margin=5.0) & np.all(np.isfinite(uv), axis=1)
    d = points - cam.centre
    dist = np.linalg.norm(d, axis=1)
    d /= dist[:, None]
    for centre, size, yaw in boxes:
        ok &= ray_box(cam.centre, d, centre, size, yaw) >= dist - 1e-3
    return ok


def make(cam: Camera, placements: list[tuple[float, float, float]], obstacles: list[Box],
         rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """World points (N, 3) in metres and noisy image points (N, 2) in pixels."""
    world = []
    for x, y, yaw in placements:
        markers = box_markers(x, y, yaw)
        boxes = [(np.array([x, y, BOX_SIZE[2] / 2]), BOX_SIZE, np.radians(yaw))]
        boxes += [(o.centre, o.size, o.yaw) for o in obstacles]
        world.append(markers[visible(cam, markers, boxes)])
    W = np.round(np.concatenate(world), 3)
    I = cam.project(W) + rng.normal(0.0, NOISE_PX, size=(len(W), 2))
    return W, I


def write(path: Path, cam: Camera, world: np.ndarray, image: np.ndarray, what: str) -> None:
    c = cam.centre
    lines = [
        f"# Calibration points for kato-lab {cam.id} ({what}), made by make_points.py (seed {SEED}).",
        "# Markers on a 0.3 x 0.3 x 1.1 m box (corners and mid-height) at several floor positions.",
        f"# image_size: {cam.width}x{cam.height}",
        f"# true camera centre: ({c[0]:.3f}, {c[1]:.3f}, {c[2]:.3f}) m",
        f"# true intrinsics: fx = {cam.K[0, 0]:.2f}, fy = {cam.K[1, 1]:.2f}, cx = {cam.K[0, 2]:.2f}, "
        f"cy = {cam.K[1, 2]:.2f} px; distortion k1 = {cam.dist[0]:g}, k2 = {cam.dist[1]:g}",
        f"# image noise: Gaussian, sigma = {NOISE_PX} px per coordinate",
        "X,Y,Z,x,y",
    ]
    lines += [f"{X:.3f},{Y:.3f},{Z:.3f},{u:.2f},{v:.2f}" for (X, Y, Z), (u, v) in zip(world, image)]
    path.write_text("\n".join(lines) + "\n")
    print(f"wrote {path.name}: {len(world)} points, {int(np.sum(world[:, 2] == 0))} on the floor")


def main() -> None:
    scene = load_scene(SCENE)
    rng = np.random.default_rng(SEED)
    what = {"cam1": "oblique, no lens distortion", "cam2": "straight down, wide angle, barrel distortion"}
    for cam_id in ("cam1", "cam2"):
        cam = scene.cameras[cam_id].scaled(4.0)
        W, I = make(cam, PLACEMENTS[cam_id], scene.obstacles, rng)
        write(HERE / f"lab_{cam_id}_points.csv", cam, W, I, what[cam_id])


if __name__ == "__main__":
    main()
