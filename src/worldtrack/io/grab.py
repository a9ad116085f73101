"""One camera's grab thread: opening a device, stream or file, stamping and keeping frames, reconnecting.

See :mod:`worldtrack.io.live` for how cameras are bundled; this module reads one camera.
"""

from __future__ import annotations

import math
import os
import queue
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from worldtrack.errors import InputError

_END = object()


#: FFmpeg's options for live streams unless ``OPENCV_FFMPEG_CAPTURE_OPTIONS`` says otherwise.
FFMPEG_PROBE = "analyzeduration;500000|probesize;131072"
#: URL schemes opened through OpenCV's FFmpeg backend.
STREAM_SCHEMES = ("rtsp", "rtsps", "rtmp", "http", "https", "udp", "rtp", "tcp", "srt")
_END = object()


def parse_source(text: str) -> int | str:
    """A camera's source: an integer device index, a stream URL or a file path (as given)."""
    text = str(text).strip()
    return int(text) if text.isdigit() else text


def is_live(source: int | str) -> bool:
    """True for a device index or a stream URL (frames come in real time and may be dropped)."""
    return isinstance(source, int) or str(source).split("://", 1)[0].lower() in STREAM_SCHEMES


@dataclass
class GrabStats:
    """One camera's counters: frames grabbed, frames dropped (a newer one replaced them before the
    tracker took them), reconnections, seconds without signal, and the last problem met."""

    frames: int = 0
    dropped: int = 0
    reconnects: int = 0
    outage_s: float = 0.0
    last_error: str = ""


def _open_capture(source: int | str, open_timeout_s: float, read_timeout_s: float):
    """An OpenCV capture of ``source``: streams through the FFmpeg backend with open and read
    timeouts (so a dead stream returns instead of blocking), devices and files as OpenCV opens them."""
    import cv2
    if "OPENCV_LOG_LEVEL" not in os.environ:     # read when cv2 is imported: too late here, so also set it
        os.environ["OPENCV_LOG_LEVEL"] = "ERROR"
        cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_ERROR)
    # FFmpeg probes 5 s of a stream by default before the first frame; half a second finds a
    # camera's video stream and starts tracking (and a reconnection) seconds sooner.
    os.environ.setdefault("OPENCV_FFMPEG_CAPTURE_OPTIONS", FFMPEG_PROBE)
    if isinstance(source, int):
        return cv2.VideoCapture(source)
    if is_live(source):
        params = [cv2.CAP_PROP_OPEN_TIMEOUT_MSEC, int(open_timeout_s * 1000),
                  cv2.CAP_PROP_READ_TIMEOUT_MSEC, int(read_timeout_s * 1000)]
        return cv2.VideoCapture(source, cv2.CAP_FFMPEG, params)
    return cv2.VideoCapture(str(source))


def check_source(camera_id: str, source: int | str) -> None:
    """:class:`InputError` if a file source is neither a video file nor a folder of images, or a
    stream URL's scheme needs an FFmpeg backend this OpenCV build does not have."""
    from worldtrack.io.sources import _IMAGE_SUFFIXES
    if isinstance(source, int):
        return
    if is_live(source):
        import cv2
        if not cv2.videoio_registry.hasBackend(cv2.CAP_FFMPEG):
            raise InputError(f"{camera_id}: {source}: this OpenCV ({cv2.__version__}) was built without FFmpeg, "
                             "which reads stream URLs (see cv2.getBuildInformation(); the opencv-python wheel "
                             "from PyPI has it)")
        return
    p = Path(str(source))
    if p.is_dir() and not any(q.suffix.lower() in _IMAGE_SUFFIXES for q in p.iterdir()):
        raise InputError(f"{camera_id}: {source}: folder holds no images ({', '.join(_IMAGE_SUFFIXES)})")
    if not p.exists():
        raise InputError(f"{camera_id}: {source}: no such video file or folder (or give a device index or a "
                         f"stream URL: {', '.join(s + '://' for s in STREAM_SCHEMES[:6])}…)")


class _FolderReader:
    """A folder of images (sorted by name) read like an OpenCV capture."""

    def __init__(self, folder: Path):
        from worldtrack.io.sources import _IMAGE_SUFFIXES
        self.files = sorted(p for p in folder.iterdir() if p.suffix.lower() in _IMAGE_SUFFIXES)
        self.i = 0

    def isOpened(self) -> bool:
        return bool(self.files)

    def get(self, prop: int) -> float:
        return 0.0

    def grab(self) -> bool:
        self.i += 1
        return self.i <= len(self.files)

    def read(self):
        import cv2
        if self.i >= len(self.files):
            return False, None
        img = cv2.imread(str(self.files[self.i]), cv2.IMREAD_COLOR)
        if img is None:
            raise InputError(f"{self.files[self.i]}: frame {self.i} cannot be decoded")
        self.i += 1
        return True, img

    def release(self) -> None:
        pass


class Grabber(threading.Thread):
    """Reads one camera in the background.

    Parameters
    ----------
    camera_id : str
    source : device index, stream URL or file path (:func:`parse_source`)
    fps : frame rate of a file's time stamps (default: its header, else 10)
    epoch : wall-clock time (s) of a file's frame 0
    pace : release a file's frames at their wall-clock times, starting with the frame due now
    clock : wall clock, seconds
    backoff_s : (first, largest) wait before reopening a dropped live stream
    """

    def __init__(self, camera_id: str, source: int | str, fps: float | None = None, epoch: float = 0.0,
                 pace: bool = False, clock: Callable[[], float] = time.time,
                 backoff_s: tuple[float, float] = (0.5, 8.0), open_timeout_s: float = 3.0,
                 read_timeout_s: float = 2.0, buffer_frames: int = 8):
        super().__init__(name=f"grab-{camera_id}", daemon=True)
        self.camera_id, self.source, self.clock = camera_id, source, clock
        self.live = is_live(source)
        self.epoch, self.pace = float(epoch), bool(pace)
        self.backoff_s, self.open_timeout_s, self.read_timeout_s = backoff_s, open_timeout_s, read_timeout_s
        self.stats = GrabStats()
        self.fps = fps
        self._halt = threading.Event()
        self._cond = threading.Condition()
        self._newest: tuple[float, int, np.ndarray] | None = None   # live: the one slot
        self._taken = -1
        self._queue: queue.Queue = queue.Queue(maxsize=buffer_frames)   # files: every frame
        self.ended = False
        check_source(camera_id, source)
        if not self.live:
            cap = _FolderReader(Path(source)) if Path(source).is_dir() else \
                _open_capture(source, open_timeout_s, read_timeout_s)
            if not cap.isOpened():
                raise InputError(f"{camera_id}: {source}: cannot open as a video")
            import cv2
            header = cap.get(cv2.CAP_PROP_FPS)
            self.fps = fps or (float(header) if header and math.isfinite(header) and header > 0 else 10.0)
            self._cap = cap

    # ------------------------------------------------------------------ the thread
    def run(self) -> None:
        try:
            self._run_live() if self.live else self._run_file()
        except Exception as e:     # reported to the reader, not lost in a thread
            self.stats.last_error = f"{type(e).__name__}: {e}"
            self._finish()

    def _run_file(self) -> None:
        import cv2
        cap = self._cap
        index = 0
        if self.pace:
            due = max(0, math.ceil((self.clock() - self.epoch) * self.fps - 1e-6))
            while index < due and cap.grab():     # not CAP_PROP_POS_FRAMES: it may land on a key frame
                index += 1
        while not self._halt.is_set():
            ok, img = cap.read()
            if not ok or img is None:
                break
            t = self.epoch + index / self.fps
            if self.pace:
                delay = t - self.clock()
                if delay > 0 and self._halt.wait(delay):
                    break
            self.stats.frames += 1
            while not self._halt.is_set():
                try:
                    self._queue.put((t, index, img), timeout=0.2)
                    break
                except queue.Full:
                    continue
            index += 1
        cap.release()
        self._finish()

    def _run_live(self) -> None:
        wait = self.backoff_s[0]
        lost_at: float | None = None
        first = True
        while not self._halt.is_set():
            cap = _open_capture(self.source, self.open_timeout_s, self.read_timeout_s)
            if not cap.isOpened():
                cap.release()
                self.stats.last_error = f"cannot open {self.source}"
                lost_at = self.clock() if lost_at is None else lost_at
                if self._halt.wait(wait):
                    break
                wait = min(wait * 2, self.backoff_s[1])
                continue
            if not first:
                self.stats.reconnects += 1
            first = False
            if lost_at is not None:
                self.stats.outage_s += self.clock() - lost_at
                lost_at = None
            wait = self.backoff_s[0]
            while not self._halt.is_set():
                if not cap.grab():
                    break
                t = self.clock()
                ok, img = cap.retrieve()
                if not ok or img is None:
                    break
                self._offer(t, img)
            cap.release()
            if not self._halt.is_set():
                self.stats.last_error = f"stream {self.source} stopped; reconnecting"
                lost_at = self.clock()
        self._finish()

    def _offer(self, t: float, img: np.ndarray) -> None:
        with self._cond:
            if self._newest is not None and self._newest[1] > self._taken:
                self.stats.dropped += 1
            index = self.stats.frames
            self.stats.frames += 1
            self._newest = (t, index, img)
            self._cond.notify_all()

    def _finish(self) -> None:
        with self._cond:
            self.ended = True
            self._cond.notify_all()
        while True:          # after the frames still queued (a reader slower than the file)
            try:
                self._queue.put(_END, timeout=0.2)
                return
            except queue.Full:
                if self._halt.is_set():
                    return

    # ------------------------------------------------------------------ the reader's side
    def newest(self, after: int, timeout: float) -> tuple[float, int, np.ndarray] | None:
        """A live camera's newest frame if it is newer than frame ``after`` (waits up to ``timeout``)."""
        deadline = time.monotonic() + timeout
        with self._cond:
            while (self._newest is None or self._newest[1] <= after) and not self.ended:
                left = deadline - time.monotonic()
                if left <= 0:
                    return None
                self._cond.wait(left)
            if self._newest is None or self._newest[1] <= after:
                return None
            self._taken = self._newest[1]
            return self._newest

    def next_frame(self, timeout: float | None = None):
        """A file's next frame ``(t, index, image)``, or None at its end."""
        item = self._queue.get(timeout=timeout)
        if item is _END:
            self._queue.put(_END)
            return None
        return item

    def stop(self) -> None:
        self._halt.set()


__all__ = ["FFMPEG_PROBE", "GrabStats", "Grabber", "STREAM_SCHEMES", "check_source", "is_live", "parse_source"]
