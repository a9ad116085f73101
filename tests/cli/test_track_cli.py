"""``worldtrack track`` and ``worldtrack demo`` end to end on files, and how they fail."""

import csv
import shutil

import cv2
import numpy as np
import pytest

from worldtrack.cli import main
from worldtrack.synth import make_scenario, write_sequence


@pytest.fixture(scope="module")
def sequence(tmp_path_factory):
    out = tmp_path_factory.mktemp("seq")
    write_sequence(make_scenario("two-crossing", size=(160, 120), frames=30, seed=1), out, png=True, progress=False)
    return out


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


def test_video_of_the_wrong_size_is_one_line_exit_2(sequence, tmp_path, capsys):
    wrong = tmp_path / "wrong"
    wrong.mkdir()
    for p in sorted((sequence / "cam1").glob("*.png"))[:3]:
        cv2.imwrite(str(wrong / p.name), cv2.resize(cv2.imread(str(p)), (320, 240)))
    shutil.copy(sequence / "cam1_background.png", tmp_path / "cam1_background.png")
    code = main(["track", str(sequence / "scene.yaml"), "--video", f"cam1={wrong}", "--out",
                 str(tmp_path / "o"), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert err[-1].startswith("error: cam1: ") and "is 320x240 but the scene's camera is 160x120" in err[-1]
    assert (tmp_path / "o" / "tracks.csv").read_text().startswith("frame,time,id")   # kept, valid


def test_corrupt_frame_stops_cleanly_keeping_earlier_frames(sequence, tmp_path, capsys):
    frames = tmp_path / "cam1"
    shutil.copytree(sequence / "cam1", frames)
    shutil.copy(sequence / "cam1_background.png", tmp_path / "cam1_background.png")
    (frames / "000012.png").write_bytes(b"not a png")
    out = tmp_path / "o"
    code = main(["track", str(sequence / "scene.yaml"), "--video", f"cam1={frames}", "--out", str(out), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and "frame 12 cannot be decoded" in err[-1] and "outputs up to frame 11 kept" in err[-1]
    written = {int(r["frame"]) for r in rows(out / "tracks.csv")}
    assert max(written) == 11
    assert (out / "floorplan.png").exists()


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
