"""Synthetic RGB-D upper bodies for seed 003's 14-DoF tracking (the paper's simulation, §5.2.1).

A person's upper body (:func:`worldtrack.pose.body.body_geometry`: torso with head, two upper
arms, two forearms) with textured clothes — a printed shirt (checks, stripes and blobs, drawn per
person), sleeves or skin, a head with hair and face marks — moves in front of a Kinect-like
camera 2 m away: torso translation (±3 cm) and ``Rz·Ry·Rx`` rotation (±8°, ±6°, ±5°), shoulders
(±35° about their mean pose) and elbows (±30° sideways, flexed forward 15° ± 25°), smooth random
sinusoids; ``mirror=True`` gives the left–right mirror image of the same motion (the arms swap
their motions), to tell a side-specific tracker fault from a hard motion. Frames are drawn like the
faces (:mod:`worldtrack.synth.faces`): z-buffered points at twice the resolution, Lambert shading
with a moving light, area averaging, blur and noise; depth is quantised to 5 mm as in the paper.

>>> seq = body_sequence(1, n_frames=2, size=(160, 120))
>>> f = seq.render(0)
>>> f.image.shape, f.params.shape
((120, 160, 3), (14,))
"""

from __future__ import annotations

from typing import NamedTuple

import cv2
import numpy as np

from worldtrack.pose.body import BodyModel, body_geometry, body_transforms, limb_axes, stacked_points, with_part_albedo
from worldtrack.pose.render import Intrinsics, splat
from worldtrack.synth.environment import value_noise
from worldtrack.synth.faces import GREY_WEIGHTS, _smooth

N_SEQUENCES = 7
_SHIRTS = np.array([[150, 60, 40], [40, 110, 170], [60, 140, 60], [170, 170, 175], [40, 40, 140], [120, 90, 150],
                    [60, 150, 200]], float)


class BodyFrame(NamedTuple):
    """``image`` (H, W, 3) uint8 BGR; ``depth`` (H, W) float32 m, 5 mm steps (0 = none);
    ``params`` (14,) the true pose; ``axes`` dict limb → true unit axis (3,); ``time`` s."""

    image: np.ndarray
    depth: np.ndarray
    params: np.ndarray
    axes: dict
    time: float


def _albedo(part: int, p: np.ndarray, rng: np.random.Generator, seed: int, shirt: np.ndarray,
            sleeves: bool) -> np.ndarray:
    """BGR albedo (M, 3) of one part's points ``p`` (part frame)."""
    x, y, z = p[:, 0], p[:, 1], p[:, 2]
    if part == 0:
        head = y < -0.6
        cloth = shirt * (0.75 + 0.5 * ((np.floor(x / 0.06) + np.floor(y / 0.06)) % 2))[:, None]
        stripe = (np.sin(y * 90 + 3 * value_noise(x, z, 0.05, seed)) > 0.6)[:, None]
        cloth = np.where(stripe, cloth * 0.55, cloth)
        for _ in range(25):                                            # printed blobs
            c = rng.uniform([-0.18, -0.5], [0.18, -0.05])
            r = rng.uniform(0.006, 0.02)
            cloth = np.where((np.hypot(x - c[0], y - c[1]) < r)[:, None], rng.uniform(20, 240, 3), cloth)
        skin = np.array([150.0, 175.0, 215.0]) * (0.9 + 0.2 * value_noise(x, y, 0.02, seed))[:, None]
        hair = (y < -0.72) | (z > 0.03)
        face = np.where(hair[:, None], [40.0, 50.0, 70.0], skin)
        for ex in (-0.035, 0.035):                                     # eyes and mouth on the front
            face = np.where(((np.hypot(x - ex, y + 0.74) < 0.012) & (z < 0))[:, None], 30.0, face)
        face = np.where(((np.abs(y + 0.675) < 0.005) & (np.abs(x) < 0.03) & (z < 0))[:, None], [60, 60, 140], face)
        return np.where(head[:, None], face, cloth)
    skin = np.array([150.0, 175.0, 215.0]) * (0.9 + 0.2 * value_noise(x, z + y, 0.015, seed + part))[:, None]
    sleeve = shirt * (0.7 + 0.5 * (np.sin(x * 70 + part) > 0))[:, None]
    sleeve = sleeve * (0.85 + 0.3 * value_noise(x, y + z, 0.01, seed + 7 * part))[:, None]
    if part in (1, 3) or sleeves:
        return sleeve
    marks = value_noise(x * 2, y + z, 0.008, seed + 3 * part) > 0.8
    return np.where(marks[:, None], skin * 0.7, skin)


def mirror_params(P: np.ndarray) -> np.ndarray:
    """Pose parameters (..., 14) of the left–right mirror image (x → −x in the torso frame): torso
    tx, θ (about z) and φ (about y) change sign, and the arms swap, their Rz angles changing sign."""
    P = np.asarray(P, float)
    Q = P.copy()
    Q[..., [0, 3, 4]] = -P[..., [0, 3, 4]]
    flip = np.array([-1.0, 1.0, -1.0, 1.0])
    Q[..., 6:10], Q[..., 10:14] = P[..., 10:14] * flip, P[..., 6:10] * flip
    return Q


class BodySequence:
    """Sequence ``number`` (1–7 are the benchmark's no1–no7): a person moving in front of the camera."""

    def __init__(self, number: int, n_frames: int = 100, size=(640, 480), fps: float = 30.0, distance: float = 2.0,
                 noise: float = 2.0, depth_step: float = 0.005, mirror: bool = False):
        rng = np.random.default_rng([number, 3014])
        w, h = size
        f = 525.0 * w / 640                                          # Kinect-like field of view
        self.intr = Intrinsics(f, f, (w - 1) / 2, (h - 1) / 2, w, h)
        self.number, self.n_frames, self.fps, self.noise, self.depth_step = number, n_frames, fps, noise, depth_step
        self.shape = body_geometry(0.002)
        self.model_shape = body_geometry(0.003)
        shirt = _SHIRTS[number % len(_SHIRTS)]
        sleeves = bool(rng.random() < 0.5)
        pts, nrm, _, part = stacked_points(self.shape)
        alb = np.concatenate([_albedo(k, m.points, np.random.default_rng([number, k]), number * 10 + k, shirt, sleeves)
                              for k, m in enumerate(self.shape.parts)])
        self._pts, self._nrm, self._alb, self._part = pts, nrm, alb.astype(np.float32), part
        malb = np.concatenate([_albedo(k, m.points, np.random.default_rng([number, k]), number * 10 + k, shirt, sleeves)
                               for k, m in enumerate(self.model_shape.parts)])
        self.true_model = with_part_albedo(self.model_shape, (malb @ GREY_WEIGHTS).astype(np.float32), False)
        tt = np.arange(n_frames) / fps
        s = lambda a, fr=(0.1, 0.35): _smooth(rng, tt, a, fr)
        deg = np.radians
        P = np.zeros((n_frames, 14))
        P[:, 0], P[:, 1], P[:, 2] = s(0.03), 0.2 + s(0.02), distance + s(0.03)
        P[:, 3], P[:, 4], P[:, 5] = s(deg(8)), s(deg(6)), s(deg(5))
        for base, sign in ((6, 1.0), (10, -1.0)):
            P[:, base] = sign * (deg(55) + s(deg(35)))                  # shoulder: arm lowered ±35°
            P[:, base + 1] = -deg(10) + s(deg(25))                      # shoulder: forward / back
            P[:, base + 2] = sign * s(deg(30))                          # elbow in the arm's plane
            # elbow flexion: Ry(φ) with φ > 0 turns the forearm towards −z, the front (the torso's z
            # points into the back), so the forearm bends forward by 15° ± 25° (at most 10° over-straight)
            P[:, base + 3] = deg(15) + s(deg(25))
        self.params = mirror_params(P) if mirror else P
        az = np.radians(-40 + 80 * tt / max(tt[-1], 1e-9))
        self.light_dir = np.column_stack([np.sin(az) * 0.8, -np.full_like(az, 0.5), -np.cos(az) * 0.8])
        self.light_dir /= np.linalg.norm(self.light_dir, axis=1, keepdims=True)
        yy, xx = np.mgrid[0:2 * h, 0:2 * w] / (2 * f) * 3.5
        wall = 0.5 + 0.35 * value_noise(xx, yy, 0.08, number + 21) + 0.15 * value_noise(xx, yy, 0.02, number + 22)
        self._wall = (wall[..., None] * np.array([160.0, 170.0, 175.0])).astype(np.float32)
        self.wall_depth = 3.5

    def render(self, k: int) -> BodyFrame:
        p = self.params[k]
        T = body_transforms(p[None], self.shape)[0]
        Tp = T[self._part]
        xyz = (Tp[:, :, :3] @ self._pts[:, :, None])[:, :, 0] + Tp[:, :, 3]
        nrm = (Tp[:, :, :3] @ self._nrm[:, :, None])[:, :, 0]
        shade = 0.45 + 0.6 * np.maximum(nrm @ self.light_dir[k], 0.0)
        rad = (self._alb * shade[:, None]).astype(np.float32)
        r = splat(xyz, self.intr.scaled(2), footprint=2)
        img = self._wall.copy()
        hit = r.index >= 0
        img[hit] = rad[r.index[hit]]
        img = cv2.GaussianBlur(cv2.resize(img, (self.intr.width, self.intr.height), interpolation=cv2.INTER_AREA),
                               (0, 0), 0.5)
        rng = np.random.default_rng([self.number, k, 38])
        img += rng.standard_normal(img.shape, dtype=np.float32) * np.float32(self.noise) + np.float32(0.5)
        d = np.where(np.isfinite(r.depth), r.depth, self.wall_depth)[::2, ::2]
        depth = (np.round(d / self.depth_step) * self.depth_step).astype(np.float32)
        axes = {n: a[0] for n, a in limb_axes(p[None], self.shape).items()}
        return BodyFrame(np.clip(img, 0, 255).astype(np.uint8), depth, p.copy(), axes, k / self.fps)


def body_sequence(number: int, n_frames: int = 100, size=(640, 480), mirror: bool = False) -> BodySequence:
    """Upper-body sequence ``number`` (no1–no7 are 1–7), or its mirror image."""
    return BodySequence(number, n_frames, size, mirror=mirror)


_ = BodyModel  # re-exported type for callers
