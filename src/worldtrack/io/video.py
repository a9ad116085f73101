"""Writing annotated video with OpenCV; the file is valid up to the last frame written."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from worldtrack.errors import InputError


class VideoWriter:
    """MP4 (``mp4v``) writer that opens on the first frame, so the size comes from the frames.

    Parameters
    ----------
    path : output file (``.mp4``; ``.avi`` uses MJPG)
    fps : frames per second written in the header
    """

    def __init__(self, path: str | Path, fps: float):
        self.path = Path(path)
        self.fps = float(fps)
        self._writer: cv2.VideoWriter | None = None
        self.frames = 0

    def write(self, image: np.ndarray) -> None:
        if self._writer is None:
            h, w = image.shape[:2]
            fourcc = cv2.VideoWriter_fourcc(*("MJPG" if self.path.suffix.lower() == ".avi" else "mp4v"))
            self._writer = cv2.VideoWriter(str(self.path), fourcc, self.fps, (w, h))
            if not self._writer.isOpened():
                raise InputError(f"{self.path}: cannot open for writing video")
        self._writer.write(np.ascontiguousarray(image))
        self.frames += 1

    def close(self) -> None:
        if self._writer is not None:
            self._writer.release()
            self._writer = None

    def __enter__(self) -> "VideoWriter":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
