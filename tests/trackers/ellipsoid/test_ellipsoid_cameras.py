"""Per-camera state: views of cameras, rays, and the compiled pixel test against its reference."""

import numpy as np
from _ellipsoid_scenes import lab_scene, person_mask, two_camera_scene

from worldtrack.trackers.ellipsoid.args import DrawArgs
from worldtrack.trackers.ellipsoid.cameras import camera_view, pixel_clear, pixel_clear_reference, ray_direction


def test_camera_view_scales_the_ring_and_counts_visible_pixels_behind_obstacles():
    lab = lab_scene()
    view = camera_view(lab, "cam1", None, ring_px_160=5.0, draw=DrawArgs(0.1, 0.0))
    cam = lab.cameras["cam1"]
    assert view.ring_px == round(5.0 * np.sqrt(cam.width * cam.height / (160 * 120)))
    person = np.array([-1.0, 1.0])
    # In the open: the count is the drawn silhouette's (up to the edge pixels of float32 grids).
    assert abs(view.visible_pixels(person, 1.65, 0.4) - person_mask(cam, person, 1.65, 0.4).sum()) <= 3
    behind_desk = np.array([-1.0, 2.9])
    assert 0 < view.visible_pixels(behind_desk, 1.65, 0.4) < 0.85 * person_mask(cam, behind_desk, 1.65, 0.4).sum()
    assert view.visible_pixels(np.array([-1.0, -30.0]), 1.65, 0.4) == 0          # behind the camera


def test_ray_direction_is_along_the_line_of_sight_on_the_floor():
    scene = two_camera_scene()
    for cam in scene.cameras.values():
        xy = np.array([-0.5, 2.0])
        d = ray_direction(cam, xy)
        away = xy - cam.centre[:2]
        np.testing.assert_allclose(d, away / np.linalg.norm(away), atol=1e-12)


def test_pixel_clear_equals_the_reference():
    from worldtrack.geometry.camera import Camera
    cam = Camera.look_at("c", 64, 48, [0.0, -5.0, 3.0], [0.0, 0.0, 0.0], hfov_deg=60.0)
    occ = np.full((48, 64), np.inf, np.float32)
    occ[30:, 10:40] = 4.0                                     # an obstacle in the lower left
    rng = np.random.default_rng(2)
    p = rng.uniform([-3, -3], [67, 51], (500, 2))
    p[:50] = np.round(p[:50]) + 0.5                            # exact halves round to even
    for grid in (None, occ):
        got = pixel_clear(cam, grid, p)
        np.testing.assert_array_equal(got, pixel_clear_reference(cam, grid, p))
        assert got.shape == (500,) and 0 < got.sum() < 500
        np.testing.assert_array_equal(pixel_clear(cam, grid, p.reshape(50, 10, 2)), got.reshape(50, 10))
        assert pixel_clear(cam, grid, p[7]) == got[7]            # one point: a scalar
    assert not pixel_clear(cam, occ, np.array([20.0, 40.0])) and pixel_clear(cam, None, np.array([20.0, 40.0]))
