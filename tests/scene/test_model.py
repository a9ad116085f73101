"""Scene model: a turned box's footprint is where rays actually hit it."""

import numpy as np

from worldtrack.scene.model import Box


def test_yawed_box_footprint_agrees_with_the_ray_intersection():
    box = Box("desk", centre=np.array([1.0, -0.5, 0.4]), size=np.array([1.2, 0.6, 0.8]), yaw=0.4)
    fp = box.footprint
    centroid = fp.mean(axis=0)
    assert np.allclose(centroid, box.centre[:2])
    # Corners turned by +yaw: the first edge runs along (cos yaw, sin yaw) with the box's length.
    edge = fp[1] - fp[0]
    assert np.allclose(edge, 1.2 * np.array([np.cos(0.4), np.sin(0.4)]))
    towards_centre = (centroid - fp) / np.linalg.norm(centroid - fp, axis=1, keepdims=True)
    down = np.tile([0.0, 0.0, -1.0], (4, 1))
    z0 = 5.0
    inside = np.column_stack([fp + 0.01 * towards_centre, np.full(4, z0)])
    outside = np.column_stack([fp - 0.01 * towards_centre, np.full(4, z0)])
    s_in = np.array([box.intersect(o, down[:1])[0] for o in inside])
    s_out = np.array([box.intersect(o, down[:1])[0] for o in outside])
    assert np.all(np.isfinite(s_in))
    np.testing.assert_allclose(z0 - s_in, box.top, atol=1e-9)      # hits the top face
    assert box.top == 0.8
    assert np.all(np.isinf(s_out))
