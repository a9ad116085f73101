"""The Tsai camera model and its conversion to the OpenCV model, on PETS 2009 View_001's numbers.

The parameters below are copied from the official PETS 2009 calibration file View_001.xml
(Willson's Tsai model, millimetres, 768x576); the check values are those of the data README:
world (-4140, -7400, 0) mm projects to (514.8, 232.0) px, 1.7 m higher is about 71 px higher in
the image, and the camera centre is about (-28.9, -19.5, 7.07) m.
"""

from __future__ import annotations

import numpy as np
import pytest

from worldtrack.geometry.camera import Camera
from worldtrack.geometry.rotation import euler_zyx
from worldtrack.geometry.tsai import TsaiCamera, conversion_errors, distorted_radius, tsai_to_camera

VIEW_001 = dict(rx=2.0405458695, ry=-0.89337703748, rz=-0.43056124791,
                T=np.array([828.73214225, -3175.4796051, 35469.298547]) / 1000.0,
                focal_mm=5.5549183034, kappa1_per_mm2=5.1113043639e-03, dpx_mm=5.1273271277e-03,
                dpy_mm=4.65e-03, sx=1.0937855397, cx=324.22149053, cy=282.56650051)
CHECK_WORLD = np.array([-4.140, -7.400, 0.0])
CHECK_PIXEL = np.array([514.8, 232.0])
CENTRE = np.array([-28.9, -19.5, 7.07])


@pytest.fixture(scope="module")
def tsai() -> TsaiCamera:
    return TsaiCamera("View_001", 768, 576, **VIEW_001)


@pytest.fixture(scope="module")
def converted(tsai):
    return tsai_to_camera(tsai)


def reference_project(cam: TsaiCamera, X: np.ndarray) -> np.ndarray:
    """Independent Tsai projection: the distorted radius by plain fixed-point iteration."""
    R = euler_zyx(cam.rz, cam.ry, cam.rx)
    out = []
    for p in np.atleast_2d(X):
        xc, yc, zc = R @ p + cam.T
        xu, yu = cam.focal_mm * xc / zc, cam.focal_mm * yc / zc
        ru = np.hypot(xu, yu)
        rd = ru
        for _ in range(500):                      # rd = ru / (1 + κ1·rd²)
            rd = ru / (1.0 + cam.kappa1_per_mm2 * rd * rd)
        xd, yd = xu * rd / ru, yu * rd / ru
        out.append([cam.sx * xd / cam.dpx_mm + cam.cx, yd / cam.dpy_mm + cam.cy])
    return np.array(out)


# ---------------------------------------------------------------------------- the exact model

def test_check_point_projects_to_the_published_pixel(tsai):
    uv = tsai.project(CHECK_WORLD)
    assert np.linalg.norm(uv - CHECK_PIXEL) < 1.0
    np.testing.assert_allclose(uv, reference_project(tsai, CHECK_WORLD)[0], atol=1e-9)


def test_head_height_is_about_71_px_higher(tsai):
    feet, head = tsai.project(np.array([CHECK_WORLD, CHECK_WORLD + [0, 0, 1.7]]))
    assert 69.0 < feet[1] - head[1] < 73.0
    assert abs(feet[0] - head[0]) < 2.0


def test_centre_and_rotation_convention(tsai):
    assert np.linalg.norm(tsai.centre - CENTRE) < 0.1
    R = tsai.R
    np.testing.assert_allclose(R, euler_zyx(VIEW_001["rz"], VIEW_001["ry"], VIEW_001["rx"]))
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
    # A point in front projects; the camera looks down (Z of the optical axis < 0).
    assert R[2, 2] < 0


def test_projection_agrees_with_an_iterative_reference_over_the_floor(tsai):
    rng = np.random.default_rng(1)
    X = np.column_stack([rng.uniform(-15, 5, 200), rng.uniform(-14, 2, 200), rng.uniform(0, 2, 200)])
    np.testing.assert_allclose(tsai.project(X), reference_project(tsai, X), atol=1e-8)


def test_backprojection_inverts_projection(tsai):
    rng = np.random.default_rng(2)
    X = np.column_stack([rng.uniform(-15, 5, 100), rng.uniform(-14, 2, 100), np.zeros(100)])
    np.testing.assert_allclose(tsai.backproject(tsai.project(X), 0.0), X, atol=1e-9)
    heads = X + [0, 0, 1.7]
    np.testing.assert_allclose(tsai.backproject(tsai.project(heads), 1.7), heads, atol=1e-9)


def test_points_behind_the_camera_are_nan(tsai):
    behind = tsai.centre - 5 * tsai.R[2]
    assert np.all(np.isnan(tsai.project(behind)))


@pytest.mark.parametrize("kappa1", [5e-3, 0.05, -5e-3, 1e-13, -1e-13, 0.0])
def test_distorted_radius_solves_the_cubic(kappa1):
    ru = np.linspace(0.0, 2.5, 101)
    rd = distorted_radius(ru, kappa1)
    np.testing.assert_allclose(rd * (1 + kappa1 * rd ** 2), ru, atol=1e-12)
    assert np.all(np.diff(rd) > 0)          # the branch through rd = ru at the centre


def test_distorted_radius_beyond_a_negative_lens_range_is_nan():
    kappa1 = -0.05
    limit = 2.0 / (3.0 * np.sqrt(3 * 0.05))          # largest ru reachable: 1.72
    rd = distorted_radius([0.5 * limit, 0.999 * limit, 1.01 * limit, 10.0], kappa1)
    assert np.all(np.isfinite(rd[:2])) and np.all(np.isnan(rd[2:]))


# ---------------------------------------------------------------------------- conversion

def test_conversion_keeps_intrinsics_and_pose(tsai, converted):
    cam = converted.camera
    f, sx, dpx, dpy = VIEW_001["focal_mm"], VIEW_001["sx"], VIEW_001["dpx_mm"], VIEW_001["dpy_mm"]
    np.testing.assert_allclose(cam.K, [[f * sx / dpx, 0, VIEW_001["cx"]], [0, f / dpy, VIEW_001["cy"]], [0, 0, 1]])
    np.testing.assert_allclose(cam.R, tsai.R)
    np.testing.assert_allclose(cam.t, tsai.T)
    np.testing.assert_allclose(cam.centre, tsai.centre)
    assert (cam.width, cam.height) == (768, 576)
    assert cam.dist[2] == cam.dist[3] == 0.0          # Tsai's lens is purely radial


def test_conversion_fit_is_far_below_a_tenth_of_a_pixel(converted):
    assert converted.max_error_px < 0.01
    assert converted.rms_error_px < converted.max_error_px
    assert converted.max_error_margin_px < 0.05
    assert converted.monotonic
    # Normalised κ = κ1·f² ≈ 0.158: OpenCV k1 ≈ −κ (series inversion r_d = r(1 − κr² + 3κ²r⁴ …)).
    assert converted.camera.dist[0] == pytest.approx(-0.1577, abs=0.003)


def test_conversion_error_is_measured_against_the_exact_model(tsai, converted):
    rng = np.random.default_rng(3)
    uv = np.column_stack([rng.uniform(0, 767, 500), rng.uniform(0, 575, 500)])
    err = conversion_errors(tsai, converted.camera, uv)
    assert err.max() <= converted.max_error_px + 1e-6
    # One radial term cannot follow Tsai's lens: the error is then visible.
    one = tsai_to_camera(tsai, radial_terms=1)
    assert one.max_error_px > 0.1 > converted.max_error_px


def test_converted_camera_reproduces_the_check_values(tsai, converted):
    cam = converted.camera
    feet, head = cam.project(np.array([CHECK_WORLD, CHECK_WORLD + [0, 0, 1.7]]))
    assert np.linalg.norm(feet - CHECK_PIXEL) < 1.0
    np.testing.assert_allclose(feet, tsai.project(CHECK_WORLD), atol=0.01)
    assert 69.0 < feet[1] - head[1] < 73.0
    # Back-projection through the OpenCV model lands where Tsai's does (within 1 mm at 15 m).
    uv = tsai.project(np.array([[-14.0, -14.2, 0.0], [4.9, 1.7, 0.0], [-4.1, -7.4, 0.0]]))
    np.testing.assert_allclose(cam.backproject(uv, 0.0), tsai.backproject(uv, 0.0), atol=1e-3)


def test_scaled_converted_camera_matches_the_rescaled_pixels(converted):
    small = converted.camera.scaled(0.625)
    assert (small.width, small.height) == (480, 360)
    uv_big = converted.camera.project(CHECK_WORLD)
    np.testing.assert_allclose(small.project(CHECK_WORLD), 0.625 * (uv_big + 0.5) - 0.5, atol=1e-9)


def test_a_lens_without_distortion_converts_exactly():
    cam = TsaiCamera("c", 640, 480, **{**VIEW_001, "kappa1_per_mm2": 0.0})
    conv = tsai_to_camera(cam)
    assert conv.radial_terms == 2 and conv.max_error_px < 1e-9
    np.testing.assert_allclose(conv.camera.dist, 0.0, atol=1e-12)
    assert isinstance(conv.camera, Camera) and not conv.camera.has_distortion


def test_invalid_parameters_are_refused():
    with pytest.raises(ValueError, match="focal_mm"):
        TsaiCamera("c", 768, 576, **{**VIEW_001, "focal_mm": 0.0})
    with pytest.raises(ValueError, match="radial_terms"):
        tsai_to_camera(TsaiCamera("c", 768, 576, **VIEW_001), radial_terms=4)
