"""The point likelihood (eq. 7): the compiled kernel against its NumPy reference."""

from __future__ import annotations

import numpy as np

from worldtrack.trackers.particle.likelihood import CameraLikelihood, owner_image, point_values_reference

from particle_scenes import thresholded_difference, H, W, make_scene


def test_point_kernel_agrees_with_reference():
    cam = make_scene().cameras["cam"]
    rng = np.random.default_rng(2)
    F = thresholded_difference(rng.uniform(0, 100, (H, W)).astype(np.float32), 30.0)
    xyz = np.column_stack([rng.uniform(-3.5, 3.5, 5000), rng.uniform(-1.5, 7.0, 5000), rng.uniform(-0.5, 2.5, 5000)])
    owner = owner_image((H, W), [(50, 150, 50, 150)])
    for box in (None, (50, 150, 50, 150)):
        v, s = CameraLikelihood(cam).point(F, xyz, owner, box)
        rv, rs = point_values_reference(cam, F, xyz, owner, box)
        np.testing.assert_array_equal(s, rs)
        np.testing.assert_array_equal(v, rv)
        assert (v > 0).sum() > 500 and s.sum() > 1000
    # In the box of another object (the owner image without its own box) every value is 0.
    u, v_ = np.round(cam.project(xyz)).T
    in_box = s & (u >= 50) & (u < 150) & (v_ >= 50) & (v_ < 150)
    assert in_box.sum() > 100
    assert np.all(CameraLikelihood(cam).point(F, xyz, owner, None)[0][in_box] == 0.0)
