"""``worldtrack track`` and ``worldtrack demo`` end to end on files, and how they fail."""

import csv
import shutil

import cv2
import numpy as np
import pytest

from worldtrack.cli import main


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def test_track_writes_tracks_videos_and_plan(sequence, tmp_path, capsys):
    out = tmp_path / "out"
    code = main(["track", str(sequence / "scene.yaml"), "--video", f"cam1={sequence / 'cam1'}",
                 "--video", f"cam2={sequence / 'cam2'}", "--out", str(out), "--quiet", "--json",
                 "--threshold", "20"])
    assert code == 0
    captured = capsys.readouterr()
    lines = [ln for ln in captured.out.splitlines() if ln.startswith("{")]
    assert len(lines) == 30                                    # one JSON line per frame
    table = rows(out / "tracks.csv")
    assert {r["id"] for r in table} and all(int(r["id"]) >= 1 for r in table)
    assert list(table[0].keys())[:10] == ["frame", "time", "id", "x", "y", "height", "width", "score", "mode", "flags"]
    # The two people are found and placed within 0.3 m of the truth by the last frame.
    gt = [r for r in rows(sequence / "gt.csv") if int(r["frame"]) == 29]
    last = [r for r in table if int(r["frame"]) == 29]
    for g in gt:
        d = min(np.hypot(float(r["x"]) - float(g["x"]), float(r["y"]) - float(g["y"])) for r in last)
        assert d < 0.3
    for cam in ("cam1", "cam2"):
        cap = cv2.VideoCapture(str(out / f"{cam}_annotated.mp4"))
        assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 30
    assert (out / "floorplan.png").stat().st_size > 10_000


def test_video_of_the_wrong_size_blames_the_video_before_any_output(sequence, tmp_path, capsys):
    wrong = tmp_path / "wrong"
    wrong.mkdir()
    for p in sorted((sequence / "cam1").glob("*.png"))[:3]:
        cv2.imwrite(str(wrong / p.name), cv2.resize(cv2.imread(str(p)), (320, 240)))
    code = main(["track", str(sequence / "scene.yaml"), "--video", f"cam1={wrong}", "--out",
                 str(tmp_path / "o"), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1
    assert err[0].startswith(f"error: cam1: {wrong}: frames are 320x240 but the scene's camera is 160x120")
    assert "--image-size 320x240" in err[0] and "background" not in err[0]
    assert not (tmp_path / "o" / "tracks.csv").exists()           # nothing written for a run that cannot start


def test_corrupt_frame_is_skipped_counted_and_tracking_goes_on(sequence, tmp_path, capsys):
    frames = tmp_path / "cam1"
    shutil.copytree(sequence / "cam1", frames)
    shutil.copy(sequence / "cam1_background.png", tmp_path / "cam1_background.png")
    (frames / "000012.png").write_bytes(b"not a png")
    (frames / "000020.png").write_bytes((sequence / "cam1" / "000020.png").read_bytes()[:200])   # truncated
    out = tmp_path / "o"
    code = main(["track", str(sequence / "scene.yaml"), "--video", f"cam1={frames}", "--out", str(out), "--quiet"])
    err = capsys.readouterr().err
    assert code == 0
    assert err.count("cannot be decoded; skipped") == 1                 # said once
    assert "cam1: 2 frame(s) could not be decoded and were skipped (12, 20)" in err
    written = {int(r["frame"]) for r in rows(out / "tracks.csv")}
    assert max(written) == 29 and not written & {12, 20}


def test_too_many_bad_frames_in_a_row_stop_cleanly_keeping_earlier_frames(sequence, tmp_path, capsys):
    frames = tmp_path / "cam1"
    shutil.copytree(sequence / "cam1", frames)
    shutil.copy(sequence / "cam1_background.png", tmp_path / "cam1_background.png")
    for k in range(15, 18):
        (frames / f"{k:06d}.png").write_bytes(b"not a png")
    out = tmp_path / "o"
    code = main(["track", str(sequence / "scene.yaml"), "--video", f"cam1={frames}", "--out", str(out), "--quiet",
                 "--max-bad-frames", "3"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and "3 frames in a row cannot be decoded (frames 15-17)" in err[-1]
    assert "outputs up to frame 14 kept" in err[-1]
    written = {int(r["frame"]) for r in rows(out / "tracks.csv")}
    assert max(written) == 14
    assert (out / "floorplan.png").exists()


def test_a_camera_that_runs_out_of_frames_is_dropped_and_the_others_go_on(sequence, tmp_path, capsys):
    short = tmp_path / "cam2"
    short.mkdir()
    for p in sorted((sequence / "cam2").glob("*.png"))[:18]:
        shutil.copy(p, short / p.name)
    shutil.copy(sequence / "cam2_background.png", tmp_path / "cam2_background.png")
    out = tmp_path / "o"
    code = main(["track", str(sequence / "scene.yaml"), "--video", f"cam1={sequence / 'cam1'}",
                 "--video", f"cam2={short}", "--out", str(out), "--quiet", "--threshold", "20"])
    err = capsys.readouterr().err
    assert code == 0
    assert f"cam2: {short}: no more frames after frame 17 (t = 1.700 s); going on with cam1" in err
    table = rows(out / "tracks.csv")
    assert max(int(r["frame"]) for r in table) == 29                 # all 30 frames of cam1 tracked
    cap = cv2.VideoCapture(str(out / "cam1_annotated.mp4"))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 30


@pytest.mark.parametrize("args, message", [
    (["--video", "cam9=x"], "no camera 'cam9' in scene"),
    (["--video", "cam1"], "expected CAMERA=PATH"),
    (["--video", "cam1=/nonexistent/video.mp4"], "no such file or folder"),
    (["--video", "cam1=V", "--init", "a,1,2"], "--init 'a,1,2': expected ID,X,Y"),
])
def test_bad_arguments_are_one_line_errors(sequence, tmp_path, capsys, args, message):
    args = [a.replace("V", str(sequence / "cam1")) if a == "cam1=V" else a for a in args]
    code = main(["track", str(sequence / "scene.yaml"), *args, "--out", str(tmp_path / "o"), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and err[-1].startswith("error: ") and message in err[-1]


def test_demo_synthesises_tracks_and_scores(tmp_path, capsys):
    code = main(["demo", "--out", str(tmp_path / "d"), "--size", "160x120", "--frames", "40"])
    out = capsys.readouterr().out
    assert code == 0
    mota = float(next(ln for ln in out.splitlines() if ln.strip().startswith("MOTA")).split()[-1])
    assert mota >= 0.5
    assert (tmp_path / "d" / "track" / "cam1_annotated.mp4").exists()
    assert (tmp_path / "d" / "track" / "floorplan.png").exists()
    assert (tmp_path / "d" / "synth" / "gt.csv").exists()
    import yaml
    info = yaml.safe_load((tmp_path / "d" / "track" / "run.yaml").read_text())
    assert info["config"]["method"] == "ellipsoid" and info["config"]["foreground"]["kind"] == "colour"
    assert info["inputs"]["synthetic"] == {"scenario": "two-crossing", "size": "160x120", "frames": 40, "seed": 0}
