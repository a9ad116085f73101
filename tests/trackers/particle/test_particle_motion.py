"""The particle tracker's motion models (``motion.model``), chosen by name, and the depth along the
line of sight.

Small rendered scenes of :mod:`particle_scenes` (ellipsoid people over a textured floor, exact ground
truth); every filter is started on the truth with ``init_track`` and no detection, so what is
measured is the filter alone.
"""

from __future__ import annotations

import numpy as np
import pytest

from worldtrack.trackers.particle.motion import (HeightWalk, jitter_reflect, predict_state, predict_state_reference,
                                                 predict_walk, reflect_reference)

from particle_scenes import FPS, clouds, make_scene, run, tracker_for


def _errors(out, pid: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Floor errors (m) of track ``pid`` per frame and their components along the camera's line of sight."""
    err, along = [], []
    for _, truth, tracks in out:
        tr = {t.id: t for t in tracks}.get(pid)
        if tr is None:
            err.append(np.inf)
            along.append(np.inf)
            continue
        x, y = truth[0][:2]
        err.append(np.hypot(tr.x - x, tr.y - y))
        along.append(tr.y - y)               # the camera at (0, −1) looks along +y
    return np.array(err), np.array(along)


def test_state_velocity_moves_each_particle_by_its_own_velocity():
    """Without noise, x_t = x_{t−1} + v·dt exactly and v persists (constant velocity)."""
    scene = make_scene(entry=False)
    tracker, _ = tracker_for(scene, motion__model="state", motion__noise_xy=0.0, motion__noise_v=0.0,
                             detection__births="none")
    tracker.init_track(0.0, 3.0)
    (f,) = clouds(tracker)
    person = [tracker.position_map[1]]
    rng = np.random.default_rng(1)
    v = np.zeros_like(f.v)
    v[:, :2] = rng.uniform(-1, 1, (len(v), 2))
    f.v = v.copy()
    before = f.xyz.copy()
    tracker.motion.predict([f], person, 0.1)
    np.testing.assert_allclose(f.xyz[:, :2], before[:, :2] + 0.1 * v[:, :2], atol=1e-12)
    np.testing.assert_allclose(f.v, v, atol=1e-12)
    tracker.motion.predict([f], person, 0.2)
    np.testing.assert_allclose(f.xyz[:, :2], before[:, :2] + 0.3 * v[:, :2], atol=1e-12)


def test_state_velocity_noise_and_initial_spread():
    """The velocity walks by noise_v·√dt per step; new filters' velocities spread velocity_spread_mps."""
    scene = make_scene(entry=False)
    tracker, _ = tracker_for(scene, motion__model="state", motion__noise_xy=0.0, motion__noise_v=1.0,
                             motion__velocity_spread_mps=0.7, detection__births="none", tracking__particles=4000)
    tracker.init_track(0.0, 3.0)
    (f,) = clouds(tracker)
    assert f.v[:, :2].std(axis=0) == pytest.approx([0.7, 0.7], rel=0.05)
    assert np.all(f.v[:, 2] == 0)
    v0 = f.v.copy()
    tracker.motion.predict([f], [tracker.position_map[1]], 0.25)
    dv = f.v[:, :2] - v0[:, :2]
    assert dv.std(axis=0) == pytest.approx([0.5, 0.5], rel=0.05)      # 1.0 m/s/√s · √0.25 s
    # Other velocity models start from rest and keep no velocity state.
    t2, _ = tracker_for(scene, detection__births="none", motion__model="object")
    t2.init_track(0.0, 3.0)
    assert np.all(clouds(t2)[0].v == 0)


def towards_camera(t):
    """Walks straight at the camera (along its line of sight) at 1 m/s, from 5.5 m to 2.5 m."""
    return [(0.3, 5.5 - 1.0 * t)]


@pytest.mark.parametrize("velocity", ["state", "object"])
def test_walker_along_the_line_of_sight_is_followed(velocity):
    """The depth along the line of sight is the column's weak direction; the filter must keep up with
    a walker coming straight at the camera, started on the truth (no lag building up)."""
    scene = make_scene(entry=False)
    tracker, bgs = tracker_for(scene, motion__model=velocity, detection__births="none", split__enabled=False, merge__enabled=False)
    tracker.init_track(*towards_camera(0.0)[0], track_id=1)
    out = run(tracker, scene, bgs, towards_camera, int(3.0 * FPS))
    err, along = _errors(out)
    assert np.all(np.isfinite(err))
    assert np.mean(err) < 0.10 and np.max(err) < 0.25
    vy = [tracks[0].vy for _, _, tracks in out[10:]]
    assert np.median(vy) == pytest.approx(-1.0, abs=0.25)


def test_prediction_kernel_equals_numpy_reference():
    """The compiled prediction (``motion.model="state"``: the velocity walk, then ``x + a·noise + v·dt``)
    gives the NumPy code's values bit for bit, clipped speeds, stopped walks (scale 0) and the
    vertical component included."""
    rng = np.random.default_rng(3)
    for f, n in ((1, 7), (6, 500)):
        old = rng.normal(0, 3, (f, n, 3))
        v = rng.normal(0, 1.5, (f, n, 3))
        a, walk = rng.standard_normal((f, n, 3)), rng.standard_normal((f, n, 2))
        noise = np.array([0.4, 0.4, 0.3]) * np.sqrt(0.1)
        scale = rng.uniform(0, 0.4, f)
        scale[0] = 0.0
        v1, v2, x1, x2 = v.copy(), v.copy(), np.empty_like(old), np.empty_like(old)
        predict_state(old, a, noise, v1, walk, scale, 2.5, 0.1, x1)
        predict_state_reference(old, a, noise, v2, walk, scale, 2.5, 0.1, x2)
        assert (np.hypot(v2[..., 0], v2[..., 1]) >= 2.5 - 1e-12).any()     # some speeds were clipped
        assert (v2[..., 2] == 0).all() and not np.allclose(x2, old)
        np.testing.assert_array_equal(v1, v2)
        np.testing.assert_array_equal(x1, x2)


def test_height_walk_kernel_equals_numpy_reflection():
    """The heights' random walk folded into [lo, hi] (np.mod's sign rules, values far outside and
    on the ends included) is the NumPy expression's, bit for bit."""
    rng = np.random.default_rng(4)
    h, a = rng.uniform(-5, 8, (7, 1000)), rng.normal(0, 3, (7, 1000))
    h[0, :30], a[0, :30] = np.repeat([0.8, 1.9, 3.0], 10), 0.0             # on the ends and on 2·span
    for scale in (0.02, 0.3, 1.0):
        out = np.empty_like(h)
        jitter_reflect(h, a, scale, 0.8, 1.9, out)
        ref = reflect_reference(h + a * scale, 0.8, 1.9)
        np.testing.assert_array_equal(out, ref)
        assert out.min() >= 0.8 and out.max() <= 1.9 and ((h + a * scale < 0.8) | (h + a * scale > 1.9)).sum() > 1000


def test_predict_walk_is_prediction_then_height_walk():
    rng = np.random.default_rng(20)
    f, n = 3, 400
    old, v = rng.normal(0, 3, (f, n, 3)), rng.normal(0, 1.5, (f, n, 3))
    a, walk = rng.standard_normal((f, n, 3)), rng.standard_normal((f, n, 2))
    h, ha = rng.uniform(0.8, 1.9, (f, n)), rng.standard_normal((f, n))
    noise, scale = np.array([0.1, 0.1, 0.05]), np.array([0.3, 0.0, 0.2])
    v1, v2, x1, x2, h1 = v.copy(), v.copy(), np.empty_like(old), np.empty_like(old), np.empty_like(h)
    predict_walk(old, a, noise, v1, walk, scale, 2.5, 0.1, x1, HeightWalk(h, ha, 0.2, 0.8, 1.9, h1))
    predict_state_reference(old, a, noise, v2, walk, scale, 2.5, 0.1, x2)
    np.testing.assert_array_equal(x1, x2)
    np.testing.assert_array_equal(v1, v2)
    np.testing.assert_array_equal(h1, reflect_reference(h + ha * 0.2, 0.8, 1.9))
    assert not np.array_equal(h1, h)
    h2 = h.copy()
    predict_walk(old, a, noise, v.copy(), walk, scale, 2.5, 0.1, x1, HeightWalk(h, np.zeros(0), 0.2, 0.8, 1.9, h2))
    np.testing.assert_array_equal(h2, h)                  # no draws: the heights stay
