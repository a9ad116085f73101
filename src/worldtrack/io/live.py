"""Live cameras: a grab thread per camera, capture time stamps, reconnection, bundles by time.

``--video CAM=0`` (a device index), ``CAM=rtsp://…``, ``CAM=http://…``, ``CAM=udp://…`` (any URL
OpenCV's FFmpeg backend opens) and video files all come through :class:`LiveSource`:

* one :class:`Grabber` thread per camera reads frames as they come and stamps each with its capture
  time (the wall clock when it was grabbed, seconds); a live stream keeps only the newest frame (a
  frame the tracker had no time for is counted as dropped), a file keeps every frame;
* a live stream that stops (the sender restarts, the network drops) is reopened with back-off
  (0.5 s, doubling, at most 8 s); the time without signal and the reconnections are counted;
* frames of several cameras are put together by capture time, not by frame number: a bundle holds
  each camera's frame nearest in time, and a camera with nothing recent is left out of it.

Streams are probed for half a second before the first frame (FFmpeg's ``analyzeduration``; set
``OPENCV_FFMPEG_CAPTURE_OPTIONS`` to change it, e.g. ``rtsp_transport;tcp`` for RTSP over TCP).
The capture time is this machine's clock when the frame was grabbed (it includes the network and
decoding delay); a sender's own wall clock would need PyAV and is not read.

A video file played as a camera (``pace=True``, what a worker of the shared map does) has capture
times ``epoch + i / fps`` and is released frame by frame at those wall-clock times, starting at
the frame due now; otherwise it is read as fast as the tracker goes, with ``t = epoch + i / fps``.

>>> parse_source("0"), parse_source("rtsp://cam.local/stream"), parse_source("clip.mp4")
(0, 'rtsp://cam.local/stream', 'clip.mp4')
>>> is_live(0), is_live("udp://127.0.0.1:5000"), is_live("clip.mp4")
(True, True, False)
"""

from __future__ import annotations

import time
from typing import Callable, Iterator, Mapping

import numpy as np

from worldtrack.errors import InputError
from worldtrack.geometry.camera import Camera
from worldtrack.io.grab import (FFMPEG_PROBE, STREAM_SCHEMES, GrabStats, Grabber, check_source, is_live,  # noqa: F401
                                parse_source)
from worldtrack.trackers.base import Frame

class LiveSource:
    """Frame bundles ``(index, t, {camera_id: Frame})`` from live cameras and files, by capture time.

    Parameters
    ----------
    sources : {camera_id: device index, stream URL or file path}
    cameras : the scene's cameras (image sizes are checked)
    fps : frame rate of files' time stamps (default: their headers)
    epoch, pace : see :class:`Grabber` (files only)
    sync_s : how long a bundle waits for the other live cameras after the first new frame (s)
    stop : stop after this many bundles
    """

    def __init__(self, sources: Mapping[str, int | str], cameras: Mapping[str, Camera], fps: float | None = None,
                 epoch: float = 0.0, pace: bool = False, sync_s: float = 0.05, stop: int | None = None,
                 clock: Callable[[], float] = time.time, **grab_options):
        unknown = [c for c in sources if c not in cameras]
        if unknown:
            raise InputError(f"--video {unknown[0]}=…: no camera {unknown[0]!r} in the scene "
                             f"(cameras: {', '.join(cameras)})")
        if not sources:
            raise InputError("no video given (use --video CAMERA=PATH, =DEVICE or =URL)")
        self.cameras = {c: cameras[c] for c in sources}
        self.grabbers = {c: Grabber(c, s, fps=fps, epoch=epoch, pace=pace, clock=clock, **grab_options)
                         for c, s in sources.items()}
        self.live = any(g.live for g in self.grabbers.values())
        rates = [g.fps for g in self.grabbers.values() if g.fps]
        self.fps = float(fps) if fps else (rates[0] if rates else 10.0)
        self.sync_s, self.stop_after = sync_s, stop
        self.length = None

    def stats(self) -> dict[str, GrabStats]:
        """Each camera's counters (frames, dropped, reconnects, seconds without signal)."""
        return {c: g.stats for c, g in self.grabbers.items()}

    def start(self) -> None:
        """Start the grab threads (iterating starts them too): a live camera's frames, and a paced
        file's clock, run from now."""
        for g in self.grabbers.values():
            if not g.is_alive() and not g.ended:
                g.start()

    def __iter__(self) -> Iterator[tuple[int, float, dict[str, Frame]]]:
        self.start()
        try:
            bundles = self._live_bundles() if self.live else self._file_bundles()
            for i, (t, bundle) in enumerate(bundles):
                if self.stop_after is not None and i >= self.stop_after:
                    return
                for cid, frame in bundle.items():
                    self._check_size(cid, frame.image, frame.index)
                yield i, t, bundle
        finally:
            self.close()

    def close(self) -> None:
        """Stop the grab threads and wait for them (a thread inside a capture call finishes it:
        at most the open or read timeout)."""
        for g in self.grabbers.values():
            g.stop()
        for g in self.grabbers.values():
            if g.is_alive():
                g.join(g.open_timeout_s + g.read_timeout_s + 1.0)

    def _check_size(self, cid: str, img: np.ndarray, index: int) -> None:
        cam = self.cameras[cid]
        if img.shape[1] != cam.width or img.shape[0] != cam.height:
            raise InputError(f"{cid}: {self.grabbers[cid].source}: frame {index} is {img.shape[1]}x{img.shape[0]} "
                             f"but the scene's camera is {cam.width}x{cam.height}")

    def _file_bundles(self) -> Iterator[tuple[float, dict[str, Frame]]]:
        heads: dict[str, tuple] = {}
        while True:
            for cid, g in self.grabbers.items():
                if cid not in heads:
                    item = g.next_frame()
                    if item is None:
                        if g.stats.last_error:
                            raise InputError(f"{cid}: {g.source}: {g.stats.last_error}")
                        return        # the shortest input ends the bundles
                    heads[cid] = item
            t0 = min(h[0] for h in heads.values())
            tolerance = 0.5 / self.fps
            bundle = {cid: Frame(img, t, idx) for cid, (t, idx, img) in heads.items() if t - t0 < tolerance}
            for cid in bundle:
                del heads[cid]
            yield max(f.t for f in bundle.values()), bundle

    def _live_bundles(self) -> Iterator[tuple[float, dict[str, Frame]]]:
        taken = {c: -1 for c in self.grabbers}
        while True:
            bundle: dict[str, Frame] = {}
            first_at = None
            while True:
                for cid, g in self.grabbers.items():
                    item = None if cid in bundle else g.newest(taken[cid], timeout=0.0)
                    if item is not None:
                        t, idx, img = item
                        bundle[cid] = Frame(img, t, idx)
                        taken[cid] = idx
                if bundle and first_at is None:
                    first_at = time.monotonic()
                if len(bundle) == len(self.grabbers):
                    break
                if first_at is not None and time.monotonic() - first_at >= self.sync_s:
                    break
                if not bundle and all(g.ended for g in self.grabbers.values()):
                    return
                time.sleep(0.003)
            yield max(f.t for f in bundle.values()), bundle


def background_from_live(source: LiveSource, frames: int = 25, timeout_s: float = 20.0) -> dict[str, np.ndarray]:
    """Temporal median of the first ``frames`` frames of each live camera (people must keep moving)."""
    from worldtrack.foreground.estimate import estimate_background
    got: dict[str, list[np.ndarray]] = {c: [] for c in source.grabbers}
    taken = {c: -1 for c in source.grabbers}
    source.start()
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline and any(len(v) < frames for v in got.values()):
        for cid, g in source.grabbers.items():
            item = g.newest(taken[cid], timeout=0.05)
            if item is not None and len(got[cid]) < frames:
                taken[cid] = item[1]
                got[cid].append(item[2])
    missing = [c for c, v in got.items() if len(v) < 3]
    if missing:
        raise InputError(f"{missing[0]}: no frames from {source.grabbers[missing[0]].source} in {timeout_s:.0f} s "
                         f"to estimate a background (give --background {missing[0]}=PNG)")
    return {c: estimate_background(v) for c, v in got.items()}


__all__ = ["GrabStats", "Grabber", "LiveSource", "STREAM_SCHEMES", "background_from_live", "check_source",
           "is_live", "parse_source"]
