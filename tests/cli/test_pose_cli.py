"""``worldtrack pose track`` end to end on a synthetic face, and its one-line errors."""

import csv

import cv2
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from worldtrack.cli import main
from worldtrack.pose import rotation_error_deg
from worldtrack.synth.faces import face_sequence, make_face

CUBE_OBJ = """v -0.04 -0.04 -0.04\nv 0.04 -0.04 -0.04\nv 0.04 0.04 -0.04\nv -0.04 0.04 -0.04
v -0.04 -0.04 0.04\nv 0.04 -0.04 0.04\nv 0.04 0.04 0.04\nv -0.04 0.04 0.04
f 1 2 3 4\nf 5 8 7 6\nf 1 5 6 2\nf 2 6 7 3\nf 3 7 8 4\nf 5 1 4 8
"""


@pytest.fixture(scope="module")
def face_dir(tmp_path_factory):
    root = tmp_path_factory.mktemp("face")
    seq = face_sequence(make_face(0), "sim1", seed=3, n_frames=5, size=(320, 240))
    (root / "rgb").mkdir()
    (root / "depth").mkdir()
    truth = []
    for k, f in enumerate(seq.frames()):
        cv2.imwrite(str(root / "rgb" / f"{k:04d}.png"), f.image)
        cv2.imwrite(str(root / "depth" / f"{k:04d}.png"), (f.depth * 1000).astype(np.uint16))
        truth.append((f.R, f.t))
    i = seq.intr
    (root / "K.yaml").write_text(f"fx: {i.fx}\nfy: {i.fy}\ncx: {i.cx}\ncy: {i.cy}\nwidth: 320\nheight: 240\n")
    M = np.eye(4)
    M[:3, :3], M[:3, 3] = truth[0]
    (root / "init.txt").write_text("\n".join(" ".join(f"{v:.9f}" for v in row) for row in M))
    (root / "cube.obj").write_text(CUBE_OBJ)
    return root, truth


def test_pose_track_writes_pose_csv_video_and_cost(face_dir, tmp_path, capsys):
    root, truth = face_dir
    out = tmp_path / "out"
    code = main(["pose", "track", "--model", "face", "--rgb", str(root / "rgb"), "--camera", str(root / "K.yaml"),
                 "--init", str(root / "init.txt"), "--out", str(out), "--candidates", "300", "--quiet"])
    assert code == 0
    with open(out / "pose.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 5 and list(rows[0])[:10] == ["frame", "time", "id", "tx", "ty", "tz", "qw", "qx", "qy", "qz"]
    for row, (R, t) in zip(rows, truth):
        R_est = Rotation.from_quat([float(row[k]) for k in ("qx", "qy", "qz", "qw")]).as_matrix()
        assert float(rotation_error_deg(R, R_est)) < 2.0
        assert np.linalg.norm([float(row[k]) - v for k, v in zip(("tx", "ty", "tz"), t)]) < 0.005
    assert rows[0]["cost"] == "" and 0 <= float(rows[-1]["cost"]) < 0.3
    assert float(rows[2]["time"]) == pytest.approx(2 / 30, abs=1e-6)
    cap = cv2.VideoCapture(str(out / "annotated.mp4"))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 5
    assert (out / "cost.png").stat().st_size > 1000


def _error(capsys, argv):
    code = main(argv)
    err = capsys.readouterr().err.strip()
    assert code == 2 and err.startswith("error: ") and "\n" not in err and "Traceback" not in err
    return err


def test_depth_and_colour_of_different_sizes(face_dir, tmp_path, capsys):
    root, _ = face_dir
    small = tmp_path / "depth"
    small.mkdir()
    for k in range(5):
        cv2.imwrite(str(small / f"{k:04d}.png"), np.full((120, 160), 600, np.uint16))
    err = _error(capsys, ["pose", "track", "--model", str(root / "cube.obj"), "--rgb", str(root / "rgb"),
                          "--depth", str(small), "--camera", str(root / "K.yaml"), "--init", "0,0,0.6,0,0,0",
                          "--out", str(tmp_path / "o"), "--quiet", "--no-video"])
    assert "depth is 160x120" in err and "320x240" in err


def test_unreadable_model(face_dir, tmp_path, capsys):
    root, _ = face_dir
    bad = tmp_path / "bad.obj"
    bad.write_bytes(b"v 0 0 zero\nf 1 2 3\n")
    err = _error(capsys, ["pose", "track", "--model", str(bad), "--rgb", str(root / "rgb"), "--camera",
                          str(root / "K.yaml"), "--init", "0,0,0.6,0,0,0", "--out", str(tmp_path / "o")])
    assert "bad.obj" in err and "OBJ" in err
    err = _error(capsys, ["pose", "track", "--model", str(tmp_path / "missing.obj"), "--rgb", str(root / "rgb"),
                          "--camera", str(root / "K.yaml"), "--init", "0,0,0.6,0,0,0", "--out", str(tmp_path / "o")])
    assert "missing.obj" in err and "cannot read" in err


def test_pose_behind_the_camera(face_dir, tmp_path, capsys):
    root, _ = face_dir
    for model in (str(root / "cube.obj"), "face"):
        err = _error(capsys, ["pose", "track", "--model", model, "--rgb", str(root / "rgb"), "--camera",
                              str(root / "K.yaml"), "--init", "0,0,-0.5,0,0,0", "--out", str(tmp_path / "o")])
        assert "behind the camera" in err


def test_bad_init_and_camera(face_dir, tmp_path, capsys):
    root, _ = face_dir
    err = _error(capsys, ["pose", "track", "--model", "face", "--rgb", str(root / "rgb"), "--camera",
                          str(root / "K.yaml"), "--init", "0,0,0.6", "--out", str(tmp_path / "o")])
    assert "x,y,z,rx,ry,rz" in err
    wrong = tmp_path / "K.yaml"
    wrong.write_text("fx: 300\nfy: 300\ncx: 160\ncy: 120\nwidth: 640\nheight: 480\n")
    err = _error(capsys, ["pose", "track", "--model", "face", "--rgb", str(root / "rgb"), "--camera", str(wrong),
                          "--init", str(root / "init.txt"), "--out", str(tmp_path / "o")])
    assert "640x480" in err and "320x240" in err


def test_pose_track_upper_body(tmp_path, capsys):
    from worldtrack.pose.body import limb_axes
    from worldtrack.pose import axis_angle_deg
    from worldtrack.synth.upper_body import body_sequence

    seq = body_sequence(3, n_frames=4, size=(640, 480))
    (tmp_path / "rgb").mkdir()
    (tmp_path / "depth").mkdir()
    frames = [seq.render(k) for k in range(4)]
    for k, f in enumerate(frames):
        cv2.imwrite(str(tmp_path / "rgb" / f"{k:03d}.png"), f.image)
        cv2.imwrite(str(tmp_path / "depth" / f"{k:03d}.png"), np.round(f.depth * 1000).astype(np.uint16))
    i = seq.intr
    (tmp_path / "K.yaml").write_text(f"K: [[{i.fx}, 0, {i.cx}], [0, {i.fy}, {i.cy}], [0, 0, 1]]\n")
    p0 = frames[0].params
    init = ",".join(f"{v:.6f}" for v in np.r_[p0[:3], np.degrees(p0[3:])])
    base = ["pose", "track", "--model", "upper-body", "--rgb", str(tmp_path / "rgb"), "--camera",
            str(tmp_path / "K.yaml"), "--out", str(tmp_path / "out"), "--quiet", "--candidates", "300"]
    err = _error(capsys, base + ["--init", init])
    assert "needs --depth" in err
    assert main(base + ["--init", init, "--depth", str(tmp_path / "depth")]) == 0
    with open(tmp_path / "out" / "pose.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 4 and "r_elbow_ry_deg" in rows[0]
    last = rows[-1]
    p = np.array([float(last[k]) for k in list(last)[3:17]])
    p[3:] = np.radians(p[3:])
    est, true = limb_axes(p[None], seq.true_model), frames[-1].axes
    errs = {n: float(axis_angle_deg(true[n], est[n][0])) for n in true}
    assert max(errs.values()) < 6.0, errs
    behind = ",".join(["0", "0", "-2"] + ["0"] * 11)
    assert "behind the camera" in _error(capsys, base + ["--init", behind, "--depth", str(tmp_path / "depth")])
