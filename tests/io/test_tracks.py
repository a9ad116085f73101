"""Track files: tracks.csv / gt.csv / MOTChallenge reading, streaming writer, MOT export."""

import enum
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from worldtrack.errors import InputError
from worldtrack.io.tracks import (TRACK_COLUMNS, TrackTable, TracksWriter, read_tracks, write_mot,
                                  write_tracks)

DATA = Path(__file__).resolve().parents[1] / "eval" / "data"


def _write(path: Path, text: str) -> Path:
    path.write_text(textwrap.dedent(text).lstrip("\n"), encoding="utf-8")
    return path


def test_tracks_csv_keeps_extra_columns_with_their_types_and_sorts_rows():
    t = read_tracks(DATA / "pred_small.csv")
    assert len(t) == 10
    assert t.columns[:5] == ["frame", "time", "id", "x", "y"]
    assert list(t.extra) == ["height", "width", "score", "mode", "flags", "sx"]
    assert t.frame.dtype == np.int64 and t.id.dtype == np.int64
    # Sorted by (frame, id).
    assert np.all(np.diff(t.frame * 100 + t.id) > 0)
    assert t.extra["sx"].dtype == float and np.all(t.extra["sx"] == 0.4)
    assert t.extra["mode"].dtype.kind == "U"
    last = t.select(t.id == 14)
    assert last.extra["flags"][0] == "unmeasurable;occluded"
    assert last.extra["mode"][0] == "capture"
    assert last.xy.tolist() == [[10.0, 10.0]]
    assert np.isclose(last.time[0], 0.4)


def test_gt_csv_reads_per_camera_columns_as_numbers():
    t = read_tracks(DATA / "gt_small.csv")
    assert len(t) == 10 and t.ids().tolist() == [1, 2] and t.frames().tolist() == [0, 1, 2, 3, 4]
    assert t.extra["vis_cam1"].dtype == float
    assert t.extra["vis_cam1"][(t.id == 2) & (t.frame == 2)][0] == 0.0
    assert t.extra["feet_cam1"][t.id == 2].tolist() == [0, 0, 0, 0, 0]
    assert t.extra["z_head"][t.id == 1][0] == pytest.approx(1.70)


def test_time_is_optional_and_unknown_text_columns_are_kept(tmp_path):
    p = _write(tmp_path / "t.csv", """
        id,frame,y,x,note
        2,1,0.5,1.5,hello
        1,1,0.25,1.0,
        """)
    t = read_tracks(p)
    assert np.all(np.isnan(t.time))
    assert t.id.tolist() == [1, 2]                  # sorted by id within the frame
    assert t.xy.tolist() == [[1.0, 0.25], [1.5, 0.5]]
    assert t.extra["note"].tolist() == ["", "hello"]


@pytest.mark.parametrize("ending", ["\r", "\r\n", "\n"])
def test_every_line_ending_reads_the_same_rows(tmp_path, ending):
    p = tmp_path / "t.csv"
    p.write_bytes(ending.join(["frame,id,x,y", "0,1,1.0,2.0", "", "1,1,1.5,2.5", ""]).encode())
    t = read_tracks(p)
    assert t.frame.tolist() == [0, 1] and t.xy.tolist() == [[1.0, 2.0], [1.5, 2.5]]


def test_the_fast_and_the_cell_by_cell_readers_give_the_same_table(tmp_path):
    from worldtrack.io.track_reader import _read_csv_cells, _read_csv_fast

    rng = np.random.default_rng(3)
    rows = [f"{f},{f / 7:.6f},{i},{x:.4f},{y:.4f},1.7,,{s:.3f},tracking,,note{i}"
            for f in range(40) for i, x, y, s in zip(range(1, 4), *rng.normal(size=(3, 3)))]
    text = "frame,time,id,x,y,height,width,score,mode,flags,note\n" + "\n".join(rows) + "\n"
    fast, cells = _read_csv_fast(text, "t.csv"), _read_csv_cells(text, "t.csv")
    assert fast.columns == cells.columns
    for c in fast.columns:
        a, b = fast.column(c), cells.column(c)
        assert a.dtype.kind == b.dtype.kind and (np.array_equal(a, b, equal_nan=True) if a.dtype.kind == "f"
                                                 else a.tolist() == b.tolist()), c


def test_excel_byte_order_mark_is_ignored(tmp_path):
    p = tmp_path / "bom.csv"
    p.write_bytes("\ufeffframe,id,x,y\n0,1,1.0,2.0\n".encode("utf-8"))
    assert read_tracks(p).xy.tolist() == [[1.0, 2.0]]


@pytest.mark.parametrize("text, message", [
    ("frame,id,height\n0,1,1.7\n", "missing columns: x, y"),
    ("frame,id,x,y\n0,1,1.0,2.0\n1,1,abc,2.0\n", "line 3, column x: expected a number, got 'abc'"),
    ("frame,id,x,y\n0,1,1.0,\n", "line 2, column y: expected a number, got ''"),
    ("frame,id,x,y\n0,1,nan,2.0\n", "line 2, column x: expected a finite number, got 'nan'"),
    ("frame,id,x,y\n0.5,1,1.0,2.0\n", "line 2, column frame: expected a whole number from 0 to 1000000000, got '0.5'"),
    ("frame,id,x,y\n0,0,1.0,2.0\n", "line 2, column id: expected a whole number from 1 to 1000000000, got '0'"),
    ("frame,id,x,y\n-1,1,1.0,2.0\n", "line 2, column frame: expected a whole number from 0 to 1000000000, got '-1'"),
    # Numbers that used to wrap or overflow: frame 1e30 and 2**63, id 1e19, x = 1e308.
    ("frame,id,x,y\n1e30,1,1.0,2.0\n", "line 2, column frame: expected a whole number from 0 to 1000000000, got '1e30'"),
    ("frame,id,x,y\n9223372036854775808,1,1.0,2.0\n", "line 2, column frame: expected a whole number from 0"),
    ("frame,id,x,y\n0,1e19,1.0,2.0\n", "line 2, column id: expected a whole number from 1 to 1000000000, got '1e19'"),
    ("frame,id,x,y\n0,1,1e308,2.0\n", "line 2, column x: expected metres within ±1e+06, got '1e308'"),
    ("frame,id,x,y\n0,1,1.0,2.0\x00\n", "holds NUL bytes"),
    ("frame,id,x,y\n0,1,1.0\n", "line 2: expected 4 fields (frame,id,x,y), got 3"),
    ("frame,id,x,y\n0,1,1.0,2.0\n0,2,1.0,2.0\n\n0,1,3.0,4.0\n",
     "line 5: duplicate row for frame 0, id 1 (first at line 2)"),
    ("", "empty file"),
    ("\n  \n", "empty file"),
    ("1,2,3,4,5\n", "line 1: no header and only 5 numeric columns"),
    ("frame,id,x,x,y\n", "line 1: repeated columns: x"),
    ("frame;id;x;y\n0;1;1.0;2.0\n", "missing columns: frame, id, x, y (the header is one column"),
])
def test_bad_files_raise_one_line_input_errors_naming_file_line_and_column(tmp_path, text, message):
    p = tmp_path / "bad.csv"
    p.write_text(text, encoding="utf-8")
    with pytest.raises(InputError) as e:
        read_tracks(p)
    assert str(e.value).startswith(f"{p}: {message}")
    assert "\n" not in str(e.value)


def test_missing_file_is_an_input_error(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        read_tracks(tmp_path / "nope.csv")


def test_header_only_file_is_an_empty_table(tmp_path):
    p = _write(tmp_path / "h.csv", "frame,time,id,x,y,height,width,score,mode,flags\n")
    t = read_tracks(p)
    assert len(t) == 0 and t.xy.shape == (0, 2) and "mode" in t.extra


def test_motchallenge_text_is_detected_and_made_zero_based(tmp_path):
    # frame,id,bb_left,bb_top,bb_width,bb_height,conf,x,y,z — frames from 1 in the file.
    p = _write(tmp_path / "res.txt", """
        1,3,-1,-1,-1,-1,0.9,1.5,2.5,0
        2,3,-1,-1,-1,-1,0.8,1.6,2.5,0
        1,1,10,20,30,40,1,-0.5,0.25,0
        """)
    t = read_tracks(p)
    assert t.frame.tolist() == [0, 0, 1]
    assert t.id.tolist() == [1, 3, 3]
    assert t.xy.tolist() == [[-0.5, 0.25], [1.5, 2.5], [1.6, 2.5]]
    assert t.extra["bb_left"].tolist() == [10, -1, -1]
    assert t.extra["conf"].tolist() == [1.0, 0.9, 0.8]
    assert np.all(np.isnan(t.time))


def test_motchallenge_image_only_file_is_refused():
    import motmetrics
    tud = Path(motmetrics.__file__).parent / "data" / "TUD-Campus" / "gt.txt"
    if not tud.exists():
        pytest.skip("motmetrics wheel without its test data")
    with pytest.raises(InputError, match="without world coordinates"):
        read_tracks(tud)


def test_mot_round_trip_preserves_zero_based_frames_and_ids(tmp_path):
    src = TrackTable.from_arrays(frame=[0, 0, 1, 7], id=[1, 2, 2, 9], x=[0.1, -2.5, 1 / 3, 4.0],
                                 y=[0.0, 1.25, 2 / 3, -1e-3], time=[0, 0, 0.1, 0.7],
                                 extra={"score": [0.9, 0.8, 0.7, 0.6]})
    out = tmp_path / "res.txt"
    write_mot(out, src)
    first = out.read_text().splitlines()[0].split(",")
    assert first[:2] == ["1", "1"]                   # 1-based frame in the file
    assert first[6] == "0.9"                         # conf from score
    back = read_tracks(out)
    assert back.frame.tolist() == [0, 0, 1, 7]
    assert back.id.tolist() == [1, 2, 2, 9]
    assert np.array_equal(back.xy, src.xy)           # shortest-repr floats read back exactly
    assert back.extra["z"].tolist() == [0, 0, 0, 0]


class Mode(enum.Enum):
    CAPTURE = "capture"
    TRACKING = "tracking"


class _Track:
    def __init__(self, id, x, y, **kw):
        self.id, self.x, self.y = id, x, y
        self.__dict__.update(kw)


def test_writer_writes_header_at_once_and_flushes_every_frame(tmp_path):
    p = tmp_path / "tracks.csv"
    w = TracksWriter(p, extra_columns=("sx", "sy"))
    assert p.read_text() == ",".join(TRACK_COLUMNS) + ",sx,sy\n"     # before any frame
    w.write(0, 0.0, [_Track(1, 1.0, 2.0, height=1.7, width=0.4, score=0.9, mode=Mode.CAPTURE,
                            flags=(), sx=0.4, sy=0.3)])
    # Still open: the row is already on disk.
    lines = p.read_text().splitlines()
    assert lines[1] == "0,0.0,1,1.0,2.0,1.7,0.4,0.9,capture,,,,,0.4,0.3"   # no vx, vy, speed given: empty
    w.write(1, 0.1, [{"id": 2, "xy": (3.0, 4.0), "mode": "tracking",
                      "flags": ["unmeasurable", "occluded"]}])
    assert p.read_text().splitlines()[2] == "1,0.1,2,3.0,4.0,,,,tracking,unmeasurable;occluded,,,,,"
    w.close()
    with pytest.raises(ValueError, match="after close"):
        w.write(2, 0.2, [])
    t = read_tracks(p)
    assert t.id.tolist() == [1, 2] and t.extra["flags"][1] == "unmeasurable;occluded"
    assert np.isnan(t.extra["height"][1])
    assert t.extra["sx"][0] == 0.4


def test_writer_rows_survive_a_hard_crash(tmp_path):
    # os._exit skips every Python-level buffer flush: only rows flushed by write() remain.
    p = tmp_path / "tracks.csv"
    code = textwrap.dedent(f"""
        import os
        from worldtrack.io.tracks import TracksWriter
        w = TracksWriter({str(p)!r})
        w.write(0, 0.0, [{{"id": 1, "x": 1.0, "y": 2.0}}])
        w.write(1, 0.1, [{{"id": 1, "x": 1.1, "y": 2.0}}])
        os._exit(1)
        """)
    r = subprocess.run([sys.executable, "-c", code], capture_output=True)
    assert r.returncode == 1
    t = read_tracks(p)
    assert t.frame.tolist() == [0, 1] and t.x.tolist() == [1.0, 1.1]


def test_writer_refuses_id_zero_and_clashing_extra_columns(tmp_path):
    with TracksWriter(tmp_path / "a.csv") as w:
        with pytest.raises(ValueError, match="ids start at 1"):
            w.write(0, 0.0, [{"id": 0, "x": 0.0, "y": 0.0}])
    with pytest.raises(ValueError, match="extra_columns"):
        TracksWriter(tmp_path / "b.csv", extra_columns=("x",))


def test_write_tracks_round_trips_a_table_with_extras(tmp_path):
    t = read_tracks(DATA / "gt_small.csv")
    write_tracks(tmp_path / "copy.csv", t)
    back = read_tracks(tmp_path / "copy.csv")
    assert back.columns == t.columns
    for c in t.columns:
        assert np.array_equal(back.column(c), t.column(c)), c
