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


def test_the_share_follows_how_well_e_places_the_person_along_the_ray():
    from worldtrack.trackers.ellipsoid.ray_velocity import curvature_share
    from worldtrack.trackers.ellipsoid.uncertainty import MIN_CURVATURE, SCORE_NOISE
    sure = 0.1
    assert curvature_share(1e6, sure) == 1.0                       # a sharp peak: the full gain
    c = SCORE_NOISE ** 2 / 0.2 ** 2                                # σ 0.2 m: (0.1 / 0.2)² = 1/4
    assert np.isclose(curvature_share(c, sure), 0.25)
    flat = curvature_share(0.0, sure)                              # flat (σ capped at κ / √c_min)
    assert np.isclose(flat, sure ** 2 * MIN_CURVATURE / SCORE_NOISE ** 2) and flat < 0.15
    assert curvature_share(-5.0, sure) == flat


def test_a_move_along_a_flat_ray_moves_the_person_but_not_their_velocity():
    from worldtrack.trackers.ellipsoid.uncertainty import Components
    scene = two_camera_scene()
    tr = EllipsoidTracker(scene, make_foregrounds(scene, noise_backgrounds(scene, np.random.default_rng(1)), "colour"),
                          with_overrides(EllipsoidConfig(), {"match.velocity_sure_sigma_m": 0.1}))
    p = tr.position_map.add(-1.0, 2.0, mode="tracking")
    p.t, p.prev_x, p.prev_y, p.seen_by = 1.0, -1.0, 2.0, ("c1", "c2")     # two cameras: no lone ray
    along = np.array([0.6, 0.8])
    across = np.array([-0.8, 0.6])
    p.x, p.y = -1.0 + 0.1 * along[0] + 0.1 * across[0], 2.0 + 0.1 * along[1] + 0.1 * across[1]
    for curvature, share in ((0.0, 0.1 ** 2 * 0.8 / 0.26 ** 2), (1e6, 1.0)):
        tr.uncertainty.components[p] = Components(np.array([curvature, 50.0]), along, False, False, 1.0)
        p.vx = p.vy = 0.0
        tr.life._update_velocity(p, 0.1)
        v = np.array([p.vx, p.vy])
        assert np.isclose(v @ across, 0.5)                                   # across: half the move's speed
        assert np.isclose(v @ along, 0.5 * share)                            # along: that times the share
    # Off (the default), or before E's curvature was first read: the same gain both ways.
    del tr.uncertainty.components[p]
    assert tr.life.velocity_flat(p) is None
    assert _tracker(two_camera_scene(), 1.0).life.velocity_flat(p) is None
