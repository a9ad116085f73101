"""Small scenes and drawn frames shared by the ellipsoid tracker's tests (imported as
``_ellipsoid_scenes``: pytest puts this folder on the path)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from worldtrack.geometry import quadric as q
from worldtrack.scene import load_scene, scene_from_dict
from worldtrack.trackers.base import Frame

#: The paper's lab: an oblique camera, an overhead one with barrel distortion, a desk.
LAB = Path(__file__).parents[3] / "examples" / "scenes" / "kato_lab.yaml"


def lab_scene():
    return load_scene(LAB)


def person_mask(cam, xy, height, width) -> np.ndarray:
    """(H, W) uint8: the silhouette of a person's ellipsoid at ``xy`` drawn from its conic."""
    cen, rad = q.person_ellipsoid([xy], height, width)
    C = q.ellipsoid_conics(cam.P, cen, rad)[0]
    grid = cam.ideal_pixel_grid if cam.has_distortion else None
    return q.ellipse_mask(C, (cam.height, cam.width), ideal_grid=grid).astype(np.uint8)


def one_camera_scene(size=(160, 120)):
    """The lab's oblique camera over a 6 x 6.5 m floor."""
    w, h = size
    return scene_from_dict({
        "cameras": [{"id": "cam", "image_size": [w, h], "position": [-1.0, -1.74, 2.64],
                     "look_at": [-1.0, 0.9, 0.68], "hfov_deg": 60}],
        "floor": {"walkable": [{"outer": [[-4, -1.5], [2, -1.5], [2, 5], [-4, 5]]}]},
    })


def two_camera_scene(size=(160, 120)):
    """The lab's two cameras (the paper's positions), looking at the same floor."""
    w, h = size
    return scene_from_dict({
        "cameras": [{"id": "c1", "image_size": [w, h], "position": [-1.0, -1.74, 2.64],
                     "look_at": [-1.0, 1.2, 0.8], "hfov_deg": 60},
                    {"id": "c2", "image_size": [w, h], "position": [2.5, 1.32, 3.09],
                     "look_at": [-1.0, 1.2, 0.8], "hfov_deg": 60}],
        "floor": {"walkable": [{"outer": [[-4, -1.5], [2, -1.5], [2, 5], [-4, 5]]}]},
    })


def noise_backgrounds(scene, rng) -> dict:
    """A uniform-noise background image per camera."""
    return {cid: rng.integers(70, 150, (c.height, c.width, 3), dtype=np.uint8) for cid, c in scene.cameras.items()}


def drawn_frame(scene, bg, people, rng, camera="cam") -> np.ndarray:
    """``bg`` with 1.65 x 0.4 m ellipsoid people at ``people`` [(x, y), …] in a flat colour, plus
    sensor noise (σ 3)."""
    cam = scene.cameras[camera]
    img = bg.copy()
    for x, y in people:
        cen, rad = q.person_ellipsoid([[x, y]], 1.65, 0.4)
        img[q.ellipse_mask(q.ellipsoid_conics(cam.P, cen, rad)[0], (cam.height, cam.width))] = (30, 200, 60)
    return np.clip(img + rng.normal(0, 3, img.shape), 0, 255).astype(np.uint8)


def ellipsoid_frames(scene, bgs: dict, cen: np.ndarray, rad: np.ndarray, rng, i: int,
                     shown_in: tuple[str, ...] | None = None, fps: float = 10.0) -> dict:
    """Frame ``i`` (at ``fps``) of every camera: its background with the ellipsoid ``cen, rad``
    drawn green (only in the cameras ``shown_in``, if given), plus pixel noise (σ 3)."""
    frames = {}
    for cid, cam in scene.cameras.items():
        img = bgs[cid].copy()
        if shown_in is None or cid in shown_in:
            img[q.ellipse_mask(q.ellipsoid_conics(cam.P, cen, rad)[0], (cam.height, cam.width))] = (30, 200, 60)
        frames[cid] = Frame(np.clip(img + rng.normal(0, 3, img.shape), 0, 255).astype(np.uint8), i / fps, i)
    return frames
