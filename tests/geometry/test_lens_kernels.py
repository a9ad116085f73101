"""The one compiled lens/projection kernel agrees with Camera's NumPy projection (to rounding: the
NumPy version multiplies by R with a matrix product)."""

import numpy as np
import pytest

from worldtrack.geometry import _kernels
from worldtrack.geometry.camera import Camera


def _camera(dist):
    return Camera.look_at("c", 640, 480, position=[0.3, -4.0, 2.7], target=[0.5, 3.0, 0.8], hfov_deg=80.0,
                          dist=dist)


@pytest.mark.parametrize("dist", [None, [-0.28, 0.09, 0.001, -0.002, -0.01]])
def test_project_points_equals_camera_project(dist):
    cam = _camera(dist)
    rng = np.random.default_rng(0)
    pts = np.column_stack([rng.uniform(-4, 5, 500), rng.uniform(-6, 8, 500), rng.uniform(-0.5, 3, 500)])
    pts[:5] = [[0.3, -4.0, 2.7], [0.3, -4.5, 2.7], [0.3, -3.9999999999, 2.7], [0, 0, 0], [1, 1, 1]]  # at/behind the centre
    out = np.empty((len(pts), 2))
    _kernels.project_points(pts, np.ascontiguousarray(cam.R), np.ascontiguousarray(cam.t), np.ascontiguousarray(cam.K),
                            np.ascontiguousarray(cam.dist, dtype=float), cam.has_distortion, out)
    expected = cam.project(pts)
    assert np.array_equal(np.isnan(out), np.isnan(expected))
    assert np.allclose(out[~np.isnan(out)], expected[~np.isnan(expected)], rtol=1e-12, atol=1e-9)
    assert np.isnan(out[1]).all()                                               # behind the camera


def test_undistort_inverts_distort_as_camera_does():
    cam = _camera([-0.28, 0.09, 0.001, -0.002, -0.01])
    xy = np.random.default_rng(1).uniform(-0.6, 0.6, (200, 2))
    d = cam.distort_normalised(xy)
    k = cam.dist
    back = np.array([_kernels.undistort(x, y, k[0], k[1], k[2], k[3], k[4], 200, 1e-12) for x, y in d])
    assert np.abs(back - xy).max() < 1e-9
    ideal = np.array([_kernels.distort(x, y, *k) for x, y in xy])
    assert np.array_equal(ideal, d)
