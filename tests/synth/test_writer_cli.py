"""Writing sequences to disk, byte-for-byte determinism, and the `worldtrack synth` command."""

import csv
from pathlib import Path

import cv2
import numpy as np

from worldtrack.cli import main
from worldtrack.scene import load_scene
from worldtrack.synth import make_scenario, write_sequence


def _files(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def test_same_seed_gives_the_same_bytes(tmp_path):
    a = write_sequence(make_scenario("two-crossing", frames=6, seed=7), tmp_path / "a", png=True, progress=False,
                       instances=True)
    b = write_sequence(make_scenario("two-crossing", frames=6, seed=7), tmp_path / "b", png=True, progress=False,
                       instances=True)
    fa, fb = _files(a), _files(b)
    assert set(fa) == set(fb)
    assert "cam1/000005.png" in fa and "cam2_instance/000000.png" in fa and "gt.csv" in fa
    assert all(fa[k] == fb[k] for k in fa), [k for k in fa if fa[k] != fb[k]]
    c = write_sequence(make_scenario("two-crossing", frames=6, seed=8), tmp_path / "c", png=True, progress=False)
    assert _files(c)["cam1/000005.png"] != fa["cam1/000005.png"]


def test_output_folder_contents_for_a_stereo_robot(tmp_path):
    sc = make_scenario("follow-target", frames=3, seed=0, size=(80, 60))
    out = write_sequence(sc, tmp_path / "f", png=False, progress=False)
    names = set(_files(out))
    assert {"scene.yaml", "README.txt", "gt.csv", "frames.csv", "camera_poses.csv", "robot.mp4",
            "robot_background.png", "robot_depth/000002.png", "robot_disparity/000002.png"} <= names
    scene = load_scene(out / "scene.yaml")
    np.testing.assert_allclose(scene.cameras["robot"].P, sc.camera_at("robot", 0).P, atol=1e-6)
    disp = cv2.imread(str(out / "robot_disparity/000002.png"), cv2.IMREAD_UNCHANGED)
    depth = cv2.imread(str(out / "robot_depth/000002.png"), cv2.IMREAD_UNCHANGED)
    assert disp.dtype == np.uint16 and depth.dtype == np.uint16 and disp.shape == (60, 80)
    assert np.array_equal(disp > 0, depth > 0)
    cap = cv2.VideoCapture(str(out / "robot.mp4"))
    n = 0
    while cap.read()[0]:
        n += 1
    assert n == 3
    with open(out / "frames.csv") as f:
        rows = list(csv.DictReader(f))
    assert [int(r["frame"]) for r in rows] == [0, 1, 2] and "wb_r_robot" in rows[0] and "robot_x" in rows[0]
    with open(out / "camera_poses.csv") as f:
        assert len(list(csv.DictReader(f))) == 3


def test_gt_csv_columns_and_rows(tmp_path):
    sc = make_scenario("entry", frames=40, seed=0, size=(64, 48))
    out = write_sequence(sc, tmp_path / "e", png=True, progress=False)
    with open(out / "gt.csv") as f:
        reader = csv.DictReader(f)
        assert reader.fieldnames == ["frame", "time", "id", "x", "y", "z_head", "height", "width", "speed",
                                     "vis_cam", "head_cam", "feet_cam"]
        rows = list(reader)
    present = sum(int(p.track.present[k]) for p in sc.people for k in range(40))
    assert len(rows) == present > 0
    assert all(float(r["time"]) == int(r["frame"]) / 10 for r in rows)


def test_pose_csv_for_pose_scenarios(tmp_path):
    out = write_sequence(make_scenario("upper-body", frames=2, size=(64, 48)), tmp_path / "u", png=True,
                         progress=False)
    with open(out / "pose.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 2 and "l_elbow_rz_deg" in rows[0] and "r_forearm_axis_z" in rows[0]
    z = cv2.imread(str(out / "kinect_depth/000001.png"), cv2.IMREAD_UNCHANGED)
    assert z.dtype == np.uint16 and np.all(z[z > 0] % 5 == 0)        # 5 mm steps, in mm


def test_cli_unknown_scenario_is_a_one_line_error(tmp_path, capsys):
    assert main(["synth", "nonexistent", "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: unknown scenario 'nonexistent'")
    assert main(["synth", "crowd", "--out", str(tmp_path / "x"), "--set", "peeple=3"]) == 2
    assert main(["synth", "crowd", "--out", str(tmp_path / "x"), "--size", "huge"]) == 2
    assert "error:" in capsys.readouterr().err


def test_cli_writes_a_sequence(tmp_path, capsys):
    out = tmp_path / "s"
    assert main(["synth", "crowd", "--out", str(out), "--frames", "2", "--size", "64x48", "--png",
                 "--set", "people=3", "--set", "cameras=1", "--no-progress"]) == 0
    assert (out / "c1" / "000001.png").exists() and (out / "c1_background.png").exists()
    assert "wrote 2 frames" in capsys.readouterr().out
    assert main(["synth", "--list"]) == 0
    assert "static-grid" in capsys.readouterr().out
