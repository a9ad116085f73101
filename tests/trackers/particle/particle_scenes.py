"""Small rendered scenes with exact ground truth for the particle tracker's tests (imported as
``particle_scenes``: pytest puts this folder on the path).

People are the filled outlines of upright ellipsoids (the conic of each ellipsoid at pixel centres,
drawn far to near), in saturated colours over a smooth random colour texture with seeded sensor
noise (σ = 2). One camera 3 m up looks across a 6 × 6 m floor; the entry region is a 1.2 m strip
on the left edge of the view.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from worldtrack.config import with_overrides
from worldtrack.foreground.background import StaticBackground
from worldtrack.geometry.quadric import ellipse_mask, ellipsoid_conics, person_ellipsoid
from worldtrack.scene import scene_from_dict
from worldtrack.trackers.base import Frame
from worldtrack.trackers.particle import ParticleConfig, ParticleTracker
from worldtrack.trackers.particle.likelihood import ColumnOut, ReadAs, column_counts_reference, column_spec

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _render import texture  # noqa: E402  (tests/trackers/_render.py)

W, H = 320, 240
CAM = {"id": "cam", "image_size": [W, H], "position": [0, -1, 3], "look_at": [0, 3.5, 0.5], "hfov_deg": 70}
CAM2 = {"id": "cam2", "image_size": [W, H], "position": [5, 7, 3], "look_at": [0, 3.5, 0.5], "hfov_deg": 70}
FLOOR = {"walkable": [{"outer": [[-3, 0.5], [3, 0.5], [3, 6.5], [-3, 6.5]]}]}
DOOR = [{"name": "door", "polygon": [[-2.9, 2.0], [-1.7, 2.0], [-1.7, 4.0], [-2.9, 4.0]]}]
COLOURS = [(40, 30, 200), (200, 60, 30), (30, 170, 40), (170, 40, 170)]
HEIGHT, WIDTH = 1.7, 0.45
FPS = 10.0
#: Lens distortion of the distorted test camera (k1, k2, p1, p2, k3).
DISTORTION = [-0.2, 0.05, 0.001, -0.002, 0.0]
#: A column with two ring samples below the floor and two above its 1.9 m top.
RING_HEIGHTS = np.concatenate([[-0.2, -0.1], np.arange(20) * 0.1, [2.0, 2.1]])


def make_scene(entry: bool = True, cameras=(CAM,)):
    d = {"name": "particle-test", "cameras": list(cameras), "floor": FLOOR,
         "people": {"height": HEIGHT, "width": WIDTH}}
    if entry:
        d["entry_regions"] = DOOR
    return scene_from_dict(d)


def render(cam, background, people, rng) -> np.ndarray:
    """``background`` with ellipsoid people ``(x, y[, height])`` drawn far to near, plus noise σ = 2."""
    img = background.astype(np.float32)
    order = sorted(range(len(people)), key=lambda k: -np.hypot(people[k][0] - cam.centre[0], people[k][1] - cam.centre[1]))
    for k in order:
        p = people[k]
        h = p[2] if len(p) > 2 else HEIGHT
        centres, radii = person_ellipsoid([p[:2]], h, WIDTH)
        C = ellipsoid_conics(cam.P, centres, radii)[0]
        img[ellipse_mask(C, (H, W))] = COLOURS[k % len(COLOURS)]
    img += rng.normal(0.0, 2.0, img.shape)
    return np.clip(img, 0, 255).astype(np.uint8)


def run(tracker, scene, backgrounds, paths, n, seed=0):
    """Step ``tracker`` over ``n`` frames; ``paths(t) -> list of (x, y[, h])``. Returns [(t, truth, tracks)]."""
    rng = np.random.default_rng(seed)
    out = []
    for k in range(n):
        t = k / FPS
        people = paths(t)
        frames = {cid: Frame(render(cam, backgrounds[cid], people, rng), t, k) for cid, cam in scene.cameras.items()}
        out.append((t, people, tracker.step(frames, t)))
    return out


def foregrounds(scene, scene_seed=0):
    """Static colour backgrounds (textures) of the scene's cameras, threshold 25 (the particle tracker's
    former γ) with shadows set apart: ({camera: model}, {camera: image})."""
    bgs = {cid: texture(i + 10 * scene_seed) for i, cid in enumerate(scene.cameras)}
    return {cid: StaticBackground(bg, 25.0, "colour", shadows=True) for cid, bg in bgs.items()}, bgs


def config(**settings) -> ParticleConfig:
    """The default configuration with ``settings`` by dotted path, ``__`` for the dots
    (``detection__births="none"``)."""
    return with_overrides(ParticleConfig(), {k.replace("__", "."): v for k, v in settings.items()}, root="particle")


def tracker_for(scene, scene_seed=0, **settings):
    """A tracker with static backgrounds and ``settings`` as in :func:`config`. An ellipsoid's lowest
    point is on its axis (a person's is the near side of the feet), so the column stands on the
    particle: ``column.surface_offset_m=0``."""
    fgs, bgs = foregrounds(scene, scene_seed)
    return ParticleTracker(scene, fgs, config(**{"column__surface_offset_m": 0.0, **settings})), bgs


def clouds(tracker) -> list:
    """The tracker's tracking filters in id order."""
    return [tracker.clouds[k] for k in sorted(tracker.clouds)]


def walker(t):
    """Enters from the door region and walks right at 1 m/s."""
    return [(-2.3 + 1.0 * t, 3.0)]


# ---------------------------------------------------------------------------- column calls

_SPEC = ("on", "off", "k_min", "radius", "below", "n_below", "n_above", "top_sigma", "outside_unknown")


def column_parts(heights, tops=None, **args):
    """(ColumnSpec, ReadAs, tops) from one dict of keyword arguments (the column's and the reading's)."""
    spec = column_spec(heights, **{k: v for k, v in args.items() if k in _SPEC})
    return spec, ReadAs(**{k: v for k, v in args.items() if k not in _SPEC}), tops


def column(cl, hit, xy, heights, **args) -> ColumnOut:
    """``CameraLikelihood.column`` with the column's and the reading's arguments in one dict."""
    spec, read, tops = column_parts(heights, **args)
    return cl.column(hit, xy, spec, read, tops)


def column_reference(cam, hit, xy, heights, **args) -> ColumnOut:
    """:func:`column_counts_reference` with the arguments of :func:`column`."""
    spec, read, tops = column_parts(heights, **args)
    return column_counts_reference(cam, hit, xy, spec, read, tops)


def hit_image(F: np.ndarray, gamma: float) -> np.ndarray:
    """``F > γ`` as (H, W) uint8: the labels a foreground without shadows gives (test input)."""
    return np.ascontiguousarray(np.asarray(F) > gamma).astype(np.uint8)


def thresholded_difference(F: np.ndarray, gamma: float) -> np.ndarray:
    """F with ``F ≤ γ`` set to 0, float32: what the point likelihood reads (test input)."""
    f = np.asarray(F, dtype=np.float32)
    return np.ascontiguousarray(np.where(f > gamma, f, np.float32(0.0)))
