"""White balance, illumination, Kinect-like depth and stereo disparity."""

import numpy as np
import pytest

from worldtrack.synth import make_scenario
from worldtrack.synth.photometry import Light, LightingSchedule, LightSegment, WhiteBalance
from worldtrack.synth.sensors import (SensorSpec, depth_to_png_mm, disparity_to_png, kinect_depth,
                                      occluded_in_second_view, stereo_measurement)


def test_auto_white_balance_jumps_only_past_its_threshold():
    wb = WhiteBalance(threshold=40)
    grey = np.array([100.0, 100.0, 100.0])
    assert wb.update(0, grey) == (512, 512)
    assert wb.update(1, np.array([100.0, 100.0, 95.0])) == (512, 512)        # 27 steps: holds
    r, b = wb.update(2, np.array([120.0, 100.0, 80.0]))                      # bluish → jump
    assert (r, b) == (640, 427)
    wb2 = WhiteBalance(mode="fixed", schedule={3: (300, 2000)})
    gains = [wb2.update(k, grey) for k in range(5)]
    assert gains[:3] == [(512, 512)] * 3 and gains[3] == (300, 1023) and gains[4] == (300, 1023)


def test_scheduled_white_balance_jumps_appear_in_frames_csv_rows():
    sc = make_scenario("follow-target", frames=20, seed=0, size=(80, 60), others=0, wb_jumps=(6, 14),
                       segments=("front",), white_balance="fixed")
    metas = [b.meta for b in sc.frames()]
    r = np.array([m["wb_r_robot"] for m in metas])
    b = np.array([m["wb_b_robot"] for m in metas])
    for g in (r, b):
        assert g.dtype.kind == "i" and g.min() >= 0 and g.max() <= 1023
    schedule = sc.rigs["robot"].white_balance.schedule
    changes = set(np.flatnonzero((np.diff(r) != 0) | (np.diff(b) != 0)) + 1)
    assert changes == {6, 14}
    for f, (rr, bb) in schedule.items():
        assert (r[f], b[f]) == (rr, bb)


def test_auto_white_balance_follows_the_light_colour_in_steps():
    sc = make_scenario("follow-target", frames=80, seed=1, size=(80, 60), others=1)
    metas = [b.meta for b in sc.frames()]
    r = np.array([m["wb_r_robot"] for m in metas])
    seg = [m["segment"] for m in metas]
    boundaries = [k for k in range(1, 80) if seg[k] != seg[k - 1]]
    assert len(boundaries) == 3
    jumps = np.flatnonzero(np.diff(r) != 0) + 1
    assert len(jumps) >= 1
    # The warm sun → bluish shade change makes the camera raise red gain at once.
    shade = boundaries[1]
    assert r[shade + 2] - r[shade - 1] > 40


def test_lighting_drift_and_segments():
    sched = LightingSchedule(Light(level=1.0), drift=0.05, drift_period=10.0,
                             segments=(LightSegment(4.0, "dim", level=0.5, direct=0.0),))
    levels = np.array([sched.at(t)[0].level for t in np.arange(0, 4, 0.1)])
    assert 0.94 < levels.min() < levels.max() < 1.06
    light, name = sched.at(5.0)
    assert name == "dim" and light.direct == 0.0 and light.level == pytest.approx(0.5 * (1 + 0.05 * np.sin(np.pi)))


def test_kinect_depth_quantised_invalid_below_min_and_in_projector_shadow():
    rng = np.random.default_rng(0)
    H, W = 40, 80
    depth = np.full((H, W), 2.0, np.float32)
    depth[:, 30:50] = 1.0                       # a near block in front of a wall
    depth[:5, :] = 0.3                          # too close
    spec = SensorSpec("rgbd", baseline=0.075, depth_step=0.005)
    fx = 60.0
    # The projector sits 7.5 cm to the right: it sees the wall shifted and the block's left side hidden.
    proj = np.full((H, W), 2.0, np.float32)
    shift_near, shift_far = fx * 0.075 / 1.0, fx * 0.075 / 2.0
    proj[:, int(round(30 - shift_near)):int(round(50 - shift_near))] = 1.0
    proj[:5, :] = 0.3
    z = kinect_depth(spec, depth, proj, fx, rng)
    valid = z > 0
    assert np.all(z[:5] == 0)
    np.testing.assert_allclose(z[valid] / 0.005, np.round(z[valid] / 0.005), atol=1e-3)
    assert np.all(np.abs(z[valid] - depth[valid]) < 0.03)
    # In the image, the wall just left of the block is hidden from the projector (to the right).
    band = ~valid[10:, 20:30].all(axis=0)
    assert 1 <= band.sum() <= int(np.ceil(shift_near - shift_far)) + 1 and band[-1]
    assert valid[10:, 35:45].all() and valid[10:, 50:].all()
    assert depth_to_png_mm(z).dtype == np.uint16 and depth_to_png_mm(z)[20, 70] in (1995, 2000, 2005)


def test_stereo_holes_where_texture_is_missing_or_occluded():
    rng = np.random.default_rng(1)
    H, W = 40, 100
    depth = np.full((H, W), 3.0, np.float32)
    depth[:, 40:60] = 1.5
    fx, B = 100.0, 0.12
    right = np.full((H, W), 3.0, np.float32)
    right[:, int(40 - fx * B / 1.5):int(60 - fx * B / 1.5)] = 1.5
    grey = rng.uniform(50, 200, (H, W)).astype(np.float32)
    grey[:, 75:95] = 120.0                      # a textureless patch
    spec = SensorSpec("stereo", baseline=B, speckle=0.0)
    disp, z = stereo_measurement(spec, depth, right, fx, grey, rng)
    assert np.all(disp[5:-5, 78:92] == 0)                       # no texture, no match
    occ, _ = occluded_in_second_view(depth, right, fx, B)
    assert occ[:, 36:40].all() and not occ[:, 28:34].any()      # background left of the block is hidden
    assert not occ[:, 40:75].any()
    assert np.all(disp[:, 36:40] == 0)
    ok = disp > 0
    np.testing.assert_allclose(disp[ok], fx * B / depth[ok], atol=0.6)
    np.testing.assert_allclose(disp[ok] * 16, np.round(disp[ok] * 16), atol=1e-3)
    np.testing.assert_allclose(z[ok], fx * B / disp[ok], rtol=1e-5)
    assert disparity_to_png(disp).max() == int(round(disp.max() * 16))


def test_stereo_scenario_has_holes_beside_people():
    sc = make_scenario("follow-target", frames=8, seed=0, size=(160, 120))
    v = list(sc.frames())[-1].views["robot"]
    person = v.instance > 0
    assert person.sum() > 200
    assert (v.disparity[person] > 0).mean() > 0.6
    # Left of each person's silhouette (occluded in the right view) there is a band of holes.
    left_edge = person[:, 1:] & ~person[:, :-1]
    rows, cols = np.nonzero(left_edge)
    beside = v.disparity[rows, np.maximum(cols - 1, 0)]
    assert (beside == 0).mean() > 0.7


def test_face_pose_depth_is_quantised_and_invalid_when_too_close():
    far = list(make_scenario("face-pose", frames=2, seed=0, size=(80, 60)).frames())[-1].views["kinect"]
    z = far.sensor_depth
    assert (z > 0).mean() > 0.5
    np.testing.assert_allclose(z / 0.005, np.round(z / 0.005), atol=1e-3)
    near = list(make_scenario("face-pose", frames=2, seed=0, size=(80, 60), distance=0.35).frames())[-1].views["kinect"]
    face = (near.instance > 0) & (near.depth < 0.48)
    assert face.sum() > 20 and np.all(near.sensor_depth[face] == 0)
