"""Light and the camera's response to it: lighting over time, white balance, exposure, noise.

Image formation for one camera and frame (all in display units, 0–255 under unit light)::

    radiance = level · (ambient · albedo + direct · albedo · max(0, n·L) · (1 − strength·shadow))
               + emissive                                          (per pixel, BGR)
    raw      = exposure · tint ⊙ radiance · vignetting             (tint: the light's colour)
    image    = blur(raw ⊙ (b_gain/512, 1, r_gain/512)) + noise  →  uint8

The white-balance gains are integers in 0…1023 with 512 = ×1, as the Bumblebee2 of seed 001 reports
them. :class:`WhiteBalance` is the camera's automatic white balance: it compares the grey-world
gains of the current raw frame with the ones it holds and, when they differ by more than a
threshold, jumps to them at once (cameras adjust in steps, not smoothly). Scheduled set-points
override it at given frames, so tests and scenarios can place jumps exactly.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import math

import cv2
import numpy as np
from numba import njit
from scipy.special import ndtri

WB_UNITY = 512
WB_MAX = 1023


@dataclass(frozen=True)
class Light:
    """The lighting of one frame.

    Parameters
    ----------
    ambient, direct : float — ambient and directional intensity (relative, ~0.5 each indoors)
    direction : (3,) unit vector from the scene towards the light (Z > 0)
    tint : (3,) BGR colour of the light (1, 1, 1 = white)
    level : float — global multiplier (illumination drift, lights switched)
    exposure : float — camera exposure multiplier (auto-exposure, e.g. < 1 in backlight)
    """

    ambient: float = 0.55
    direct: float = 0.55
    direction: tuple = (0.3, -0.4, 0.866)
    tint: tuple = (1.0, 1.0, 1.0)
    level: float = 1.0
    exposure: float = 1.0

    @property
    def L(self) -> np.ndarray:
        d = np.asarray(self.direction, dtype=float)
        return d / np.linalg.norm(d)


def light_direction(azimuth_deg: float, elevation_deg: float) -> tuple[float, float, float]:
    """Unit vector towards a light at ``azimuth_deg`` (from +X towards +Y) and ``elevation_deg``."""
    az, el = np.radians(azimuth_deg), np.radians(elevation_deg)
    return (float(np.cos(el) * np.cos(az)), float(np.cos(el) * np.sin(az)), float(np.sin(el)))


@dataclass(frozen=True)
class LightSegment:
    """From ``start`` (seconds) on, the lighting changes to these values (None: unchanged)."""

    start: float
    name: str = ""
    ambient: float | None = None
    direct: float | None = None
    direction: tuple | None = None
    tint: tuple | None = None
    level: float | None = None
    exposure: float | None = None
    relative_to_camera: bool = False  # direction given in the (moving) camera's yaw frame


@dataclass(frozen=True)
class LightingSchedule:
    """Lighting over time: a base light, slow drift of its level, and abrupt segments.

    ``level(t) = base.level · segment level · (1 + drift · sin(2π t / drift_period + drift_phase))``.
    """

    base: Light = field(default_factory=Light)
    drift: float = 0.03
    drift_period: float = 40.0
    drift_phase: float = 0.0
    segments: tuple = ()

    def at(self, t: float, camera_yaw: float | None = None) -> tuple[Light, str]:
        """The light at time ``t`` (s) and the name of the segment in force."""
        values = dict(ambient=self.base.ambient, direct=self.base.direct, direction=self.base.direction,
                      tint=self.base.tint, level=self.base.level, exposure=self.base.exposure)
        name = ""
        relative = False
        for seg in sorted(self.segments, key=lambda s: s.start):
            if seg.start <= t + 1e-9:
                for k in values:
                    val = getattr(seg, k)
                    if val is not None:
                        values[k] = val
                if seg.direction is not None:
                    relative = seg.relative_to_camera
                name = seg.name
        if relative and camera_yaw is not None:
            d = np.asarray(values["direction"], dtype=float)
            c, s = np.cos(camera_yaw), np.sin(camera_yaw)
            values["direction"] = (c * d[0] - s * d[1], s * d[0] + c * d[1], d[2])
        values["level"] *= 1.0 + self.drift * np.sin(2 * np.pi * t / self.drift_period + self.drift_phase)
        return Light(**values), name


@dataclass
class WhiteBalance:
    """A camera's automatic white balance with integer R/B gains (0…1023, 512 = ×1).

    Parameters
    ----------
    mode : "auto" (grey world with a jump threshold) or "fixed"
    r, b : int — gains at the start (auto mode sets them from the first frame)
    threshold : int — auto mode jumps to the grey-world gains when either differs by more
    schedule : dict frame → (r, b) — set-points applied at exactly those frames (both modes)
    offsets : dict frame → (dr, db) — from that frame on, these steps are added to the gains the
        camera reports and applies (until the next entry): a white balance that wanders off by
        itself, as seed 001's camera did. The automatic white balance keeps its own state.
    """

    mode: str = "auto"
    r: int = WB_UNITY
    b: int = WB_UNITY
    threshold: int = 40
    schedule: dict = field(default_factory=dict)
    offsets: dict = field(default_factory=dict)
    _started: bool = False

    def update(self, frame: int, raw_mean_bgr: np.ndarray) -> tuple[int, int]:
        """Gains for this frame, given the mean BGR of the raw (pre-white-balance) image."""
        if self.mode == "auto":
            m = np.maximum(np.asarray(raw_mean_bgr, dtype=float), 1e-3)
            tr = int(np.clip(round(WB_UNITY * m[1] / m[2]), 0, WB_MAX))
            tb = int(np.clip(round(WB_UNITY * m[1] / m[0]), 0, WB_MAX))
            if not self._started or abs(tr - self.r) > self.threshold or abs(tb - self.b) > self.threshold:
                self.r, self.b = tr, tb
        self._started = True
        if frame in self.schedule:
            r, b = self.schedule[frame]
            self.r, self.b = int(np.clip(r, 0, WB_MAX)), int(np.clip(b, 0, WB_MAX))
        if not self.offsets:
            return self.r, self.b
        dr, db = self.offset_at(frame)
        return int(np.clip(self.r + dr, 0, WB_MAX)), int(np.clip(self.b + db, 0, WB_MAX))

    def offset_at(self, frame: int) -> tuple[int, int]:
        """The (dr, db) steps of :attr:`offsets` in force at ``frame`` ((0, 0) before the first)."""
        starts = [f for f in self.offsets if f <= frame]
        return tuple(int(v) for v in self.offsets[max(starts)]) if starts else (0, 0)


def grey_world_mean(raw: np.ndarray) -> np.ndarray:
    """Mean BGR (3,) of a raw (pre-white-balance) image (H, W, 3), what :meth:`WhiteBalance.update` reads.

    Every 4th pixel in both directions, leaving out dark (≤ 3) and saturated (≥ 250) ones; the
    plain mean (+ 1e-3) when 10 or fewer remain.
    """
    sub = raw[::4, ::4].reshape(-1, 3)
    ok = np.all((sub > 3) & (sub < 250), axis=1)
    return sub[ok].mean(axis=0) if ok.sum() > 10 else sub.mean(axis=0) + 1e-3


@dataclass(frozen=True)
class SensorNoise:
    """Optics and sensor: blur, vignetting, shot and read noise (display units, 0–255).

    ``σ² = read_noise² + shot_noise · value``; ``blur_sigma`` in pixels at 640 px width (scaled
    with the image); ``vignetting`` is the relative fall-off at the image corners.
    """

    read_noise: float = 1.8
    shot_noise: float = 0.05
    blur_sigma: float = 0.8
    vignetting: float = 0.12


def vignetting_map(width: int, height: int, strength: float) -> np.ndarray:
    """(H, W) float32 factor: 1 at the centre, 1 − strength at the corners (cos⁴-like)."""
    v, u = np.mgrid[0:height, 0:width].astype(np.float32)
    r2 = ((u - (width - 1) / 2) ** 2 + (v - (height - 1) / 2) ** 2) / (((width - 1) / 2) ** 2 + ((height - 1) / 2) ** 2)
    return (1.0 - strength * r2).astype(np.float32)


# Standard normal quantiles of the 256 byte values: one random byte → one N(0, 1) sample
# (tails cut at ±2.9σ). Far faster than Gaussian sampling, and the image is quantised to 8 bits anyway.
NORMAL_LUT = ndtri((np.arange(256) + 0.5) / 256.0).astype(np.float32)


def noise_bytes(rng: np.random.Generator, shape: tuple[int, ...]) -> np.ndarray:
    """Uniform random bytes (uint8, ``shape``) from the generator's bit stream."""
    n = int(np.prod(shape))
    return rng.bit_generator.random_raw((n + 7) // 8).view(np.uint8)[:n].reshape(shape)


@njit(cache=True)
def _finish_kernel(img, gains, vignette, noise, lut, read2, shot, out):
    """uint8 = round(clip(x + sqrt(read² + shot·x)·N, 0, 255)), x = img·gain·vignetting (in place)."""
    H, W, C = img.shape
    for v in range(H):
        for u in range(W):
            f = vignette[v, u]
            for c in range(C):
                x = img[v, u, c] * gains[c] * f
                std = math.sqrt(read2 + shot * max(x, np.float32(0.0)))
                x = x + std * lut[noise[v, u, c]]
                x = min(max(x, np.float32(0.0)), np.float32(255.0))
                out[v, u, c] = np.uint8(math.floor(x + 0.5))


def _blur(radiance: np.ndarray, noise: SensorNoise) -> np.ndarray:
    sigma = noise.blur_sigma * radiance.shape[1] / 640.0
    return cv2.GaussianBlur(radiance, (0, 0), sigma) if sigma > 0.05 else radiance


def expose(radiance: np.ndarray, gains_bgr: np.ndarray, noise: SensorNoise, rng: np.random.Generator | None,
           vignette: np.ndarray | None) -> np.ndarray:
    """Raw radiance (H, W, 3) float32 → uint8 BGR: blur, white-balance gains, vignetting, noise, rounding.

    ``rng`` None gives the noise-free image (background plates). Numba kernel; see
    :func:`expose_reference` for the same computation in NumPy.
    """
    img = np.ascontiguousarray(_blur(radiance, noise), dtype=np.float32)
    H, W, _ = img.shape
    vig = vignette if vignette is not None else np.ones((H, W), np.float32)
    if rng is None:
        nb, read2, shot = np.zeros((H, W, 3), np.uint8), 0.0, 0.0
    else:
        nb, read2, shot = noise_bytes(rng, (H, W, 3)), noise.read_noise ** 2, noise.shot_noise
    out = np.empty((H, W, 3), np.uint8)
    _finish_kernel(img, np.asarray(gains_bgr, np.float32), np.ascontiguousarray(vig, np.float32), nb, NORMAL_LUT,
                   np.float32(read2), np.float32(shot), out)
    return out


def expose_reference(radiance: np.ndarray, gains_bgr: np.ndarray, noise: SensorNoise, nb: np.ndarray | None,
                     vignette: np.ndarray | None) -> np.ndarray:
    """NumPy version of :func:`expose`, given the noise bytes ``nb`` (None: noise-free)."""
    img = _blur(radiance, noise).astype(np.float32)
    img = img * np.asarray(gains_bgr, np.float32)[None, None, :]
    if vignette is not None:
        img = img * vignette[:, :, None]
    if nb is not None:
        std = np.sqrt(np.float32(noise.read_noise ** 2) + np.float32(noise.shot_noise) * np.maximum(img, 0))
        img = img + std * NORMAL_LUT[nb]
    return np.floor(np.clip(img, 0, 255) + 0.5).astype(np.uint8)
