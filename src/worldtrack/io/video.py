"""Writing annotated video: through an FFmpeg process when ``ffmpeg`` is on PATH, else OpenCV.

An MP4 written by OpenCV has its index (the ``moov`` atom) written at the end: a run killed with
SIGKILL leaves a file no player opens. With ``ffmpeg`` on PATH an ``.mp4`` is instead written by an
FFmpeg process reading raw frames on a pipe, as *fragmented* MP4 (``-movflags
frag_keyframe+empty_moov``, a key frame every second, each packet flushed): the index is at the
start and every fragment plays on its own. If this process is killed, FFmpeg reads the end of its
pipe and finishes the file; if FFmpeg is killed too, the file still plays up to its last whole
fragment. FFmpeg runs in a session of its own, so a Ctrl-C in the terminal reaches only
worldtrack, which closes the video cleanly. ``.avi`` (MJPG) and machines without ``ffmpeg`` use
OpenCV's writer.
"""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from pathlib import Path

import cv2
import numpy as np

from worldtrack.errors import InputError

#: Seconds to wait for FFmpeg to finish the file once its input is closed.
CLOSE_TIMEOUT_S = 60.0


def ffmpeg_command(path: Path, size: tuple[int, int], fps: float, ffmpeg: str = "ffmpeg") -> list[str]:
    """The FFmpeg command line that reads ``size`` = (W, H) BGR frames on stdin at ``fps`` and writes
    fragmented MP4 (MPEG-4 part 2, as OpenCV's ``mp4v``, at the frames' own size) to ``path``.

    >>> ffmpeg_command(Path("v.mp4"), (641, 480), 10.0)[-3:]
    ['-movflags', 'frag_keyframe+empty_moov+default_base_moof', 'v.mp4']
    """
    w, h = size
    return [ffmpeg, "-hide_banner", "-loglevel", "error", "-y", "-f", "rawvideo", "-pix_fmt", "bgr24",
            "-s", f"{w}x{h}", "-r", f"{fps:g}", "-i", "pipe:0", "-an", "-c:v", "mpeg4", "-q:v", "4",
            "-pix_fmt", "yuv420p", "-g", str(max(1, round(fps))), "-flush_packets", "1",
            "-movflags", "frag_keyframe+empty_moov+default_base_moof", str(path)]


class VideoWriter:
    """Video writer that opens on the first frame, so the size comes from the frames.

    Parameters
    ----------
    path : output file (``.mp4``: fragmented MP4 through FFmpeg when it is on PATH, else OpenCV's
        ``mp4v``; ``.avi``: OpenCV's MJPG)
    fps : frames per second written in the header
    backend : ``"ffmpeg"``, ``"opencv"`` or None (FFmpeg for ``.mp4`` when ``ffmpeg`` is on PATH)

    Attributes
    ----------
    frames : int — frames written so far
    backend : str — the writer in use
    """

    def __init__(self, path: str | Path, fps: float, backend: str | None = None):
        self.path = Path(path)
        self.fps = float(fps)
        self.frames = 0
        ffmpeg = shutil.which("ffmpeg")
        if backend is None:
            backend = "ffmpeg" if ffmpeg and self.path.suffix.lower() == ".mp4" else "opencv"
        if backend == "ffmpeg" and not ffmpeg:
            raise InputError(f"{self.path}: ffmpeg is not on PATH")
        self.backend = backend
        self._ffmpeg = ffmpeg
        self._writer: cv2.VideoWriter | None = None
        self._process: subprocess.Popen | None = None
        self._log = None

    def write(self, image: np.ndarray) -> None:
        """Append one (H, W, 3) uint8 BGR frame."""
        if self._writer is None and self._process is None:
            self._open(image.shape[1], image.shape[0])
        if self._process is not None:
            try:
                self._process.stdin.write(np.ascontiguousarray(image, dtype=np.uint8).tobytes())
            except (BrokenPipeError, ValueError):
                raise OSError(f"{self.path}: ffmpeg stopped writing the video: {self._ffmpeg_error()}") from None
        else:
            self._writer.write(np.ascontiguousarray(image))
        self.frames += 1

    def _open(self, w: int, h: int) -> None:
        if self.backend == "ffmpeg":
            self._log = tempfile.TemporaryFile()
            self._process = subprocess.Popen(ffmpeg_command(self.path, (w, h), self.fps, self._ffmpeg),
                                             stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=self._log,
                                             start_new_session=True)
            return
        fourcc = cv2.VideoWriter_fourcc(*("MJPG" if self.path.suffix.lower() == ".avi" else "mp4v"))
        self._writer = cv2.VideoWriter(str(self.path), fourcc, self.fps, (w, h))
        if not self._writer.isOpened():
            raise InputError(f"{self.path}: cannot open for writing video")

    def _ffmpeg_error(self, code: int | None = None) -> str:
        """FFmpeg's last line of complaint, or its exit status."""
        lines: list[str] = []
        if self._log is not None:
            self._log.seek(0)
            lines = self._log.read().decode("utf-8", "replace").strip().splitlines()
        return lines[-1] if lines else f"exit status {code}"

    def close(self) -> None:
        """Finish the file (FFmpeg: close its input and wait for it)."""
        if self._writer is not None:
            self._writer.release()
            self._writer = None
        process, self._process = self._process, None
        try:
            if process is not None:
                _finish(process, self.path, self._ffmpeg_error)
        finally:
            if self._log is not None:
                self._log.close()
                self._log = None

    def __enter__(self) -> "VideoWriter":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _finish(process: subprocess.Popen, path: Path, error) -> None:
    """Close FFmpeg's input and wait for it to finish ``path``; OSError naming its complaint if it fails."""
    try:
        process.stdin.close()
    except BrokenPipeError:
        pass
    try:
        code = process.wait(timeout=CLOSE_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        process.kill()
        code = process.wait()
    if code != 0:
        raise OSError(f"{path}: ffmpeg failed to finish the video: {error(code)}")
