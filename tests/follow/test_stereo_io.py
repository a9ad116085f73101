"""StereoSGBM disparity, and reading depth / disparity / gains / poses per frame with clear errors."""

import cv2
import numpy as np
import pytest

from worldtrack.errors import InputError
from worldtrack.follow.stereo import StereoMatcher, disparity_to_depth
from worldtrack.geometry.camera import Camera
from worldtrack.geometry.rotation import rotation_to_rodrigues
from worldtrack.io.rgbd import RGBDSource, read_gains, read_poses

CAM = Camera.look_at("robot", 64, 48, position=(0, 0, 1.1), target=(1, 0, 1.1), hfov_deg=66)


def test_sgbm_finds_a_known_shift_and_depth_follows():
    rng = np.random.default_rng(0)
    left = cv2.GaussianBlur(rng.integers(0, 255, (120, 200)).astype(np.uint8), (3, 3), 0)
    right = np.zeros_like(left)
    right[:, :-12] = left[:, 12:]                                         # 12 px of disparity everywhere
    m = StereoMatcher(fx=240.0, baseline=0.12, min_depth=1.0)
    d = m.disparity(cv2.cvtColor(left, cv2.COLOR_GRAY2BGR), cv2.cvtColor(right, cv2.COLOR_GRAY2BGR))
    inner = d[20:100, 60:180]
    assert np.mean(np.abs(inner - 12.0) < 0.5) > 0.95
    np.testing.assert_allclose(disparity_to_depth(np.float32([[12.0]]), 240.0, 0.12), [[2.4]], rtol=1e-6)
    with pytest.raises(InputError, match="left image is 200x120 but right is"):
        m.disparity(left, right[:, :100])


def write_inputs(tmp_path, n=3, depth_size=(64, 48), gains=True, disparity=False):
    rgb = tmp_path / "robot"
    rgb.mkdir()
    folder = tmp_path / ("robot_disparity" if disparity else "robot_depth")
    folder.mkdir()
    for k in range(n):
        cv2.imwrite(str(rgb / f"{k:06d}.png"), np.full((48, 64, 3), 100, np.uint8))
        value = 16 * 12 if disparity else 2000                             # 12 px, or 2 m
        cv2.imwrite(str(folder / f"{k:06d}.png"), np.full(depth_size[::-1], value, np.uint16))
    cols = "frame,time,wb_r_robot,wb_b_robot" if gains else "frame,time,light_level,segment"
    (tmp_path / "frames.csv").write_text(cols + "\n" + "".join(f"{k},{k * 0.1:.1f},{500 + k},{520}\n" for k in range(n)))
    r = rotation_to_rodrigues(CAM.R)
    (tmp_path / "camera_poses.csv").write_text(
        "frame,time,camera,rvec_x,rvec_y,rvec_z,t_x,t_y,t_z\n"
        + "".join(f"{k},{k * 0.1},robot,{r[0]},{r[1]},{r[2]},{CAM.t[0] - k},{CAM.t[1]},{CAM.t[2]}\n" for k in range(n)))
    return rgb, folder


def test_source_reads_depth_gains_and_poses(tmp_path):
    rgb, depth = write_inputs(tmp_path)
    gains, times = read_gains(tmp_path / "frames.csv", "robot")
    poses = read_poses(tmp_path / "camera_poses.csv", "robot")
    frames = list(RGBDSource(CAM, rgb, depth=depth, gains=gains, times=times, poses=poses))
    assert len(frames) == 3
    frame, cam = frames[2]
    assert frame.t == pytest.approx(0.2) and frame.meta["wb_gains"] == (502.0, 520.0)
    np.testing.assert_allclose(frame.depth, 2.0)
    np.testing.assert_allclose(cam.t, CAM.t - [2, 0, 0], atol=1e-9)
    np.testing.assert_allclose(cam.R, CAM.R, atol=1e-9)


def test_disparity_needs_a_baseline_and_becomes_depth(tmp_path):
    rgb, disp = write_inputs(tmp_path, disparity=True)
    with pytest.raises(InputError, match="--baseline"):
        RGBDSource(CAM, rgb, disparity=disp)
    frame, _ = next(iter(RGBDSource(CAM, rgb, disparity=disp, baseline=0.12)))
    np.testing.assert_allclose(frame.depth, CAM.K[0, 0] * 0.12 / 12.0, rtol=1e-5)


def test_clear_errors_for_mismatched_or_missing_inputs(tmp_path):
    rgb, depth = write_inputs(tmp_path, depth_size=(32, 24), gains=False)
    with pytest.raises(InputError, match=r"--depth .*000000.png: frame 0 is 32x24 but the colour image is 64x48"):
        next(iter(RGBDSource(CAM, rgb, depth=depth)))
    with pytest.raises(InputError, match="no column 'wb_r_robot'"):
        read_gains(tmp_path / "frames.csv", "robot")
    with pytest.raises(InputError, match="no pose of camera 'left'"):
        read_poses(tmp_path / "camera_poses.csv", "left")
    with pytest.raises(InputError, match="exactly one of --depth, --disparity or --right"):
        RGBDSource(CAM, rgb)
