"""A live stream: ``ffmpeg`` sends a synthetic video over UDP on 127.0.0.1, ``worldtrack track``
reads it live (grab thread, capture time stamps), the sender stops and starts again, and the
stream is reconnected and tracked on. An HTTP stream (``ffmpeg`` as the HTTP server) is read,
dropped and reconnected by a camera's grab thread."""

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


def _tcp_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _serve_http(video, port: int, start_s: float, seconds: float) -> subprocess.Popen:
    """``ffmpeg`` as an HTTP server of one MPEG-TS stream (one client), from ``start_s`` of ``video``."""
    return subprocess.Popen(["ffmpeg", "-loglevel", "error", "-re", "-ss", str(start_s), "-t", str(seconds), "-i",
                             str(video), "-c:v", "mpeg2video", "-q:v", "2", "-g", "5", "-f", "mpegts", "-listen", "1",
                             f"http://127.0.0.1:{port}/west.ts"], stdin=subprocess.DEVNULL)


def test_an_http_stream_is_read_live_and_reconnected_after_the_server_restarts(two_rooms):
    if shutil.which("ffmpeg") is None:
        pytest.skip("ffmpeg is not installed (make test installs it: apt-get install ffmpeg)")
    from worldtrack.io.grab import Grabber
    port = _tcp_port()
    url = f"http://127.0.0.1:{port}/west.ts"
    server = _serve_http(two_rooms / "west.mp4", port, 0.0, 3.0)
    grabber = Grabber("west", url, backoff_s=(0.25, 1.0))
    frames: list = []
    take = _taker(grabber, frames)
    try:
        time.sleep(0.5)                                           # the server listens
        grabber.start()
        take(4.0)
        server.kill()                                             # (it has sent its 3 s by now)
        server.wait(10)
        take(1.5)                                                 # the server is gone: nothing comes
        down = len(frames)
        server = _serve_http(two_rooms / "west.mp4", port, 5.0, 3.0)
        take(5.0)
    finally:
        server.kill()
        grabber.stop()
        grabber.join(10)
    assert grabber.live and grabber.stats.reconnects >= 1 and grabber.stats.outage_s > 1.0, grabber.stats
    assert down >= 10 and len(frames) - down >= 10, (down, len(frames))
    stamps = np.array([t for _, t, _, _ in frames])
    assert np.all(np.diff(stamps) > 0) and np.all(np.diff([i for _, _, i, _ in frames]) > 0)
    # The capture time is this machine's clock when the frame was grabbed: before it was taken.
    assert all(0 <= got - t < 1.0 for got, t, _, _ in frames)
    assert all(img.shape == (240, 320, 3) for _, _, _, img in frames)


def _gst_python() -> str | None:
    """The system Python with GStreamer's RTSP server (PyGObject), not this virtualenv's."""
    import os
    for python in dict.fromkeys(filter(None, [shutil.which("python3", path=os.defpath), shutil.which("python3")])):
        probe = subprocess.run([python, "-c", "import gi; gi.require_version('GstRtspServer', '1.0')"],
                               capture_output=True)
        if probe.returncode == 0:
            return python
    return None


def _serve_rtsp(python: str, movie, port: int, tmp_path) -> subprocess.Popen:
    """GStreamer's RTSP server (``rtsp_server.py``) serving ``movie`` at rtsp://127.0.0.1:port/west."""
    from pathlib import Path
    log = tmp_path / f"rtsp{time.monotonic_ns()}.log"
    server = subprocess.Popen([python, str(Path(__file__).with_name("rtsp_server.py")), str(port), "west", str(movie)],
                              stdout=open(log, "w"), stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
    wait_until(lambda: "ready" in log.read_text() or server.poll() is not None, 20, what="the RTSP server")
    assert server.poll() is None, log.read_text()
    return server


def test_an_rtsp_camera_is_read_live_and_reconnected_after_the_server_restarts(two_rooms, tmp_path):
    """An IP camera's RTSP stream (GStreamer's RTSP server, RTP/JPEG made by ffmpeg from the synthetic
    video): the grab thread reads the video's own frames live, the server goes away, and the thread
    reconnects once it is back."""
    import cv2
    if shutil.which("ffmpeg") is None:
        pytest.skip("ffmpeg is not installed (make test installs it: apt-get install ffmpeg)")
    python = _gst_python()
    if python is None:
        pytest.skip("GStreamer's RTSP server is not installed (make test installs gir1.2-gst-rtsp-server-1.0)")
    from worldtrack.io.grab import Grabber
    movie = tmp_path / "west.avi"      # RTP/JPEG takes baseline JPEG with the standard Huffman tables
    subprocess.run(["ffmpeg", "-loglevel", "error", "-y", "-i", str(two_rooms / "west.mp4"), "-c:v", "mjpeg",
                    "-huffman", "default", "-pix_fmt", "yuvj420p", "-q:v", "3", str(movie)], check=True)
    port = _tcp_port()
    server = _serve_rtsp(python, movie, port, tmp_path)
    grabber = Grabber("west", f"rtsp://127.0.0.1:{port}/west", backoff_s=(0.25, 1.0))
    frames: list = []
    take = _taker(grabber, frames)
    try:
        grabber.start()
        take(3.0)
        server.kill()
        server.wait(10)
        take(1.5)                                                 # the camera is gone: nothing new comes
        down = len(frames)
        server = _serve_rtsp(python, movie, port, tmp_path)
        take(4.0)
    finally:
        server.kill()
        grabber.stop()
        grabber.join(10)
    assert grabber.stats.reconnects >= 1 and grabber.stats.outage_s > 1.0, grabber.stats
    assert down >= 10 and len(frames) - down >= 10, (down, len(frames))
    stamps = np.array([t for _, t, _, _ in frames])
    assert np.all(np.diff(stamps) > 0) and all(0 <= got - t < 1.0 for got, t, _, _ in frames)
    # The frames are the video's: each within a few grey levels of one of its frames (a stream
    # decoded wrongly, e.g. with the wrong Huffman tables, is off by tens).
    cap, video = cv2.VideoCapture(str(two_rooms / "west.mp4")), []
    while (got := cap.read())[0]:
        video.append(got[1].astype(np.float32))
    video = np.array(video)
    for _, _, _, img in frames[::5]:
        assert img.shape == (240, 320, 3)
        assert np.abs(video - img.astype(np.float32)).mean(axis=(1, 2, 3)).min() < 4.0


def test_a_stream_url_without_ffmpeg_in_opencv_is_one_clear_error(monkeypatch):
    import cv2

    from worldtrack.errors import InputError
    from worldtrack.io.grab import Grabber
    monkeypatch.setattr(cv2.videoio_registry, "hasBackend", lambda backend: backend != cv2.CAP_FFMPEG)
    with pytest.raises(InputError, match=r"^cam1: rtsp://127.0.0.1:8554/x: this OpenCV .* without FFmpeg"):
        Grabber("cam1", "rtsp://127.0.0.1:8554/x")
    Grabber("cam2", 0)         # a device index does not need FFmpeg (not started: no camera here)


def _taker(grabber, frames: list):
    """``take(seconds)``: append every new frame ``grabber`` hands over for that long to ``frames``, as
    (arrival time, *the grabber's item)."""
    taken = -1

    def take(seconds: float) -> None:
        nonlocal taken
        end = time.time() + seconds
        while time.time() < end:
            item = grabber.newest(taken, timeout=0.2)
            if item is not None:
                taken = item[1]
                frames.append((time.time(), *item))
    return take
