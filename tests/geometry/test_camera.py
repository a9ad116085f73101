"""Camera: projection, distortion, back-projection, decomposition, normalisation."""

import cv2
import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from worldtrack.geometry.camera import Camera, normalise_projection
from worldtrack.geometry.rotation import rotation_to_rodrigues


def oblique(dist=None, size=(640, 480)):
    return Camera.look_at("c", size[0], size[1], position=(-1.0, -1.74, 2.64), target=(-1.0, 0.9, 0.68),
                          hfov_deg=60, dist=dist)


def random_camera(rng, dist=True):
    pos = np.array([rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(1.5, 5)])
    target = np.array([rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(0, 1)])
    # Moderate lenses: with strong barrel distortion and a wide field the corners lie beyond the
    # range where the distortion polynomial can be inverted by fixed-point iteration (OpenCV too).
    d = [rng.uniform(-0.15, 0.05), rng.uniform(-0.01, 0.02), rng.uniform(-1e-3, 1e-3), rng.uniform(-1e-3, 1e-3), 0.0]
    return Camera.look_at("r", 640, 480, pos, target, hfov_deg=rng.uniform(40, 90), dist=d if dist else None)


def test_look_at_centre_projects_to_principal_point():
    cam = Camera.look_at("c", 640, 480, position=(0, -4, 2.5), target=(0, 0, 1), hfov_deg=60)
    np.testing.assert_allclose(cam.project([[0, 0, 1]]), [[319.5, 239.5]], atol=1e-9)
    np.testing.assert_allclose(cam.centre, [0, -4, 2.5], atol=1e-12)
    # Image top is up: a point above the target projects higher (smaller v).
    assert cam.project([[0, 0, 2]])[0, 1] < 239.5


def test_projection_matches_opencv_with_distortion():
    rng = np.random.default_rng(1)
    for _ in range(5):
        cam = random_camera(rng)
        pts = np.column_stack([rng.uniform(-3, 3, 200), rng.uniform(-3, 3, 200), rng.uniform(0, 2, 200)])
        pts = pts[cam.depth(pts) > 0.5]
        # Stay inside the region where the distortion polynomial is monotonic (the real lens).
        xy = (pts @ cam.R.T + cam.t)[:, :2] / cam.depth(pts)[:, None]
        pts = pts[np.linalg.norm(xy, axis=1) < 0.9]
        ref, _ = cv2.projectPoints(pts, rotation_to_rodrigues(cam.R), cam.t, cam.K, cam.dist)
        np.testing.assert_allclose(cam.project(pts), ref[:, 0, :], atol=1e-6)


def test_undistort_matches_opencv_and_inverts_distort():
    cam = oblique(dist=[-0.25, 0.05, 1e-3, -5e-4, 0.0])
    rng = np.random.default_rng(2)
    uv = np.column_stack([rng.uniform(0, 639, 300), rng.uniform(0, 479, 300)])
    ideal = cam.undistort_pixels(uv)
    ref = cv2.undistortPoints(uv[:, None, :], cam.K, cam.dist, R=None, P=cam.K,
                              criteria=(cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12))[:, 0, :]
    np.testing.assert_allclose(ideal, ref, atol=1e-4)
    np.testing.assert_allclose(cam.distort_pixels(ideal), uv, atol=1e-6)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), z=st.floats(0.0, 1.8))
@example(seed=1326, z=0.0)  # a corner pixel where the fixed-point undistortion alone stops 2e-6 px short
def test_backproject_then_project_round_trip(seed, z):
    rng = np.random.default_rng(seed)
    cam = random_camera(rng)
    uv = np.column_stack([rng.uniform(0, 639, 50), rng.uniform(0, 479, 50)])
    world = cam.backproject(uv, z)
    ok = np.isfinite(world).all(axis=1)
    np.testing.assert_allclose(world[ok, 2], z, atol=1e-9)
    np.testing.assert_allclose(cam.project(world[ok]), uv[ok], atol=1e-6)


def test_pixels_beyond_the_lens_fold_have_no_ray():
    """Barrel distortion k1 = −0.45 folds back at r_f = 1/sqrt(3·0.45) ≈ 0.861 (normalised), where
    r·(1 + k1·r²) peaks at ≈ 0.574: pixels farther out have no ray. Undistortion gives them none
    (76 % of this wide image), and no point it returns lies beyond the fold — the final Newton
    refinement, run on every pixel, would find roots on the far branch for some of them."""
    k1 = -0.45
    cam = Camera.look_at("fold", 640, 480, (0, -4, 3), (0, 0, 0.5), hfov_deg=100, dist=[k1, 0, 0, 0, 0])
    r_fold = np.sqrt(1 / (3 * -k1))
    rd_max = r_fold * (1 + k1 * r_fold ** 2)
    v, u = np.mgrid[0:480, 0:640]
    pixels = np.column_stack([u.ravel(), v.ravel()]).astype(float)
    rd = np.hypot(*cam._pixels_to_normalised(pixels).T)
    ideal = cam.undistort_pixels(pixels)
    ok = np.isfinite(ideal).all(axis=1)
    assert not (ok & (rd > rd_max + 1e-6)).any()                      # no ray beyond the fold
    assert (ok | (rd > rd_max - 1e-3)).all()                          # every pixel inside it has one
    assert np.hypot(*cam._pixels_to_normalised(ideal[ok]).T).max() <= r_fold
    np.testing.assert_allclose(cam.distort_pixels(ideal[ok]), pixels[ok], atol=1e-6)


def test_backproject_above_horizon_is_nan_and_behind_camera_projects_nan():
    cam = Camera.look_at("c", 640, 480, position=(0, 0, 2), target=(0, 10, 2), hfov_deg=60)  # horizontal
    top = cam.backproject([[320, 10]], 0.0)  # looking above the horizon: never reaches the floor
    assert np.isnan(top).all()
    assert np.isnan(cam.project([[0, -5, 1]])).all()  # behind the camera


def test_from_projection_recovers_k_r_t_for_any_scale_and_sign():
    cam = oblique()
    for s in (1.0, 3.7, -0.02):
        c2 = Camera.from_projection("x", 640, 480, s * cam.P)
        np.testing.assert_allclose(c2.K, cam.K, atol=1e-8)
        np.testing.assert_allclose(c2.R, cam.R, atol=1e-12)
        np.testing.assert_allclose(c2.t, cam.t, atol=1e-12)


def test_normalisation_survives_world_origin_on_principal_plane():
    # Camera directly above the origin looking horizontally: the origin's depth is 0, so the
    # paper's C34 = 1 normalisation would divide by zero. Ours must not.
    cam = Camera.look_at("h", 640, 480, position=(0, 0, 2.5), target=(0, 5, 2.5), hfov_deg=60)
    assert abs(cam.P[2, 3]) < 1e-12
    Pn = normalise_projection(7.0 * cam.P)
    np.testing.assert_allclose(np.linalg.norm(Pn[2, :3]), 1.0)
    c2 = Camera.from_projection("h", 640, 480, 7.0 * cam.P)
    np.testing.assert_allclose(c2.centre, [0, 0, 2.5], atol=1e-12)
    # h of the normalised matrix is the depth along the optical axis.
    X = np.array([1.0, 4.0, 1.0, 1.0])
    assert Pn[2] @ X == pytest.approx(4.0)


def test_rank_deficient_projection_is_rejected():
    P = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0], [1.0, 1.0, 0, 1.0]])
    with pytest.raises(ValueError, match="rank"):
        normalise_projection(P)


def test_floor_direction_oblique_and_straight_down():
    np.testing.assert_allclose(oblique().floor_direction, [0, 1], atol=1e-12)
    down = Camera.look_at("d", 640, 480, (1, 1, 3), (1, 1, 0), hfov_deg=90)
    d = down.floor_direction
    np.testing.assert_allclose(np.linalg.norm(d), 1.0)
    # Straight down: the image top is world +Y, so the floor direction is +Y.
    np.testing.assert_allclose(d, [0, 1], atol=1e-9)
    assert down.project([[1, 2, 0]])[0, 1] < 239.5  # +Y appears towards the image top


def test_in_image_uses_pixel_centres_at_integers():
    cam = oblique(size=(160, 120))
    uv = np.array([[-0.5, 0], [-0.51, 0], [159.49, 119.49], [159.5, 0], [0, 119.5]])
    assert cam.in_image(uv).tolist() == [True, False, True, False, False]


def test_scaled_camera_projects_to_scaled_pixels():
    cam = oblique(dist=[-0.1, 0.01, 0, 0, 0], size=(768, 576))
    small = cam.scaled(0.625)
    assert (small.width, small.height) == (480, 360)
    pts = np.array([[-1, 1, 0], [0, 2, 1.7], [-2, 0.5, 0.3]])
    np.testing.assert_allclose(small.project(pts), 0.625 * (cam.project(pts) + 0.5) - 0.5, atol=1e-9)


def test_floor_rays_point_from_the_foot_point():
    cam = Camera.look_at("c", 320, 240, position=(1.0, -2.0, 3.0), target=(1.0, 3.0, 0.0), hfov_deg=60)
    along, dist = cam.floor_rays(np.array([[4.0, 2.0], [1.0, -2.0], [1.1, -2.0]]))
    np.testing.assert_allclose(along[0], [0.6, 0.8], atol=1e-12)
    np.testing.assert_allclose(dist, [5.0, 0.0, 0.1], atol=1e-12)
    np.testing.assert_allclose(along[1], cam.floor_direction)               # the foot point itself
    np.testing.assert_allclose(along[2], [1.0, 0.0], atol=1e-12)
    near, _ = cam.floor_rays(np.array([1.1, -2.0]), min_distance=0.3)       # too near to trust
    np.testing.assert_allclose(near, cam.floor_direction)
    np.testing.assert_allclose(cam.floor_distance([[4.0, 2.0, 1.7]]), [5.0])


def test_a_camera_sees_a_standing_person_only_with_feet_and_head_in_front_of_it_and_in_the_image():
    # Horizontal camera 1 m up looking along +y, 60° across: 4:3 image, so ±22.8° vertically.
    cam = Camera.look_at("c", 640, 480, position=(0, 0, 1), target=(0, 10, 1), hfov_deg=60)
    # 5 m ahead: feet 11.3° down, head (1.7 m) 8.0° up; 1.5 m ahead: feet 33.7° down, out of the
    # image; 5 m behind: the mirror image of "5 m ahead" would fall in the image, but it is behind.
    sees = cam.sees_standing([[0, 5], [0, 1.5], [0, -5]], 1.7)
    assert sees.tolist() == [True, False, False]
