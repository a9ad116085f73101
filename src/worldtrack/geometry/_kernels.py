"""The one compiled lens and projection kernel: every Numba kernel that projects calls these.

The arithmetic is that of :meth:`worldtrack.geometry.camera.Camera.project` (the NumPy reference;
``tests/geometry/test_kernels.py`` checks that they agree bit for bit): world → camera frame
``R·p + t``, perspective division, OpenCV's lens distortion (k1, k2, p1, p2, k3) on normalised
coordinates, then the intrinsics ``K`` (with skew). Kernels read a camera's constants once per call
as a tuple of scalars (:func:`lens`): read from the arrays inside a sample loop they would be
reloaded at every sample, as the compiler cannot tell that the output arrays do not alias them.

All functions are inlined into the kernels that call them (``inline="always"``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def lens(K, dist):
    """A camera's intrinsics and distortion as scalars:
    ``(f_x, skew, c_x, f_y, c_y, k1, k2, p1, p2, k3)`` from ``K`` (3, 3) and ``dist`` (5,)."""
    return K[0, 0], K[0, 1], K[0, 2], K[1, 1], K[1, 2], dist[0], dist[1], dist[2], dist[3], dist[4]


@njit(cache=True, inline="always")
def distortion_terms(x, y, k1, k2, p1, p2, k3):
    """OpenCV's lens model at normalised point (x, y): the radial factor
    ``1 + k1·r² + k2·r⁴ + k3·r⁶`` and the tangential shifts (dx, dy)."""
    r2 = x * x + y * y
    radial = radial_factor(r2, k1, k2, k3)
    dx = 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x)
    dy = p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y
    return radial, dx, dy


@njit(cache=True, inline="always")
def radial_factor(r2, k1, k2, k3):
    """OpenCV's radial distortion factor ``1 + k1·r² + k2·r⁴ + k3·r⁶`` at ``r2 = r²``."""
    return 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))


@njit(cache=True, inline="always")
def distort(x, y, k1, k2, p1, p2, k3):
    """Normalised ideal point (x, y) → normalised distorted point (OpenCV's model).

    Summed left to right as :meth:`Camera.distort_normalised` sums (``x·radial + 2·p1·x·y +
    p2·(r² + 2x²)``), so the two agree bit for bit."""
    r2 = x * x + y * y
    radial = radial_factor(r2, k1, k2, k3)
    return (x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
            y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y)


@njit(cache=True, inline="always")
def undistort(xd, yd, k1, k2, p1, p2, k3, max_iterations, tol):
    """Invert :func:`distort` by fixed-point iteration (as OpenCV and
    :meth:`Camera.undistort_normalised` do): until no coordinate moves by more than ``tol``."""
    x, y = xd, yd
    for _ in range(max_iterations):
        radial, dx, dy = distortion_terms(x, y, k1, k2, p1, p2, k3)
        xn = (xd - dx) / radial
        yn = (yd - dy) / radial
        change = max(abs(xn - x), abs(yn - y))
        x, y = xn, yn
        if not change > tol:
            break
    return x, y


@njit(cache=True, inline="always")
def camera_to_pixel(cx, cy, cz, lens_, has_dist):
    """Camera-frame point → pixel (u, v), not rounded, not tested against the image; NaN, NaN
    behind the camera (depth ≤ 1e-9 m). ``lens_`` from :func:`lens`."""
    if not cz > 1e-9:
        return np.nan, np.nan
    x = cx / cz
    y = cy / cz
    if has_dist:
        x, y = distort(x, y, lens_[5], lens_[6], lens_[7], lens_[8], lens_[9])
    return lens_[0] * x + lens_[1] * y + lens_[2], lens_[3] * y + lens_[4]


@njit(cache=True, inline="always")
def world_to_camera(px, py, pz, R, t):
    """World point → camera frame ``R·p + t`` (three scalars)."""
    cx = R[0, 0] * px + R[0, 1] * py + R[0, 2] * pz + t[0]
    cy = R[1, 0] * px + R[1, 1] * py + R[1, 2] * pz + t[1]
    cz = R[2, 0] * px + R[2, 1] * py + R[2, 2] * pz + t[2]
    return cx, cy, cz


@njit(cache=True, inline="always")
def world_to_pixel(px, py, pz, R, t, lens_, has_dist):
    """World point → pixel (u, v) (NaN behind the camera): :meth:`Camera.project` of one point."""
    cx, cy, cz = world_to_camera(px, py, pz, R, t)
    return camera_to_pixel(cx, cy, cz, lens_, has_dist)


@njit(cache=True, inline="always")
def nearest_index(c, n):
    """Nearest pixel index of coordinate ``c`` along an image axis of ``n`` pixels; −1 outside the
    image (``−0.5 ≤ c < n − 0.5``) or NaN."""
    if not (c >= -0.5 and c < n - 0.5):
        return -1
    return int(math.floor(c + 0.5))


@njit(cache=True, inline="always")
def ideal_to_real_pixel(u, v, K, dist):
    """Pixel of the ideal pinhole image → pixel of the real (distorted) image."""
    fx, s, cx, fy, cy = K[0, 0], K[0, 1], K[0, 2], K[1, 1], K[1, 2]
    y = (v - cy) / fy
    x = (u - cx - s * y) / fx
    xd, yd = distort(x, y, dist[0], dist[1], dist[2], dist[3], dist[4])
    return fx * xd + s * yd + cx, fy * yd + cy


@njit(cache=True)
def project_points(points, R, t, K, dist, has_dist, out):
    """:func:`world_to_pixel` of (N, 3) world points into ``out`` (N, 2), in place — the kernel
    the tests compare with :meth:`Camera.project`."""
    lens_ = lens(K, dist)
    for i in range(points.shape[0]):
        out[i, 0], out[i, 1] = world_to_pixel(points[i, 0], points[i, 1], points[i, 2], R, t, lens_, has_dist)


__all__ = ["camera_to_pixel", "distort", "radial_factor", "distortion_terms", "ideal_to_real_pixel", "lens", "nearest_index",
           "project_points", "undistort", "world_to_camera", "world_to_pixel"]
