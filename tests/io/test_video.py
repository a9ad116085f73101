"""The annotated-video writer: fragmented MP4 through FFmpeg (readable after a kill), OpenCV otherwise."""

import os
import shutil
import signal
import time

import cv2
import numpy as np
import pytest

from worldtrack.errors import InputError
from worldtrack.io.video import VideoWriter

needs_ffmpeg = pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="ffmpeg is not on PATH")


def frame(i: int, size=(241, 321)) -> np.ndarray:
    """A frame whose mean grey level says its number (i · 8)."""
    return np.full((*size, 3), 8 * i, np.uint8)


def read_back(path) -> list[float]:
    """The mean grey level of every frame OpenCV reads from ``path``."""
    cap = cv2.VideoCapture(str(path))
    means = []
    while True:
        ok, img = cap.read()
        if not ok:
            break
        means.append(float(img.mean()))
    cap.release()
    return means


@needs_ffmpeg
def test_ffmpeg_writes_every_frame_in_order_at_the_frames_own_size(tmp_path):
    path = tmp_path / "v.mp4"
    with VideoWriter(path, 10) as w:
        for i in range(25):
            w.write(frame(i))
    assert w.backend == "ffmpeg" and w.frames == 25
    means = read_back(path)
    assert len(means) == 25 and np.allclose(means, [8 * i for i in range(25)], atol=3)
    cap = cv2.VideoCapture(str(path))
    assert (cap.get(cv2.CAP_PROP_FRAME_WIDTH), cap.get(cv2.CAP_PROP_FRAME_HEIGHT)) == (321, 241)


@needs_ffmpeg
def test_a_killed_ffmpeg_leaves_the_fragments_written_so_far_playable(tmp_path):
    path = tmp_path / "v.mp4"
    w = VideoWriter(path, 10)
    for i in range(30):                              # three fragments of one second (10 frames)
        w.write(frame(i))
    w._process.stdin.flush()
    time.sleep(1.0)                                  # let FFmpeg encode what it has
    os.kill(w._process.pid, signal.SIGKILL)
    w._process.wait()
    w._process = None                                # (the writer's own close would report the kill)
    means = read_back(path)
    assert len(means) >= 20 and np.allclose(means, [8 * i for i in range(len(means))], atol=3)


def test_opencv_writes_when_asked_and_avi_is_always_opencv(tmp_path):
    for name, backend in (("v.mp4", "opencv"), ("v.avi", None)):
        with VideoWriter(tmp_path / name, 10, backend=backend) as w:
            for i in range(5):
                w.write(frame(i, (240, 320)))
        assert w.backend == "opencv" and len(read_back(tmp_path / name)) == 5


def test_asking_for_ffmpeg_without_it_is_a_clear_error(tmp_path, monkeypatch):
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(InputError, match="ffmpeg is not on PATH"):
        VideoWriter(tmp_path / "v.mp4", 10, backend="ffmpeg")
    assert VideoWriter(tmp_path / "v.mp4", 10).backend == "opencv"
