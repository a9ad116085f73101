"""A live stream: ``ffmpeg`` sends a synthetic video over UDP on 127.0.0.1, ``worldtrack track``
reads it live (grab thread, capture time stamps), the sender stops and starts again, and the
stream is reconnected and tracked on."""

from __future__ import annotations

import shutil
import signal
import socket
import subprocess
import time

import numpy as np
import pytest

from _mapkit import WORLDTRACK, wait_until
from worldtrack.io.tracks import read_tracks

pytestmark = pytest.mark.slow


def _udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _send(video, port: int, start_s: float, seconds: float) -> subprocess.Popen:
    return subprocess.Popen(["ffmpeg", "-loglevel", "error", "-re", "-ss", str(start_s), "-t", str(seconds), "-i",
                             str(video), "-c:v", "mpeg2video", "-q:v", "2", "-g", "5", "-f", "mpegts",
                             f"udp://127.0.0.1:{port}?pkt_size=1316"], stdin=subprocess.DEVNULL)


def test_a_udp_stream_is_tracked_live_and_reconnected_after_a_drop(two_rooms, tmp_path):
    if shutil.which("ffmpeg") is None:
        pytest.skip("ffmpeg is not installed (make test installs it: apt-get install ffmpeg)")
    port = _udp_port()
    out = tmp_path / "live"
    log = open(tmp_path / "track.log", "w")
    track = subprocess.Popen([*WORLDTRACK, "track", str(two_rooms / "scene.yaml"), "--video",
                              f"west=udp://127.0.0.1:{port}", "--background", f"west={two_rooms / 'west_background.png'}",
                              "--out", str(out), "--quiet", "--no-video"], stdout=subprocess.DEVNULL, stderr=log)
    sender = subprocess.Popen(["true"])
    try:
        wait_until(lambda: "tracker ready" in (tmp_path / "track.log").read_text(), 120, what="the tracker")
        time.sleep(0.5)                                           # listening
        sender = _send(two_rooms / "west.mp4", port, 0.0, 5.0)
        sender.wait(30)
        dropped_at = time.time()
        time.sleep(3.0)                                           # the stream is down (> read timeout)
        sender = _send(two_rooms / "west.mp4", port, 7.0, 5.0)    # and back, 7 s into the video
        restarted_at = time.time()
        sender.wait(30)
        time.sleep(0.5)
    finally:
        sender.kill()
        track.send_signal(signal.SIGINT)                          # Ctrl-C: outputs so far are kept
        track.wait(30)
    text = (tmp_path / "track.log").read_text()
    assert track.returncode == 130, text[-800:]
    line = next(ln for ln in text.splitlines() if ln.startswith("west: ") and "frames grabbed" in ln)
    grabbed, reconnects = int(line.split()[1]), int(line.split(", ")[2].split()[0])
    assert reconnects >= 1 and grabbed >= 50, line
    tracks = read_tracks(out / "tracks.csv")
    assert np.all(np.diff(np.unique(tracks.time)) > 0)            # capture times, increasing
    before, after = tracks.time < dropped_at, tracks.time > restarted_at
    assert before.sum() >= 10 and after.sum() >= 10, (before.sum(), after.sum())
    # Wherever it tracked, somebody was: each position within 0.5 m of a ground-truth position.
    gt = read_tracks(two_rooms / "gt.csv")
    d = np.linalg.norm(tracks.xy[:, None, :] - gt.xy[None, :, :], axis=2).min(axis=1)
    assert np.median(d) < 0.2 and np.mean(d < 0.5) > 0.9, (np.median(d), np.mean(d < 0.5))
