"""``worldtrack eval``: table, JSON, per-frame CSV, plot, and one-line errors with exit code 2."""

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from worldtrack.cli import main
from worldtrack.io.tracks import TrackTable, read_tracks, write_mot, write_tracks

DATA = Path(__file__).resolve().parents[1] / "eval" / "data"
GT = str(DATA / "gt_small.csv")
PRED = str(DATA / "pred_small.csv")


def _json(capsys, argv):
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


def test_ground_truth_against_itself_json(capsys):
    m = _json(capsys, ["eval", GT, GT, "--json"])
    assert m["mota"] == 1.0 and m["motp_m"] == 0.0 and m["idf1"] == 1.0
    assert m["num_switches"] == 0 and m["hota"] == pytest.approx(1.0) and m["hota_assa"] == pytest.approx(1.0)
    assert m["mean_error_m"] == 0.0 and m["num_position_pairs"] == 10


def test_table_shows_metrics_and_paper_errors(capsys):
    assert main(["eval", GT, PRED]) == 0
    out = capsys.readouterr().out
    lines = {ln.split("  ")[1].strip(): ln.rsplit("  ", 1)[1].strip()
             for ln in out.splitlines() if ln.startswith("  ")}
    assert lines["MOTA"] == "0.700"                          # see tests/eval/test_mot.py
    assert lines["IDF1"] == "0.700"
    assert lines["ID switches"] == "1"
    assert lines["mean error"] == f"{2.5 / 9:.3f} m"         # (5·0.3 + 2·0.4 + 2·0.1) / 9
    assert lines["mean |dX|"] == f"{1.5 / 9:.3f} m" and lines["mean |dY|"] == f"{1.0 / 9:.3f} m"
    m = _json(capsys, ["eval", GT, PRED, "--json"])            # HOTA and its parts, as computed
    assert lines["HOTA (DetA / AssA / LocA)"] == (f"{m['hota']:.3f} ({m['hota_deta']:.3f} / {m['hota_assa']:.3f} / "
                                                   f"{m['hota_loca']:.3f})")
    assert 0.2 < m["hota"] < 0.8 and m["hota"] == pytest.approx((m["hota_deta"] * m["hota_assa"]) ** 0.5, abs=0.05)


def test_swapped_copy_per_frame_csv_and_mot_input(tmp_path, capsys):
    gt = read_tracks(GT)
    swapped = TrackTable.from_arrays(gt.frame, np.where(gt.frame >= 2, 3 - gt.id, gt.id),
                                     gt.x, gt.y, time=gt.time)
    write_mot(tmp_path / "swapped.txt", swapped)               # PRED as MOTChallenge text
    per_frame = tmp_path / "pf.csv"
    m = _json(capsys, ["eval", GT, str(tmp_path / "swapped.txt"), "--json",
                       "--per-frame", str(per_frame)])
    assert m["num_switches"] == 2                                # each person changes id once
    rows = list(csv.DictReader(per_frame.open()))
    assert list(rows[0]) == ["frame", "num_gt", "num_pred", "matches", "misses", "fp",
                             "switches", "mean_error_m"]
    assert [int(r["switches"]) for r in rows] == [0, 0, 2, 0, 0]
    assert all(r["num_gt"] == r["num_pred"] == r["matches"] == "2" for r in rows)


def test_area_and_gate_options(tmp_path, capsys):
    # Only GT 1 at (0, 0) and prediction 11 at (0.3, 0) are inside this square.
    area = "--area=-1,-1,1,-1,1,1,-1,1"
    m = _json(capsys, ["eval", GT, PRED, "--json", area])
    assert m["num_objects"] == 5 and m["num_false_positives"] == 0 and m["mota"] == 1.0
    m = _json(capsys, ["eval", GT, PRED, "--json", area, "--gate", "0.2"])   # 0.3 m > 0.2 m
    assert m["num_matches"] == 0 and m["num_misses"] == 5


def test_plot_writes_a_png(tmp_path, capsys):
    out = tmp_path / "eval.png"
    assert main(["eval", GT, PRED, "--plot", str(out)]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    from matplotlib.image import imread
    h, w = imread(out).shape[:2]
    assert w > h > 300                                          # two panels side by side
    assert f"plot: {out}" in capsys.readouterr().out


def _one_line_error(capsys, argv) -> str:
    assert main(argv) == 2
    captured = capsys.readouterr()
    err = captured.err.strip()
    assert err.startswith("error: ") and "\n" not in err and "Traceback" not in err
    assert captured.out == ""
    return err


def test_missing_columns_is_one_line_exit_2(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("frame,id,height\n0,1,1.7\n")
    err = _one_line_error(capsys, ["eval", GT, str(bad)])
    assert err == f"error: {bad}: missing columns: x, y"


def test_non_numeric_value_is_one_line_exit_2(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("frame,time,id,x,y\n0,0.0,1,1.0,2.0\n1,0.1,1,abc,2.0\n")
    err = _one_line_error(capsys, ["eval", str(bad), GT])
    assert err == f"error: {bad}: line 3, column x: expected a number, got 'abc'"


@pytest.mark.parametrize("extra, fragment", [
    (["--gate", "-1"], "--gate: expected a positive distance"),
    (["--gate", "wide"], "--gate: expected a distance in metres, got 'wide'"),
    (["--area", "0,0,1,1"], "--area: expected x1,y1,x2,y2,... with 3 to 1000 finite (x, y) points, got 4"),
    (["--area", "0,0,1,x,1,1"], "no such file, and not numbers x1,y1,x2,y2"),
])
def test_bad_options_are_one_line_exit_2(capsys, extra, fragment):
    assert fragment in _one_line_error(capsys, ["eval", GT, PRED, *extra])


def test_missing_file_and_unwritable_output_are_one_line_exit_2(tmp_path, capsys):
    assert "no such file" in _one_line_error(capsys, ["eval", str(tmp_path / "nope.csv"), PRED])
    err = _one_line_error(capsys, ["eval", GT, PRED, "--per-frame",
                                   str(tmp_path / "no" / "dir" / "pf.csv")])
    assert "cannot write" in err


def test_header_only_prediction_scores_all_misses(tmp_path, capsys):
    empty = tmp_path / "tracks.csv"
    write_tracks(empty, TrackTable.from_arrays([], [], [], []))
    m = _json(capsys, ["eval", GT, str(empty), "--json"])
    assert m["num_misses"] == 10 and m["mota"] == 0.0 and m["num_predictions"] == 0
    assert m["mean_error_m"] is None                            # NaN -> null in JSON


def test_area_can_be_a_file_with_comments(tmp_path, capsys):
    # The square of test_area_and_gate_options, over two lines: only GT 1 and prediction 11 inside.
    area = tmp_path / "area.txt"
    area.write_text("# a square around GT 1 at (0, 0)\n-1,-1, 1,-1\n1,1,-1,1\n")
    m = _json(capsys, ["eval", GT, PRED, "--json", "--area", str(area)])
    assert m["num_objects"] == 5 and m["num_false_positives"] == 0 and m["mota"] == 1.0
    assert m == _json(capsys, ["eval", GT, PRED, "--json", "--area=-1,-1,1,-1,1,1,-1,1"])
