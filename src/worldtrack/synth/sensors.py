"""What a camera measures besides colour: stereo disparity and Kinect-like depth, with their holes.

Both sensors are modelled from the exact depth of the rendered view plus the exact depth of a
second viewpoint shifted by the baseline along the camera's x axis (the stereo pair's right camera,
or the depth camera's pattern projector). A left pixel whose 3-D point is not the first surface
seen from the second viewpoint is occluded there and gets no measurement — the holes beside every
person in a real disparity or Kinect image.

* **Stereo** (Bumblebee2-like, seed 001): disparity ``d = fx·B / Z`` in pixels (rectified pinhole
  pair), with Gaussian matching noise, quantised to 1/16 px; invalid (0) where occluded in the
  right view, outside it, where the left image has too little texture to match (local standard
  deviation below a threshold), on sky, and in a few random speckles. Depth ``Z = fx·B / d``.
* **RGB-D** (Kinect-like, seed 003): depth with axial noise ``σ = k·Z²``, quantised to
  ``depth_step`` (1 mm by default, coarser e.g. 5 mm for seed 003's simulation), invalid (0) below
  ``depth_min`` (0.5 m), beyond ``depth_max`` and in the projector's shadow.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from worldtrack.errors import InputError
from worldtrack.geometry.camera import Camera

SENSOR_KINDS = ("mono", "stereo", "rgbd")


@dataclass(frozen=True)
class SensorSpec:
    """The kind of camera and its depth model.

    Parameters
    ----------
    kind : "mono", "stereo" or "rgbd"
    baseline : float, metres — stereo baseline, or RGB-D camera–projector offset
    depth_step : float, metres — RGB-D quantisation step
    depth_min, depth_max : float, metres — RGB-D valid range
    depth_noise : float, 1/m — RGB-D axial noise ``σ = depth_noise·Z²``
    disparity_noise : float, pixels — stereo matching noise (σ)
    texture_threshold : float, display units — stereo fails where the local std is below this
    speckle : float — fraction of random invalid pixels (stereo)
    """

    kind: str = "mono"
    baseline: float = 0.12
    depth_step: float = 0.001
    depth_min: float = 0.5
    depth_max: float = 8.0
    depth_noise: float = 1.4e-3
    disparity_noise: float = 0.12
    texture_threshold: float = 1.0
    speckle: float = 0.002

    def __post_init__(self):
        if self.kind not in SENSOR_KINDS:
            raise InputError(f"sensor: expected one of {', '.join(SENSOR_KINDS)}, got {self.kind!r}")
        if self.baseline <= 0:
            raise InputError(f"baseline: expected a positive length in metres, got {self.baseline}")
        if self.depth_step <= 0:
            raise InputError(f"depth_step: expected a positive step in metres, got {self.depth_step}")

    @property
    def has_depth(self) -> bool:
        return self.kind in ("stereo", "rgbd")


def second_view(camera: Camera, baseline: float) -> Camera:
    """The camera moved by ``baseline`` metres along its own x axis (image right), same rotation."""
    return camera.moved(camera.R, camera.t - np.array([baseline, 0.0, 0.0]))


def occluded_in_second_view(depth: np.ndarray, depth_second: np.ndarray, fx: float, baseline: float,
                            rel_tol: float = 0.03, abs_tol: float = 0.01) -> tuple[np.ndarray, np.ndarray]:
    """Which pixels of the first view are not seen from the second (rectified pinhole pair).

    Parameters
    ----------
    depth, depth_second : (H, W) float32, metres along the optical axis (inf where nothing)
    fx : float, pixels; baseline : float, metres

    Returns
    -------
    occluded : (H, W) bool — also True where the point falls outside the second image
    disparity : (H, W) float32 — ``fx·B/Z`` (0 where depth is not finite)
    """
    H, W = depth.shape
    finite = np.isfinite(depth) & (depth > 0)
    disp = np.zeros((H, W), dtype=np.float32)
    disp[finite] = fx * baseline / depth[finite]
    u = np.arange(W, dtype=np.float32)[None, :]
    ur = np.rint(u - disp).astype(np.int64)
    inside = (ur >= 0) & (ur < W)
    rows = np.broadcast_to(np.arange(H)[:, None], (H, W))
    z2 = np.full((H, W), np.inf, dtype=np.float32)
    z2[inside] = depth_second[rows[inside], ur[inside]]
    with np.errstate(invalid="ignore"):
        consistent = np.abs(z2 - depth) <= rel_tol * depth + abs_tol
    return ~(inside & consistent) | ~finite, disp


def local_std(grey: np.ndarray, size: int = 7) -> np.ndarray:
    """Standard deviation of ``grey`` (H, W) float32 in a size × size window."""
    m = cv2.blur(grey, (size, size))
    m2 = cv2.blur(grey * grey, (size, size))
    return np.sqrt(np.maximum(m2 - m * m, 0.0))


def stereo_measurement(spec: SensorSpec, depth: np.ndarray, depth_right: np.ndarray, fx: float,
                       clean_grey: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Disparity (px) and depth (m) a stereo matcher would report; 0 = no measurement.

    ``clean_grey`` is the left image's noise-free brightness (H, W) float32 for the texture test.
    """
    occluded, disp = occluded_in_second_view(depth, depth_right, fx, spec.baseline)
    textureless = local_std(clean_grey) < spec.texture_threshold
    invalid = occluded | textureless
    if spec.speckle > 0:
        invalid |= rng.random(depth.shape) < spec.speckle
    # Matching windows smear occlusion holes by a pixel or two.
    invalid = cv2.dilate(invalid.astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)
    noisy = disp + spec.disparity_noise * rng.standard_normal(depth.shape, dtype=np.float32)
    noisy = np.rint(noisy * 16.0) / 16.0
    invalid |= noisy <= 0
    disparity = np.where(invalid, 0.0, noisy).astype(np.float32)
    z = np.zeros_like(disparity)
    ok = disparity > 0
    z[ok] = fx * spec.baseline / disparity[ok]
    return disparity, z


def kinect_depth(spec: SensorSpec, depth: np.ndarray, depth_projector: np.ndarray, fx: float,
                 rng: np.random.Generator) -> np.ndarray:
    """Depth (m) a Kinect-like RGB-D camera reports: noisy, quantised, 0 where invalid."""
    shadow, _ = occluded_in_second_view(depth, depth_projector, fx, spec.baseline)
    finite = np.isfinite(depth)
    z = np.where(finite, depth, 0.0).astype(np.float32)
    z = z + spec.depth_noise * z * z * rng.standard_normal(depth.shape, dtype=np.float32)
    z = np.rint(z / spec.depth_step) * spec.depth_step
    invalid = shadow | ~finite | (z < spec.depth_min) | (z > spec.depth_max)
    return np.where(invalid, 0.0, z).astype(np.float32)


def depth_to_png_mm(depth: np.ndarray) -> np.ndarray:
    """Metres (0 = invalid) → uint16 millimetres for a 16-bit PNG (saturates at 65.535 m)."""
    return np.clip(np.rint(np.nan_to_num(depth, nan=0.0, posinf=0.0) * 1000.0), 0, 65535).astype(np.uint16)


def disparity_to_png(disparity: np.ndarray) -> np.ndarray:
    """Pixels (0 = invalid) → uint16 in 1/16 px (OpenCV's fixed-point convention)."""
    return np.clip(np.rint(disparity * 16.0), 0, 65535).astype(np.uint16)
