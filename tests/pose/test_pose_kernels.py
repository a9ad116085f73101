"""The compiled kernels of worldtrack.pose agree with their NumPy references."""

import numpy as np
import pytest

from worldtrack.pose.cost import (BILINEAR, NEAREST_POSITIVE, EigenTemplateCost, SparseTemplate,
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


@pytest.mark.parametrize("mode", [BILINEAR, NEAREST_POSITIVE])
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
    v1, z1 = project_sample(images, INTR, T, tpl, mode)
    v2, z2 = project_sample_reference(images, INTR, T, tpl, mode)
    np.testing.assert_allclose(z1, z2)
    assert np.array_equal(np.isnan(v1), np.isnan(v2))
    np.testing.assert_allclose(np.nan_to_num(v1), np.nan_to_num(v2), rtol=1e-5, atol=1e-3)
    assert np.isnan(v1[0]).all() and np.isfinite(v1[1:]).any()


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
