"""Live sources without a network: files and image folders through the grab threads."""

import threading
import time

import cv2
import numpy as np
import pytest

from worldtrack.errors import InputError
from worldtrack.geometry.camera import Camera
from worldtrack.io.live import LiveSource, parse_source


def _folder(path, n, value=0):
    path.mkdir()
    for i in range(n):
        img = np.full((24, 32, 3), (value + 7 * i) % 256, np.uint8)
        cv2.imwrite(str(path / f"{i:04d}.png"), img)
    return path


def _cams(*ids):
    return {c: Camera.look_at(c, 32, 24, [0.0, 0.0, 3.0], [3.0, 0.0, 0.0], hfov_deg=60) for c in ids}


def test_a_slow_reader_gets_every_frame_of_a_file_with_its_time_and_the_end(tmp_path):
    src = LiveSource({"a": str(_folder(tmp_path / "a", 20))}, _cams("a"), fps=5.0, epoch=100.0,
                     buffer_frames=4)
    got = []

    def read():
        for i, t, frames in src:
            time.sleep(0.01)                  # slower than the grab thread: its queue fills up
            got.append((i, t, int(frames["a"].image[0, 0, 0]), frames["a"].index))
    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    reader.join(20)
    assert not reader.is_alive(), "the reader still waits after the file's end"
    assert [g[3] for g in got] == list(range(20))           # every frame, in order
    assert [g[1] for g in got] == pytest.approx([100.0 + k / 5.0 for k in range(20)])
    assert [g[2] for g in got] == [(7 * k) % 256 for k in range(20)]


def test_cameras_are_bundled_by_time_not_by_frame_number(tmp_path):
    a = _folder(tmp_path / "a", 10)
    b = _folder(tmp_path / "b", 5)
    src = LiveSource({"a": str(a)}, _cams("a"), fps=10.0)
    src.grabbers.update(LiveSource({"b": str(b)}, _cams("b"), fps=5.0).grabbers)
    src.cameras.update(_cams("b"))
    bundles = [(round(t, 3), sorted(f)) for _, t, f in src]
    # b (5 frames/s) joins a (10 frames/s) on every other bundle; the shorter input ends the run.
    assert bundles[:4] == [(0.0, ["a", "b"]), (0.1, ["a"]), (0.2, ["a", "b"]), (0.3, ["a"])]


def test_a_paced_file_starts_at_the_frame_due_now(tmp_path):
    src = LiveSource({"a": str(_folder(tmp_path / "a", 30))}, _cams("a"), fps=10.0, epoch=time.time() - 1.0,
                     pace=True)
    first = next(iter(src))
    src.close()
    assert 9 <= first[2]["a"].index <= 12 and first[1] == pytest.approx(src.grabbers["a"].epoch
                                                                         + first[2]["a"].index / 10.0)


def test_bad_sources_are_one_line(tmp_path):
    assert parse_source(" 2 ") == 2
    with pytest.raises(InputError, match="a: .*nothing: no such video file or folder"):
        LiveSource({"a": str(tmp_path / "nothing")}, _cams("a"))
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputError, match="folder holds no images"):
        LiveSource({"a": str(tmp_path / "empty")}, _cams("a"))
    with pytest.raises(InputError, match="no camera 'z' in the scene"):
        LiveSource({"z": "0"}, _cams("a"))
    src = LiveSource({"a": str(_folder(tmp_path / "big", 2))}, {"a": Camera.look_at("a", 64, 48, [0, 0, 3], [3, 0, 0],
                                                                                     hfov_deg=60)})
    with pytest.raises(InputError, match="frame 0 is 32x24 but the scene's camera is 64x48"):
        list(src)
