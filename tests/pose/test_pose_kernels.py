"""The compiled kernels of worldtrack.pose agree with their NumPy references."""

import numpy as np
import pytest

from worldtrack.pose.cost import (BILINEAR, DEPTH_BILINEAR, NEAREST_POSITIVE, EigenTemplateCost, SparseTemplate,
                                  _eigen_epsilon_kernel, project_sample, project_sample_reference)
from worldtrack.pose.render import Intrinsics, splat, splat_reference

INTR = Intrinsics(120.0, 110.0, 31.5, 23.5, 64, 48)


@pytest.mark.parametrize("footprint", [1, 2])
def test_splat_matches_reference(footprint):
    rng = np.random.default_rng(1)
    xyz = np.column_stack([rng.uniform(-0.3, 0.3, 3000), rng.uniform(-0.2, 0.2, 3000), rng.uniform(0.5, 2.0, 3000)])
    xyz[:5, 2] = -1.0                                        # behind the camera: never drawn
    a, b = splat(xyz, INTR, footprint), splat_reference(xyz, INTR, footprint)
    np.testing.assert_array_equal(a.index, b.index)
    np.testing.assert_array_equal(a.depth, b.depth)
    assert not np.isin(np.arange(5), a.index).any()


def test_splat_keeps_nearest_point():
    xyz = np.array([[0.0, 0.0, 2.0], [0.0, 0.0, 1.0], [0.0, 0.0, 3.0]])
    r = splat(xyz, INTR)
    assert r.index[24, 32] == 1 and r.depth[24, 32] == 1.0   # (cx, cy) rounds to pixel (32, 24)


@pytest.mark.parametrize("mode", [BILINEAR, NEAREST_POSITIVE, DEPTH_BILINEAR])
def test_project_sample_matches_reference(mode):
    rng = np.random.default_rng(2)
    images = rng.uniform(0, 255, (2, 48, 64)).astype(np.float32)
    images[:, 10:14, 20:30] = 0                              # no depth there (nearest mode → NaN)
    tpl = SparseTemplate(rng.normal(0, 0.05, (200, 3)), rng.integers(0, 2, 200), np.zeros(200))
    T = np.zeros((7, 2, 3, 4))
    T[..., :3, :3] = np.eye(3)
    T[..., 2, 3] = rng.uniform(0.4, 1.0, (7, 2))
    T[..., :2, 3] = rng.normal(0, 0.05, (7, 2, 2))
    T[0, :, 2, 3] = -0.5                                     # candidate behind the camera
    v1, z1 = project_sample(images, INTR, T, tpl, mode, max_step=60.0)       # some quads smooth, some edges
    v2, z2 = project_sample_reference(images, INTR, T, tpl, mode, max_step=60.0)
    np.testing.assert_allclose(z1, z2)
    assert np.array_equal(np.isnan(v1), np.isnan(v2))
    np.testing.assert_allclose(np.nan_to_num(v1), np.nan_to_num(v2), rtol=1e-5, atol=1e-3)
    assert np.isnan(v1[0]).all() and np.isfinite(v1[1:]).any()


def test_depth_bilinear_is_exact_on_a_plane_and_does_not_mix_across_an_edge():
    # A slanted plane (depth linear in u) with a step edge to a wall at 3 m: on the plane the
    # reading is the plane's depth at the sub-pixel position; next to the edge it is the nearest
    # pixel's, never a mixture of person and wall (which nearest-pixel reading of a 5 mm staircase
    # and plain bilinear reading across the edge both get wrong).
    u = np.arange(64, dtype=np.float32)
    depth = np.broadcast_to(1.0 + 0.002 * u, (48, 64)).copy()
    depth[:, 40:] = 3.0
    uv = np.array([[10.3, 20.6], [25.75, 5.25], [39.4, 12.0], [39.6, 12.0]])
    pts = np.column_stack([(uv[:, 0] - INTR.cx) / INTR.fx, (uv[:, 1] - INTR.cy) / INTR.fy, np.ones(4)])
    T = np.zeros((1, 1, 3, 4))
    T[0, 0, :3, :3] = np.eye(3)
    tpl = SparseTemplate(pts, np.zeros(4, int), np.zeros(4))
    v = project_sample(depth, INTR, T, tpl, DEPTH_BILINEAR)[0][0, 0]
    np.testing.assert_allclose(v[:2], 1.0 + 0.002 * uv[:2, 0], rtol=1e-6)
    np.testing.assert_allclose(v[2:], [1.0 + 0.002 * 39, 3.0], rtol=1e-6)
    np.testing.assert_array_equal(project_sample_reference(depth, INTR, T, tpl, DEPTH_BILINEAR)[0][0, 0], v)


def test_eigen_epsilon_kernel_matches_residuals():
    rng = np.random.default_rng(3)
    grey = rng.uniform(0, 255, (48, 64)).astype(np.float32)
    tpl = SparseTemplate(rng.normal(0, 0.05, (150, 3)), np.zeros(150, int), rng.uniform(50, 200, 150))
    cost = EigenTemplateCost(tpl, rng.normal(size=(150, 4)), grey, INTR, c=10.0)
    T = np.zeros((5, 1, 3, 4))
    T[..., :3, :3] = np.eye(3)
    T[..., 2, 3] = 0.6 + 0.1 * np.arange(5)[:, None]
    r = cost.residuals(T)
    vals, _ = project_sample(cost.images, INTR, T, tpl)
    np.testing.assert_allclose(_eigen_epsilon_kernel(vals[:, 0], cost.Q, cost.c), (r * r).sum(1), rtol=1e-9)


def test_colour_depth_epsilon_kernel_matches_residuals():
    from worldtrack.pose.cost import ColourDepthCost

    rng = np.random.default_rng(4)
    grey = rng.uniform(0, 255, (48, 64)).astype(np.float32)
    depth = rng.uniform(0.5, 1.0, (48, 64)).astype(np.float32)
    depth[:, :20] = 0                                                  # holes: ρ = 1
    col = SparseTemplate(rng.normal(0, 0.05, (120, 3)), np.zeros(120, int), rng.uniform(50, 200, 120))
    dep = SparseTemplate(rng.normal(0, 0.05, (80, 3)), np.zeros(80, int), np.zeros(80))
    T = np.zeros((6, 1, 3, 4))
    T[..., :3, :3] = np.eye(3)
    T[..., 2, 3] = 0.5 + 0.1 * np.arange(6)[:, None]
    for lam, d_img in ((0.9, depth), (0.3, depth), (0.5, None)):
        cost = ColourDepthCost(col, dep, grey, d_img, INTR, lam=lam)
        r = cost.residuals(T)
        np.testing.assert_allclose(cost.epsilon(T), (r * r).sum(1), rtol=1e-9)


def test_equal_shares_of_the_template():
    # The water-filling once let the remainder go negative on the last groups: with 128 points over
    # the body's 5 parts the right arm (parts 3, 4) got no colour point at all.
    from worldtrack.pose.template import _by_group, equal_shares

    np.testing.assert_array_equal(equal_shares([99, 77, 47, 58, 35], 128), [26, 26, 26, 25, 25])
    np.testing.assert_array_equal(equal_shares([3, 77, 10, 58, 2], 128), [3, 57, 10, 56, 2])
    np.testing.assert_array_equal(equal_shares([3, 4], 128), [3, 4])
    rng = np.random.default_rng(5)
    for _ in range(200):
        counts, n = rng.integers(0, 60, rng.integers(1, 7)), int(rng.integers(0, 200))
        q = equal_shares(counts, n)
        assert q.sum() == min(n, counts.sum()) and (q >= 0).all() and (q <= counts).all()
        full = q < counts                                     # groups not exhausted get equal shares ±1
        assert not full.any() or q[full].max() - q[full].min() <= 1
        assert not full.any() or q[full].min() >= q[~full].max(initial=0) - 1
    group = np.repeat(np.arange(5), [99, 77, 47, 58, 35])
    rc = np.column_stack([np.arange(len(group))] * 2)
    picked = group[_by_group(rc, rng.random(len(group)), group, 128)[:, 0]]
    np.testing.assert_array_equal(np.bincount(picked), [26, 26, 26, 25, 25])


def test_compiled_retract_and_state_pose_equal_their_numpy_references():
    from worldtrack.pose.models import quat_matrix, retract, retract_reference, state_pose

    rng = np.random.default_rng(4)
    X = np.concatenate([rng.normal(size=(40, 3)), rng.normal(size=(40, 4))], 1)
    X[:, 3:] /= np.linalg.norm(X[:, 3:], axis=1, keepdims=True)
    X[:, 3:] *= np.sign(X[:, 3:4])
    D = rng.normal(size=(40, 6)) * 0.3
    D[0, 3:] = [1.0, 1.0, 1.0]                                   # longer than 1: scaled to unit length
    np.testing.assert_allclose(retract(X, D, 0.1), retract_reference(X, D, 0.1), atol=1e-7)
    np.testing.assert_allclose(retract(X[1:], D[1:], 0.1), retract_reference(X[1:], D[1:], 0.1), atol=1e-13)
    np.testing.assert_allclose(retract(X[3], D[:5], 0.1), retract_reference(X[3], D[:5], 0.1), atol=1e-13)   # broadcast
    assert retract(X[3], D[5], 0.1).shape == (7,)
    R, t = state_pose((2 * X).reshape(4, 10, 7))                  # quaternions normalised first
    np.testing.assert_allclose(R.reshape(-1, 3, 3), quat_matrix(X[:, 3:]), atol=1e-13)
    np.testing.assert_allclose(t.reshape(-1, 3), 2 * X[:, :3])


def test_cull_and_bound_equals_its_numpy_reference():
    from worldtrack.pose.render import cull_and_bound, cull_and_bound_reference

    rng = np.random.default_rng(8)
    xyz = rng.normal([0, 0, 1.0], 0.3, (500, 3))
    xyz[:20, 2] = -0.5                                               # behind the camera
    nrm = rng.normal(size=(500, 3))
    intr = Intrinsics(500.0, 500.0, 320.0, 240.0, 640, 480)
    for normals in (nrm, None):
        a, box_a = cull_and_bound(xyz, normals, intr)
        b, box_b = cull_and_bound_reference(xyz, normals, intr)
        np.testing.assert_array_equal(a, b)
        np.testing.assert_allclose(box_a, box_b, rtol=1e-12)
    culled = (nrm * xyz).sum(1) > 0
    assert culled.sum() > 100 and (cull_and_bound(xyz, nrm, intr)[0][culled, 2] == -1).all()
    assert cull_and_bound(np.array([[0.0, 0.0, -1.0]]), None, intr)[1] is None


def test_posed_points_transform_and_cull_like_the_reference():
    from worldtrack.geometry.rotation import rodrigues
    from worldtrack.pose.render import cull_and_bound_reference, posed_points

    rng = np.random.default_rng(9)
    pts, nrm = rng.normal(0, 0.1, (400, 3)), rng.normal(size=(400, 3))
    R, t = rodrigues([0.3, -0.8, 0.2]), np.array([0.05, -0.02, 0.7])
    intr = Intrinsics(500.0, 500.0, 320.0, 240.0, 640, 480)
    ref = cull_and_bound_reference(pts @ R.T + t, nrm @ R.T, intr)[0]
    np.testing.assert_allclose(posed_points(pts, nrm, R, t), ref, atol=1e-14)
    assert 100 < (ref[:, 2] == -1).sum() < 300


def test_template_never_picks_a_point_of_unknown_appearance():
    """Where an occluder (NaN albedo) shows in single pixels among textured ones, the smoothed
    drawing is defined there; an extremum there must not make a template point of the occluder."""
    from worldtrack.pose.template import sparse_template_pixels

    rng = np.random.default_rng(10)
    g = np.arange(-0.05, 0.05, 0.0008)
    X, Y = np.meshgrid(g, g)
    pts = np.column_stack([X.ravel(), Y.ravel(), np.full(X.size, 0.5)])
    albedo = rng.uniform(50, 200, len(pts)).astype(np.float32)
    albedo[pts[:, 0] > 0.01] = np.nan                                 # the right part: an occluder
    sliver = rng.random(len(pts)) < 0.1                               # and occluder points scattered in front
    albedo[sliver] = np.nan
    pts[sliver, 2] -= 0.002
    intr = Intrinsics(600.0, 600.0, 80.0, 80.0, 160, 160)
    tp = sparse_template_pixels(albedo, pts, intr, 1024)
    assert len(tp.colour) > 100 and np.isfinite(albedo[tp.colour]).all()
