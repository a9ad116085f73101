"""One camera's floor geometry for the columns — lines of sight, floor distances, the surface a
column stands on, the columns beside a centre — in kernels against Camera.floor_rays."""

from __future__ import annotations

import numpy as np

from worldtrack.trackers.particle.floor import raster_contains
from worldtrack.trackers.particle.likelihood import CameraLikelihood
from worldtrack.trackers.particle.likelihood.camera import columns_beside_reference

from particle_scenes import CAM, CAM2, make_scene


def test_lines_of_sight_and_near_surface_agree_with_floor_rays():
    """The kernels' lines of sight equal Camera.floor_rays' (its fallback direction at the foot point
    and for NaN included), and the near-surface points ``xy − offset·along``."""
    cam = make_scene().cameras["cam"]
    cl = CameraLikelihood(cam)
    rng = np.random.default_rng(3)
    xy = np.column_stack([rng.normal(0, 3, 5000), rng.normal(2, 3, 5000)])
    xy[:3] = cam.centre[:2]                             # at the foot point
    xy[3] = np.nan
    along, _ = cam.floor_rays(xy)
    np.testing.assert_array_equal(cl.along(xy), along)
    np.testing.assert_array_equal(cl.near_surface(xy, 0.14), xy - 0.14 * along)
    assert np.array_equal(cl.along(xy[:1]), cam.floor_direction[None])


def test_column_stands_on_the_near_surface():
    """Each camera's column stands ``offset`` nearer to it than the particle, on the floor line from
    the camera's foot point."""
    scene = make_scene(cameras=(CAM, CAM2))
    xy = np.array([[0.0, 3.0], [1.0, 2.0]])
    for cid, cam in scene.cameras.items():
        c = cam.centre[:2]
        moved = CameraLikelihood(cam).near_surface(xy, 0.25)
        np.testing.assert_allclose(np.hypot(*(xy - c).T) - np.hypot(*(moved - c).T), 0.25, atol=1e-12)
        cross = (xy - c)[:, 0] * (moved - c)[:, 1] - (xy - c)[:, 1] * (moved - c)[:, 0]
        np.testing.assert_allclose(cross, 0.0, atol=1e-12)               # on the same line of sight


def test_floor_distances_equal_floor_rays():
    cam = make_scene().cameras["cam"]
    rng = np.random.default_rng(24)
    xy = np.column_stack([rng.normal(0, 3, 3000), rng.normal(2, 3, 3000)])
    xy[0] = cam.centre[:2]
    got = CameraLikelihood(cam).distances(xy)
    np.testing.assert_array_equal(got, cam.floor_rays(xy)[1])
    assert got[0] == 0.0 and got.max() > 5


def test_columns_beside_agree_with_floor_rays():
    """Where a filter learns its colours: the columns beside its centre (kernel against floor_rays)."""
    cam = make_scene().cameras["cam"]
    cl = CameraLikelihood(cam)
    rng = np.random.default_rng(9)
    xy = np.column_stack([rng.uniform(-3, 3, 300), rng.uniform(0, 7, 300)])
    xy[0] = cam.centre[:2]
    spread = rng.uniform(0.05, 0.2, 300)
    for offset in (0.14, 0.0):
        got = cl.beside(xy, offset, spread)
        np.testing.assert_array_equal(got, columns_beside_reference(cam, xy, offset, spread))
    assert np.allclose(np.hypot(*(got[1::3] - got[::3]).T), spread)


def test_kernels_read_the_floor_columns_of_xyz():
    """near_surface and raster_contains read (N, 3) positions as their first two columns."""
    scene = make_scene()
    cl = CameraLikelihood(scene.cameras["cam"])
    rng = np.random.default_rng(15)
    xyz = np.column_stack([rng.uniform(-4, 4, 500), rng.uniform(-1, 8, 500), rng.uniform(0, 2, 500)])
    np.testing.assert_array_equal(cl.near_surface(xyz, 0.14), cl.near_surface(xyz[:, :2].copy(), 0.14))
    raster = scene.walkable.raster(0.01)
    np.testing.assert_array_equal(raster_contains(raster, xyz), raster.contains(xyz[:, :2]))
