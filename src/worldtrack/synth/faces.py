"""Synthetic faces for seed 003's face tracking: nine identities with shape and texture, head
motion (Sim1 small, Sim2 large) and light that changes during a sequence.

A face is a height field over an ellipse in the *face frame* (x right, y down, z into the head;
the face looks along −z, so ``R = I`` faces a camera that looks along +z): a head-shaped base with
nose, eye sockets and eyeballs, brow ridge, cheekbones, lips and chin, their sizes drawn per
identity. Its albedo (BGR, 0–255 under unit light) has skin tone with low-frequency variation,
freckles and moles, eyes (sclera, iris, pupil, lash line), brows, lips and mouth line, nostrils,
a hairline and, for some, stubble — enough intensity extrema for a sparse template.

Frames are drawn by z-buffering the surface points at twice the resolution (2×2 splats), Lambert
shading (ambient + one directional light, attached shadows), 2×2 area averaging, a slight blur and
sensor noise, over a textured wall 1.4 m away; a hair-covered back of the head fills the rest.
Depth (metres, 1 mm steps) comes with every frame.

>>> face = make_face(3)
>>> seq = face_sequence(face, "sim1", seed=0, n_frames=2, size=(160, 120))
>>> f = next(iter(seq.frames()))
>>> f.image.shape, f.depth.dtype
((120, 160, 3), dtype('float32'))
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterator, NamedTuple

import cv2
import numpy as np

from worldtrack.errors import InputError
from worldtrack.geometry.rotation import euler_zyx
from worldtrack.pose.models import PointModel
from worldtrack.pose.render import Intrinsics, splat
from worldtrack.synth.environment import value_noise

N_IDENTITIES = 9
GREY_WEIGHTS = np.array([0.114, 0.587, 0.299])                  # BGR → grey (OpenCV's)
_SKIN = np.array([[170, 190, 232], [150, 178, 222], [125, 155, 205], [105, 135, 185], [80, 108, 150],
                  [60, 80, 120], [140, 165, 210], [160, 185, 228], [95, 120, 168]], float)
_IRIS = np.array([[30, 55, 85], [140, 105, 60], [60, 100, 70], [25, 35, 50]], float)
_HAIR = np.array([[20, 22, 28], [30, 45, 70], [45, 75, 115], [100, 140, 175], [140, 140, 145]], float)


@dataclass(frozen=True)
class Face:
    """One identity: sizes (m) and the seed of its texture. Build with :func:`make_face`."""

    identity: int
    width: float
    height: float
    nose: float
    eye_x: float
    eye_y: float
    mouth_y: float
    mouth_w: float
    skin: tuple
    iris: tuple
    hair: tuple
    freckles: int
    stubble: bool
    seed: int


def make_face(identity: int) -> Face:
    """Identity ``identity`` (0–8 are the benchmark's nine faces; any integer gives a face)."""
    rng = np.random.default_rng([identity, 3003])
    return Face(int(identity), width=rng.uniform(0.074, 0.086), height=rng.uniform(0.100, 0.112),
                nose=rng.uniform(0.8, 1.25), eye_x=rng.uniform(0.029, 0.035), eye_y=rng.uniform(-0.018, -0.008),
                mouth_y=rng.uniform(0.048, 0.058), mouth_w=rng.uniform(0.018, 0.025),
                skin=tuple(_SKIN[identity % len(_SKIN)] * rng.uniform(0.95, 1.05)),
                iris=tuple(_IRIS[rng.integers(len(_IRIS))]), hair=tuple(_HAIR[rng.integers(len(_HAIR))]),
                freckles=int(rng.integers(20, 140)), stubble=bool(rng.random() < 0.35), seed=int(rng.integers(1 << 30)))


def _g(x, y, x0, y0, sx, sy):
    return np.exp(-0.5 * (((x - x0) / sx) ** 2 + ((y - y0) / sy) ** 2))


def face_depth(face: Face, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Surface depth z (m, into the head) at face-frame (x, y); the nose tip is near z = −0.02."""
    A, B, C = face.width * 1.08, face.height * 1.15, 0.095
    base = C * (1 - np.sqrt(np.clip(1 - (x / A) ** 2 - (y / B) ** 2, 0.0, 1.0)))
    ex, ey, n = face.eye_x, face.eye_y, face.nose
    yb, yt = ey - 0.012, 0.028 * n ** 0.3
    s = np.clip((y - yb) / (yt - yb), 0, 1)
    ridge = (0.006 + 0.016 * n * s) * np.exp(-0.5 * (x / (0.006 + 0.006 * s)) ** 2)
    ridge *= np.where(y > yt, np.exp(-0.5 * ((y - yt) / 0.006) ** 2), 1.0) / (1 + np.exp(-(y - yb) / 0.004))
    z = base - ridge
    for side in (-1, 1):
        z += 0.011 * _g(x, y, side * ex, ey, 0.016, 0.011)              # eye socket
        z -= 0.006 * _g(x, y, side * ex, ey + 0.002, 0.009, 0.006)      # eyeball
        z -= 0.006 * _g(x, y, side * 0.047, 0.014, 0.015, 0.012)        # cheekbone
        z -= 0.004 * _g(x, y, side * 0.014, yt - 0.002, 0.005, 0.004)   # nose wing
    z -= 0.005 * _g(x, y, 0, ey - 0.02, 0.05, 0.007)                     # brow ridge
    z -= 0.005 * _g(x, y, 0, face.mouth_y - 0.006, face.mouth_w, 0.005)  # upper lip
    z -= 0.006 * _g(x, y, 0, face.mouth_y + 0.007, face.mouth_w * 0.9, 0.005)
    z += 0.002 * _g(x, y, 0, face.mouth_y, face.mouth_w, 0.0015)         # mouth crease
    z -= 0.006 * _g(x, y, 0, face.height * 0.82, 0.02, 0.01)             # chin
    return z


def face_albedo(face: Face, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """BGR albedo (..., 3), 0–255, at face-frame (x, y)."""
    rng = np.random.default_rng(face.seed)
    skin = np.asarray(face.skin)
    shade = 1 + 0.10 * (value_noise(x, y, 0.02, face.seed) - 0.5) + 0.06 * (value_noise(x, y, 0.004, face.seed + 1) - 0.5)
    a = skin * shade[..., None]
    a *= 1 - 0.12 * _g(x, y, 0, face.mouth_y, face.mouth_w * 1.4, 0.012)[..., None] * face.stubble
    red = np.array([0.78, 0.72, 1.0])
    for side in (-1, 1):
        a *= 1 - (0.10 * _g(x, y, side * 0.045, 0.025, 0.015, 0.012))[..., None] * (1 - red)    # cheek blush
    for _ in range(face.freckles):                                        # freckles and moles
        cx, cy = rng.uniform(-face.width, face.width), rng.uniform(-0.07, 0.09)
        r, k = rng.uniform(0.0008, 0.0022), rng.uniform(0.15, 0.4)
        a *= 1 - k * _g(x, y, cx, cy, r, r)[..., None]
    if face.stubble:
        chin = (y > face.mouth_y - 0.015) & (np.abs(x) < face.width * 0.85)
        a *= np.where(chin, 0.82 + 0.12 * value_noise(x, y, 0.0015, face.seed + 2), 1.0)[..., None]
    lips = ((x / face.mouth_w) ** 2 + ((y - face.mouth_y) / 0.0095) ** 2) < 1
    a = np.where(lips[..., None], a * np.array([0.72, 0.68, 0.95]), a)
    a *= 1 - 0.7 * _g(x, y, 0, face.mouth_y, face.mouth_w * 0.8, 0.0011)[..., None]          # mouth line
    nose_y = 0.028 * face.nose ** 0.3 + 0.004
    for side in (-1, 1):
        ex, ey = side * face.eye_x, face.eye_y
        sclera = ((x - ex) / 0.0125) ** 2 + ((y - ey) / 0.0055) ** 2 < 1
        a = np.where(sclera[..., None], np.array([215.0, 222.0, 228.0]), a)
        d = np.hypot(x - ex, y - ey)
        a = np.where((sclera & (d < 0.0055))[..., None], np.asarray(face.iris), a)
        a = np.where((sclera & (d < 0.0021))[..., None], 12.0, a)
        lid = np.abs(y - (ey - 0.0055 * np.sqrt(np.clip(1 - ((x - ex) / 0.0135) ** 2, 0, 1)))) < 0.0011
        a = np.where((lid & (np.abs(x - ex) < 0.0135))[..., None], 30.0, a)
        by = ey - 0.014 - 0.004 * np.clip(1 - ((x - ex - side * 0.002) / 0.02) ** 2, 0, 1)
        brow = (np.abs(y - by) < 0.0026) & (np.abs(x - ex - side * 0.002) < 0.021)
        strokes = 0.55 + 0.45 * value_noise(x * 3, y, 0.002, face.seed + 3 + side)
        a = np.where(brow[..., None], np.asarray(face.hair) * strokes[..., None] + 10, a)
        nostril = ((x - side * 0.0075) / 0.0035) ** 2 + ((y - nose_y) / 0.002) ** 2 < 1
        a = np.where(nostril[..., None], a * 0.3, a)
    hairline = y < -face.height * 0.78 + 0.008 * np.sin(x * 60 + face.seed % 7) + 0.25 * x * x / face.width
    hair = np.asarray(face.hair) * (0.7 + 0.6 * value_noise(x * 4, y, 0.003, face.seed + 5))[..., None]
    return np.clip(np.where(hairline[..., None], hair, a), 0, 255)


def face_surface(face: Face, spacing: float = 0.001) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points (M, 3), outward normals (M, 3) and BGR albedo (M, 3) on a grid ``spacing`` m apart."""
    xs = np.arange(-face.width, face.width + 1e-9, spacing)
    ys = np.arange(-face.height * 0.98, face.height * 0.98 + 1e-9, spacing)
    X, Y = np.meshgrid(xs, ys)
    inside = (X / face.width) ** 2 + (Y / (face.height * 0.98)) ** 2 < 1
    x, y = X[inside], Y[inside]
    z = face_depth(face, x, y)
    h = 1e-4
    zx = (face_depth(face, x + h, y) - face_depth(face, x - h, y)) / (2 * h)
    zy = (face_depth(face, x, y + h) - face_depth(face, x, y - h)) / (2 * h)
    n = np.column_stack([zx, zy, -np.ones_like(zx)])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    return np.column_stack([x, y, z]), n, face_albedo(face, x, y)


def face_model(face: Face, spacing: float = 0.001, head_spacing: float | None = 0.0015,
               albedo_samples: int = 3) -> PointModel:
    """The tracker's model of ``face`` (the paper's 3-D face model): face surface points with grey
    albedo and, unless ``head_spacing`` is None, the front half of the skull behind it (points
    ``head_spacing`` m apart) with unknown appearance (NaN albedo: hair gives no stable texture).
    The skull is never part of a template, but it hides the face points it covers when the head
    turns: without it a template at 50° of yaw kept points the hair hides (LM started at the true
    pose of such frames ended 1.8° away on average, 0.8° with it).

    A point's albedo is the mean over its ``spacing``-wide cell (``albedo_samples``² samples, as a
    scanned model's texel averages its patch of skin; 1 = the texture sampled at the point): a
    texture finer than the spacing (stubble, 1.5 mm) would otherwise alias in the model.
    """
    p, n, bgr = face_surface(face, spacing)
    if albedo_samples > 1:
        offsets = ((np.arange(albedo_samples) + 0.5) / albedo_samples - 0.5) * spacing
        bgr = sum(face_albedo(face, p[:, 0] + dx, p[:, 1] + dy) for dx in offsets for dy in offsets)
        bgr = bgr / albedo_samples ** 2
    albedo = (bgr @ GREY_WEIGHTS).astype(np.float32)
    if head_spacing is not None:
        hp, hn, _ = _head_back(face, head_spacing)
        front = hp[:, 2] < _SKULL_CENTRE_Z                         # the back half never hides the face
        p, n = np.concatenate([p, hp[front]]), np.concatenate([n, hn[front]])
        albedo = np.concatenate([albedo, np.full(int(front.sum()), np.nan, np.float32)])
    return PointModel(p, n, albedo, spacing)


_SKULL_CENTRE_Z = 0.09                                           # m behind the face frame's origin


def _head_back(face: Face, spacing: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points of an ellipsoidal skull behind the face, covered in hair (fills the silhouette)."""
    a, b, c = face.width * 1.15, face.height * 1.2, 0.10
    u, v = np.meshgrid(np.arange(0, 2 * np.pi, spacing / a), np.arange(0.02, np.pi, spacing / b))
    p = np.column_stack([(a * np.sin(v) * np.cos(u)).ravel(), (-b * np.cos(v)).ravel(),
                         (_SKULL_CENTRE_Z + c * np.sin(v) * np.sin(u)).ravel()])
    n = (p - [0, 0, _SKULL_CENTRE_Z]) / np.array([a * a, b * b, c * c])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    inside = (p[:, 0] / face.width) ** 2 + (p[:, 1] / (face.height * 0.98)) ** 2 < 1
    keep = (p[:, 2] > 0.02) & (~inside | (p[:, 2] > face_depth(face, p[:, 0], p[:, 1]) + 0.004))
    col = np.asarray(face.hair) * (0.7 + 0.6 * value_noise(p[:, 0] * 3, p[:, 1] + p[:, 2], 0.004, face.seed + 9))[:, None]
    return p[keep], n[keep], col[keep]


class FaceFrame(NamedTuple):
    """One frame: ``image`` (H, W, 3) uint8 BGR; ``depth`` (H, W) float32 m (0 = none);
    ``R`` (3, 3), ``t`` (3,) the true face → camera pose; ``time`` s; ``light`` (ambient, direct)."""

    image: np.ndarray
    depth: np.ndarray
    R: np.ndarray
    t: np.ndarray
    time: float
    light: tuple


MOTIONS = {  # peak yaw, pitch, roll (deg); peak x, y, z (m); frequency range (Hz)
    "sim1": ((8.0, 6.0, 4.0), (0.012, 0.010, 0.02), (0.08, 0.3)),
    "sim2": ((60.0, 35.0, 25.0), (0.06, 0.05, 0.1), (0.3, 0.65)),
}
DEFAULT_SIZE = (640, 480)
DEFAULT_DISTANCE = 0.6


def _smooth(rng: np.random.Generator, t: np.ndarray, peak: float, f_range: tuple) -> np.ndarray:
    out = sum(np.sin(2 * np.pi * rng.uniform(*f_range) * t + rng.uniform(0, 2 * np.pi)) for _ in range(2))
    return peak * out / 2


class FaceSequence:
    """A face moving in front of a fixed camera (see the module docstring). ``frames()`` renders."""

    def __init__(self, face: Face, motion: str, seed: int, n_frames: int = 100, size=DEFAULT_SIZE,
                 fps: float = 30.0, distance: float = DEFAULT_DISTANCE, noise: float = 2.0):
        if motion not in MOTIONS:
            raise InputError(f"motion: expected one of {', '.join(MOTIONS)}, got {motion!r}")
        w, h = size
        f = 0.94 * w                                                 # about 56° horizontal field of view
        self.intr = Intrinsics(f, f, (w - 1) / 2, (h - 1) / 2, w, h)
        self.face, self.fps, self.n_frames, self.noise, self.seed = face, float(fps), int(n_frames), noise, seed
        rng = np.random.default_rng([seed, face.identity, 36])
        tt = np.arange(n_frames) / fps
        ang, pos, fr = MOTIONS[motion]
        yaw, pitch, roll = (np.radians(_smooth(rng, tt, a, fr)) for a in ang)
        self.R = euler_zyx(roll, yaw, pitch)                         # roll about z, yaw about y, pitch about x
        self.t = np.column_stack([_smooth(rng, tt, pos[0], fr), _smooth(rng, tt, pos[1], fr),
                                  distance + _smooth(rng, tt, pos[2], fr)])
        az = np.radians(-50 + 100 * (0.5 - 0.5 * np.cos(np.pi * tt / max(tt[-1], 1e-9))))   # light sweeps across
        el = np.radians(rng.uniform(15, 40))
        self.light_dir = np.column_stack([np.sin(az) * np.cos(el), -np.full_like(az, np.sin(el)), -np.cos(az) * np.cos(el)])
        self.ambient = 0.45 + 0.15 * np.sin(2 * np.pi * tt / max(tt[-1] * 1.3, 1e-9) + rng.uniform(0, 6))
        self.direct = 0.55 + 0.25 * np.sin(2 * np.pi * tt / max(tt[-1] * 0.9, 1e-9) + rng.uniform(0, 6))
        fp, fn, fc = face_surface(face, 0.0006)
        hp, hn, hc = _head_back(face, 0.0012)
        self._pts, self._nrm, self._alb = np.concatenate([fp, hp]), np.concatenate([fn, hn]), np.concatenate([fc, hc])
        yy, xx = np.mgrid[0:2 * h, 0:2 * w] / (2 * f) * 1.4
        wall = 0.55 + 0.35 * value_noise(xx, yy, 0.05, seed + 11) + 0.15 * value_noise(xx, yy, 0.01, seed + 12)
        self._wall = (wall[..., None] * np.array([150.0, 165.0, 175.0])).astype(np.float32)

    def frames(self) -> Iterator[FaceFrame]:
        for k in range(self.n_frames):
            yield self.render(k)

    def render(self, k: int) -> FaceFrame:
        """Frame ``k``: supersampled z-buffer, shading, area averaging, blur, noise."""
        R, t = self.R[k], self.t[k]
        xyz = self._pts @ R.T + t
        shade = self.ambient[k] + self.direct[k] * np.maximum((self._nrm @ R.T) @ self.light_dir[k], 0.0)
        rad = (self._alb * shade[:, None]).astype(np.float32)
        big = self.intr.scaled(2)
        r = splat(xyz, big, footprint=2)
        img = self._wall * np.float32(self.ambient[k] + 0.6 * self.direct[k])
        hit = r.index >= 0
        img[hit] = rad[r.index[hit]]
        img = cv2.resize(img, (self.intr.width, self.intr.height), interpolation=cv2.INTER_AREA)
        img = cv2.GaussianBlur(img, (0, 0), 0.5)
        rng = np.random.default_rng([self.seed, self.face.identity, k, 37])
        img += rng.standard_normal(img.shape, dtype=np.float32) * np.float32(self.noise) + np.float32(0.5)
        img = np.clip(img, 0, 255).astype(np.uint8)
        d = np.where(np.isfinite(r.depth), r.depth, 1.4)[::2, ::2]
        depth = (np.round(d * 1000) / 1000).astype(np.float32)
        return FaceFrame(img, depth, R.copy(), t.copy(), k / self.fps, (float(self.ambient[k]), float(self.direct[k])))


def face_sequence(face: Face, motion: str = "sim1", seed: int = 0, n_frames: int = 100, size=DEFAULT_SIZE,
                  fps: float = 30.0) -> FaceSequence:
    """A :class:`FaceSequence` of ``face`` with motion ``"sim1"`` (small) or ``"sim2"`` (large)."""
    return FaceSequence(face, motion, seed, n_frames, size, fps)
