"""The image of an ellipsoid: dual conic vs the paper's appendix vs brute-force ray casting."""

import numpy as np
import pytest

from worldtrack.geometry import quadric as q
from worldtrack.geometry.camera import Camera
from worldtrack.geometry.raycast import ray_ellipsoid


def random_setup(rng, dist=False):
    """A camera looking at a random upright ellipsoid that lies fully in front of it."""
    while True:
        centre = np.array([rng.uniform(-2, 2), rng.uniform(-2, 2), rng.uniform(0.3, 1.2)])
        radii = np.array([rng.uniform(0.1, 0.5), rng.uniform(0.1, 0.5), rng.uniform(0.3, 1.0)])
        pos = centre + np.array([rng.uniform(-4, 4), rng.uniform(-4, 4), rng.uniform(0.5, 3)])
        look = centre + rng.normal(0, 0.3, 3)
        d = [rng.uniform(-0.2, 0.0), rng.uniform(0, 0.03), 0, 0, 0] if dist else None
        cam = Camera.look_at("r", 160, 120, pos, look, hfov_deg=rng.uniform(50, 80), dist=d)
        # Fully in front: every point of the ellipsoid has positive depth.
        depth_min = cam.depth(centre) - np.linalg.norm(radii * cam.optical_axis)
        dist_to_centre = np.linalg.norm(pos - centre)
        if depth_min > 0.3 and dist_to_centre > 1.2 * radii.max():
            return cam, centre, radii


def raycast_mask(cam, centre, radii):
    v, u = np.mgrid[0:cam.height, 0:cam.width]
    o, d = cam.rays(np.column_stack([u.ravel(), v.ravel()]).astype(float))
    return np.isfinite(ray_ellipsoid(o, d, centre, radii)).reshape(cam.height, cam.width)


def iou(a, b):
    return (a & b).sum() / max((a | b).sum(), 1)


def test_dual_conic_equals_paper_appendix():
    rng = np.random.default_rng(0)
    for _ in range(20):
        cam, centre, radii = random_setup(rng)
        ra, rb = radii[0], radii[2]
        c, r = q.person_ellipsoid([centre[:2]], 2 * rb, 2 * ra)
        C = q.ellipsoid_conics(cam.P, c, r)[0]
        # The paper normalises C34 = 1; its appendix holds for any scale.
        for P in (cam.P / cam.P[2, 3], cam.P):
            k = q.kato_conic_coefficients(P, [centre[:2]], ra, rb)
            Ck = -q.conic_matrix(k)[0]  # paper: discriminant positive inside; ours negative inside
            Ck /= np.linalg.norm(Ck)
            np.testing.assert_allclose(C, Ck, atol=1e-9)


@pytest.mark.parametrize("dist", [False, True])
def test_filled_ellipse_matches_ray_casting(dist):
    rng = np.random.default_rng(1 + dist)
    n_checked = 0
    for _ in range(25):
        cam, centre, radii = random_setup(rng, dist=dist)
        truth = raycast_mask(cam, centre, radii)
        if truth.sum() < 30:
            continue
        C = q.ellipsoid_conics(cam.P, [centre], [radii])[0]
        mask = q.ellipse_mask(C, (cam.height, cam.width), ideal_grid=cam.ideal_pixel_grid if dist else None)
        assert iou(mask, truth) >= 0.99
        n_checked += 1
    assert n_checked >= 15


def test_bbox_is_tight_and_ellipse_parameters_lie_on_the_outline():
    rng = np.random.default_rng(3)
    for _ in range(20):
        cam, centre, radii = random_setup(rng)
        dual = q.ellipsoid_dual_conics(cam.P, [centre], [radii])
        C = q.ellipsoid_conics(cam.P, [centre], [radii])
        u0, u1, v0, v1 = q.dual_conic_bbox(dual)[0]
        (cx, cy), (a, b), ang = [x[0] for x in q.ellipse_parameters(C)]
        t = np.linspace(0, 2 * np.pi, 400)
        pts = np.column_stack([cx + a * np.cos(t) * np.cos(ang) - b * np.sin(t) * np.sin(ang),
                               cy + a * np.cos(t) * np.sin(ang) + b * np.sin(t) * np.cos(ang)])
        # Every parametric point is on the conic...
        vals = q.conic_values(C[0], pts[:, 0], pts[:, 1])
        scale = np.abs(q.conic_values(C[0], np.array([cx]), np.array([cy])))
        assert np.abs(vals).max() < 1e-6 * scale.max()
        # ...and the bounding box touches the outline on all four sides.
        np.testing.assert_allclose([pts[:, 0].min(), pts[:, 0].max(), pts[:, 1].min(), pts[:, 1].max()],
                                   [u0, u1, v0, v1], atol=0.05)
        assert a >= b > 0


def test_person_ellipsoid_is_the_papers():
    c, r = q.person_ellipsoid([[1.0, 2.0]], 1.65, 0.40)
    np.testing.assert_allclose(c, [[1.0, 2.0, 0.825]])
    np.testing.assert_allclose(r, [[0.2, 0.2, 0.825]])
