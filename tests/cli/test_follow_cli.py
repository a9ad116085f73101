"""``worldtrack follow`` end to end on files written by ``worldtrack synth``, and how it fails."""

import csv
import shutil

import cv2
import numpy as np
import pytest

from worldtrack.cli import main
from worldtrack.synth import make_scenario, write_sequence

PARAMS = dict(others=1, clear_route=True, wb_jump_steps=300)


@pytest.fixture(scope="module")
def sequence(tmp_path_factory):
    out = tmp_path_factory.mktemp("follow_seq")
    write_sequence(make_scenario("follow-target", size=(160, 120), frames=30, seed=2, **PARAMS), out, png=True,
                   progress=False)
    return out


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def follow(sequence, out, *extra):
    return main(["follow", str(sequence / "scene.yaml"), "--rgb", str(sequence / "robot"), "--out", str(out),
                 "--quiet", *extra])


def test_follow_writes_target_commands_video_and_plan(sequence, tmp_path):
    out = tmp_path / "out"
    code = follow(sequence, out, "--disparity", str(sequence / "robot_disparity"), "--baseline", "0.12",
                  "--target", "1")
    assert code == 0
    target = rows(out / "target.csv")
    gt = {int(r["frame"]): (float(r["x"]), float(r["y"])) for r in rows(sequence / "gt.csv") if r["id"] == "1"}
    assert len(target) == 30 and sum(int(r["found"]) for r in target) >= 28
    err = [np.hypot(float(r["x"]) - gt[int(r["frame"])][0], float(r["y"]) - gt[int(r["frame"])][1]) for r in target]
    assert max(err) < 0.2
    assert {"D", "RBhat", "E", "alpha", "w_steps", "others"} <= set(target[0])
    commands = rows(out / "commands.csv")
    assert len(commands) == 30 and all(abs(float(c["v"])) <= 1.6 for c in commands)
    assert (out / "planview.png").stat().st_size > 10_000
    cap = cv2.VideoCapture(str(out / "follow.mp4"))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 30


def test_follow_from_depth_with_a_position_as_target(sequence, tmp_path):
    x, y = next((r["x"], r["y"]) for r in rows(sequence / "gt.csv") if r["id"] == "1" and r["frame"] == "0")
    code = follow(sequence, tmp_path / "o", "--depth", str(sequence / "robot_depth"), "--target", f"{x},{y}",
                  "--frames", "10", "--no-video")
    assert code == 0
    target = rows(tmp_path / "o" / "target.csv")
    assert len(target) == 10 and all(r["found"] == "1" for r in target)
    assert not (tmp_path / "o" / "follow.mp4").exists()


def test_follow_from_a_stereo_pair(tmp_path):
    """The right camera rendered 0.12 m to the right; StereoSGBM makes the disparity."""
    sc = make_scenario("follow-target", size=(160, 120), frames=12, seed=2, **PARAMS)
    left = tmp_path / "seq"
    write_sequence(sc, left, png=True, progress=False)
    right_sc = make_scenario("follow-target", size=(160, 120), frames=12, seed=2, noise=0.0, **PARAMS)
    poses = right_sc.rigs["robot"].poses
    poses[:] = [(R, t - np.array([0.12, 0.0, 0.0])) for R, t in poses]
    (tmp_path / "right").mkdir()
    rng = np.random.default_rng(9)
    for b in right_sc.frames():
        img = np.clip(b.views["robot"].image + rng.normal(0, 1.8, (120, 160, 3)), 0, 255).astype(np.uint8)
        cv2.imwrite(str(tmp_path / "right" / f"{b.frame:06d}.png"), img)
    code = main(["follow", str(left / "scene.yaml"), "--rgb", str(left / "robot"), "--right", str(tmp_path / "right"),
                 "--baseline", "0.12", "--target", "1", "--out", str(tmp_path / "o"), "--quiet", "--no-video"])
    assert code == 0
    assert sum(r["found"] == "1" for r in rows(tmp_path / "o" / "target.csv")) >= 10


def test_depth_of_another_size_is_one_line_and_exit_2(sequence, tmp_path, capsys):
    small = tmp_path / "small_depth"
    small.mkdir()
    for f in sorted((sequence / "robot_depth").iterdir())[:3]:
        img = cv2.imread(str(f), cv2.IMREAD_ANYDEPTH)
        cv2.imwrite(str(small / f.name), cv2.resize(img, (80, 60), interpolation=cv2.INTER_NEAREST))
    code = follow(sequence, tmp_path / "o", "--depth", str(small), "--target", "1")
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert err[-1].startswith("error: --depth") and "80x60 but the colour image is 160x120" in err[-1]
    assert (tmp_path / "o" / "target.csv").exists()                  # what was opened is closed, not lost


def test_missing_gains_column_is_one_line_and_exit_2(sequence, tmp_path, capsys):
    frames = rows(sequence / "frames.csv")
    bad = tmp_path / "frames.csv"
    keep = [c for c in frames[0] if not c.startswith("wb_")]
    with open(bad, "w", newline="") as f:
        w = csv.DictWriter(f, keep, extrasaction="ignore")
        w.writeheader()
        w.writerows(frames)
    code = follow(sequence, tmp_path / "o", "--disparity", str(sequence / "robot_disparity"), "--baseline", "0.12",
                  "--target", "1", "--frames-csv", str(bad))
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1
    assert err[0].startswith("error: ") and "no column 'wb_r_robot'" in err[0]


def test_target_id_not_present_is_one_line_and_exit_2(sequence, tmp_path, capsys):
    code = follow(sequence, tmp_path / "o", "--disparity", str(sequence / "robot_disparity"), "--baseline", "0.12",
                  "--target", "9")
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1
    assert err[0] == f"error: --target 9: no person 9 in {sequence / 'gt.csv'} at frame 0 (ids there: 1, 2)"
