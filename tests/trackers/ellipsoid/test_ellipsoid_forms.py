"""Ellipses of ellipsoids: the compiled crops and owner maps against independently drawn conics."""

import numpy as np
import pytest
from _ellipsoid_scenes import lab_scene, person_mask

from worldtrack.geometry import quadric as q
from worldtrack.trackers.ellipsoid.args import DrawArgs, camera_args
from worldtrack.trackers.ellipsoid.forms import (ellipse_crop, ellipse_crop_reference, owner_crop, owner_map,
                                                 person_forms)


@pytest.fixture(scope="module")
def lab():
    return lab_scene()


@pytest.mark.parametrize("cam_id", ["cam1", "cam2"])
def test_ellipse_crop_equals_the_conic_mask(lab, cam_id):
    cam = lab.cameras[cam_id]
    args = camera_args(cam, 5.0)
    xy = np.array([[-1.0, 1.0], [-0.5, 2.0]])
    inner, _, box, valid, _ = person_forms(args, xy, np.full(2, 1.65), np.full(2, 0.4), DrawArgs(0.1, 0.0))
    grid = args.grid
    cen, rad = q.person_ellipsoid(xy, 1.65, 0.4)
    centre, axes, angle = q.ellipse_parameters(q.ellipsoid_conics(cam.P, cen, rad))
    if cam.has_distortion:
        u, v = grid[..., 0].astype(float), grid[..., 1].astype(float)
    else:
        v, u = np.mgrid[0:cam.height, 0:cam.width].astype(float)
    for k in range(2):
        crop = ellipse_crop(inner[k], box[k], grid, cam.has_distortion)
        np.testing.assert_array_equal(crop, ellipse_crop_reference(inner[k], box[k], grid, cam.has_distortion))
        full = person_mask(cam, xy[k], 1.65, 0.4).astype(bool)
        u0, u1, v0, v1 = box[k]
        assert (crop != full[v0:v1, u0:u1]).sum() <= 2       # float32 grid vs float64 at the edge
        assert crop.sum() == pytest.approx(full.sum(), abs=2)  # the box holds the whole ellipse
        # ... and the whole ring ellipse, semi-axes + 5 px, drawn independently of the kernel.
        du, dv = u - centre[k, 0], v - centre[k, 1]
        ca, sa = np.cos(angle[k]), np.sin(angle[k])
        ring = ((du * ca + dv * sa) / (axes[k, 0] + 5)) ** 2 + ((dv * ca - du * sa) / (axes[k, 1] + 5)) ** 2 < 1
        assert ring.sum() > full.sum() and ring[v0:v1, u0:u1].sum() == ring.sum()


@pytest.mark.parametrize("cam_id", ["cam1", "cam2"])
def test_owner_crop_equals_the_owner_map_and_the_masks(lab, cam_id):
    cam = lab.cameras[cam_id]
    args = camera_args(cam, 5.0)
    xy = np.array([[-1.0, 1.0], [-0.8, 1.2], [-0.5, 2.0]])    # the first two overlap in both views
    forms = person_forms(args, xy, np.full(3, 1.65), np.full(3, 0.4), DrawArgs(0.1, 0.0))
    box, grid = forms.box, args.grid
    full = owner_map(cam.height, cam.width, forms, grid, cam.has_distortion)
    # The reference, from independently drawn silhouettes: who covers each pixel.
    masks = np.stack([person_mask(cam, p, 1.65, 0.4).astype(bool) for p in xy])
    expected = np.where(masks.sum(0) > 1, -2, np.where(masks.any(0), masks.argmax(0), -1))
    assert (full != expected).sum() <= 6                     # float32 grid vs float64 at the edges
    assert (full == -2).sum() > 20                            # the overlap is there to be found
    for k in range(3):
        u0, u1, v0, v1 = box[k]
        np.testing.assert_array_equal(owner_crop(box[k], forms, grid, cam.has_distortion),
                                      full[v0:v1, u0:u1])
    window = np.array([box[0, 0], box[1, 1], box[1, 2], box[0, 3]])   # spans parts of both boxes
    np.testing.assert_array_equal(owner_crop(window, forms, grid, cam.has_distortion),
                                  full[window[2]:window[3], window[0]:window[1]])
