"""The velocity gain along a lone camera's line of sight (:mod:`worldtrack.trackers.ellipsoid.ray_velocity`)."""

import numpy as np
from _ellipsoid_scenes import noise_backgrounds, one_camera_scene, two_camera_scene

from worldtrack.config import with_overrides
from worldtrack.foreground import make_foregrounds
from worldtrack.trackers.ellipsoid import EllipsoidConfig, EllipsoidTracker
from worldtrack.trackers.ellipsoid.ray_velocity import damped_velocity


def test_the_gain_is_smaller_along_the_ray_only():
    ray = np.array([0.6, 0.8])
    v = damped_velocity(np.zeros(2), np.array([2.0, 1.0]), 0.5, 0.25, ray)
    measured_along, v_along = 2.0 * 0.6 + 1.0 * 0.8, float(v @ ray)
    across = np.array([-0.8, 0.6])
    assert np.isclose(v_along, 0.5 * 0.25 * measured_along)
    assert np.isclose(v @ across, 0.5 * (np.array([2.0, 1.0]) @ across))
    assert np.allclose(damped_velocity(np.zeros(2), np.array([2.0, 1.0]), 0.5, 1.0, ray), [1.0, 0.5])


def _tracker(scene, along: float) -> EllipsoidTracker:
    bgs = noise_backgrounds(scene, np.random.default_rng(1))
    return EllipsoidTracker(scene, make_foregrounds(scene, bgs, "colour"),
                            with_overrides(EllipsoidConfig(), {"match.velocity_along_ray": along}))


def test_the_tracker_damps_a_lone_cameras_ray_and_nobody_by_default():
    tr = _tracker(one_camera_scene(), 0.0)
    p = tr.position_map.add(-1.0, 2.0, mode="tracking")
    p.t, p.prev_x, p.prev_y, p.seen_by = 1.0, -1.0, 2.0, ("cam",)
    cam = tr.views["cam"].camera
    ray = cam.floor_rays(np.array([[-1.0, 2.0]]), min_distance=0.3)[0][0]
    p.x, p.y = -1.0 + 0.1 * ray[0] - 0.1 * ray[1], 2.0 + 0.1 * ray[1] + 0.1 * ray[0]   # 0.1 m along, 0.1 across
    tr.life._update_velocity(p, 0.1)
    v = np.array([p.vx, p.vy])
    ray = cam.floor_rays(np.array([[p.x, p.y]]), min_distance=0.3)[0][0]     # the ray where they are now
    assert abs(v @ ray) < 1e-9 and np.linalg.norm(v) > 0.45                  # across it: half the move's speed
    assert _tracker(one_camera_scene(), 1.0).life.velocity_ray(p) is None
    # Two cameras that both showed the person: no lone camera, the same gain both ways.
    two = _tracker(two_camera_scene(), 0.0)
    p.seen_by = ("c1", "c2")
    assert two.life.velocity_ray(p) is None
    p.seen_by = ("c2",)
    assert np.allclose(two.life.velocity_ray(p), two.views["c2"].camera.floor_rays(np.array([[p.x, p.y]]), 0.3)[0][0])
