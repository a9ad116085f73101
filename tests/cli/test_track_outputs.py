"""What ``worldtrack track`` writes for daily use: velocities, valid JSON, MOTChallenge rows, output
folders that are not silently overwritten, and the checks of its options."""

import csv
import json

import numpy as np
import pytest

from worldtrack.cli import main


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def _strict_json(line):
    """json.loads that refuses NaN and Infinity (which Python's json writes unless told not to)."""
    def refuse(name):
        raise ValueError(f"not valid JSON: {name}")
    return json.loads(line, parse_constant=refuse)


@pytest.fixture(scope="module")
def run(sequence, tmp_path_factory):
    """One run with --json and --mot: (out folder, JSON lines)."""
    out = tmp_path_factory.mktemp("run") / "out"
    import contextlib
    import io
    stdout = io.StringIO()
    with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(io.StringIO()):
        code = main(["track", str(sequence / "scene.yaml"), "--video", f"cam1={sequence / 'cam1'}",
                     "--video", f"cam2={sequence / 'cam2'}", "--out", str(out), "--quiet", "--json",
                     "--threshold", "20", "--mot", str(out / "mot.txt"), "--mot-camera", "cam2", "--no-video"])
    assert code == 0
    return out, [ln for ln in stdout.getvalue().splitlines() if ln.startswith("{")]


def test_tracks_carry_velocity_and_speed_close_to_the_truth(run, sequence):
    out, _ = run
    table = rows(out / "tracks.csv")
    assert {"vx", "vy", "speed", "sigma"} <= set(table[0])
    gt = rows(sequence / "gt.csv")
    errors = []
    for r in table:
        f = int(r["frame"])
        if f < 15:          # velocities need a few frames to settle
            continue
        here = [g for g in gt if int(g["frame"]) == f]
        g = min(here, key=lambda g: np.hypot(float(g["x"]) - float(r["x"]), float(g["y"]) - float(r["y"])))
        assert float(r["speed"]) == pytest.approx(np.hypot(float(r["vx"]), float(r["vy"])), abs=2e-4)
        errors.append(abs(float(r["speed"]) - float(g["speed"])))
    assert errors and np.mean(errors) < 0.3            # people walk at 0.9 m/s
    times = [r["time"] for r in table]
    assert all(len(t.split(".")[-1]) <= 6 for t in times)   # to the microsecond, not 0.30000000000000004


def test_json_lines_are_valid_json_with_the_same_columns(run):
    out, lines = run
    assert len(lines) == 30
    frames = [_strict_json(ln) for ln in lines]
    first = next(f for f in frames if f["tracks"])
    assert {"id", "x", "y", "vx", "vy", "speed", "sigma"} <= set(first["tracks"][0])
    assert "support" not in first["tracks"][0] and "own_share" not in first["tracks"][0]


def test_json_refuses_nan_rather_than_writing_it():
    from worldtrack.pipeline import _json_rows
    line = json.dumps({"tracks": _json_rows([{"id": 1, "sigma": float("nan"), "x": float("inf")}])}, allow_nan=False)
    assert _strict_json(line)["tracks"][0] == {"id": 1, "sigma": None, "x": None}


def test_mot_rows_have_world_position_and_the_box_the_person_projects_to(run, sequence):
    from worldtrack.scene import load_scene

    out, _ = run
    cam = load_scene(sequence / "scene.yaml").cameras["cam2"]
    tracks = {(int(r["frame"]), int(r["id"])): r for r in rows(out / "tracks.csv")}
    mot = np.loadtxt(out / "mot.txt", delimiter=",", ndmin=2)
    assert len(mot) == len(tracks) and mot.shape[1] == 10
    for frame, tid, left, top, w, h, conf, x, y, z in mot:
        r = tracks[(int(frame) - 1, int(tid))]                      # MOT frames from 1
        assert (x, y, z) == pytest.approx((float(r["x"]), float(r["y"]), 0.0), abs=1e-4)
        if left == -1:
            continue
        # The body's middle projects inside the box (MOT pixels from 1).
        u, v = cam.project([[x, y, float(r["height"]) / 2]])[0] + 1
        assert left <= u <= left + w and top <= v <= top + h
        assert 2 < w < 160 and 2 < h < 120                          # a person, not the whole image
    assert (mot[:, 2] != -1).mean() > 0.9            # not -1 everywhere


def test_a_folder_holding_a_run_is_refused_and_overwrite_replaces_it(sequence, tmp_path, capsys):
    out = tmp_path / "o"
    args = ["track", str(sequence / "scene.yaml"), "--video", f"cam1={sequence / 'cam1'}", "--out", str(out),
            "--quiet", "--frames", "5"]
    assert main(args) == 0
    stale = out / "cam9_annotated.mp4"
    stale.write_bytes(b"old")
    (out / "notes.txt").write_text("mine")
    before = (out / "tracks.csv").read_text()
    capsys.readouterr()
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "holds the outputs of a previous run" in err[0] and "--overwrite" in err[0]
    assert (out / "tracks.csv").read_text() == before                  # nothing emptied
    assert main(args + ["--overwrite"]) == 0
    assert not stale.exists() and (out / "notes.txt").read_text() == "mine"


@pytest.mark.parametrize("flag, value, message", [
    ("--fps", "0", "--fps: expected a positive number such as 25, got '0'"),
    ("--fps", "-7", "--fps: expected a positive number such as 25, got '-7'"),
    ("--frames", "0", "--frames: expected a whole number > 0 such as 100, got '0'"),
    ("--max-bad-frames", "x", "--max-bad-frames: expected a whole number > 0"),
])
def test_bad_numbers_are_refused(sequence, tmp_path, capsys, flag, value, message):
    code = main(["track", str(sequence / "scene.yaml"), "--video", f"cam1={sequence / 'cam1'}", "--out",
                 str(tmp_path / "o"), flag, value])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and err == [f"error: {message}"] or (code == 2 and message in err[-1])
