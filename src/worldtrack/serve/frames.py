"""Annotated camera frames on demand (``worldtrack serve out/ --frames``): JPEG over HTTP.

A finished run wrote ``<camera>_annotated.mp4`` (``worldtrack track`` without ``--no-video``);
``/api/frame/<camera>/<frame>`` seeks one of them with OpenCV and answers the frame as JPEG.
Off by default: a page that is looked at over a network should not carry the cameras' pictures
unless someone said so.
"""

from __future__ import annotations

import threading
from pathlib import Path

import cv2

from worldtrack.errors import InputError


class AnnotatedFrames:
    """The annotated videos of a run folder, one OpenCV capture per camera, read under a lock."""

    def __init__(self, folder: Path, cameras: list[str], quality: int = 80):
        self.videos = {c: folder / f"{c}_annotated.mp4" for c in cameras if (folder / f"{c}_annotated.mp4").is_file()}
        if not self.videos:
            raise InputError(f"{folder}: --frames: no <camera>_annotated.mp4 in it (the run was made with --no-video?)")
        self.quality = quality
        self._caps: dict[str, cv2.VideoCapture] = {}
        self._next: dict[str, int] = {}
        self._lock = threading.Lock()

    @property
    def cameras(self) -> list[str]:
        return list(self.videos)

    def jpeg(self, camera: str, frame: int) -> bytes | None:
        """Frame ``frame`` (from 0) of ``camera``'s annotated video as JPEG bytes; None if it has none."""
        if camera not in self.videos or frame < 0:
            return None
        with self._lock:
            cap = self._caps.get(camera)
            if cap is None:
                cap = self._caps[camera] = cv2.VideoCapture(str(self.videos[camera]))
                self._next[camera] = 0
            if self._next[camera] != frame:          # the next frame is read without seeking (playing)
                cap.set(cv2.CAP_PROP_POS_FRAMES, frame)
            ok, img = cap.read()
            self._next[camera] = frame + 1 if ok else -1
        if not ok:
            return None
        ok, buf = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, self.quality])
        return buf.tobytes() if ok else None

    def close(self) -> None:
        with self._lock:
            for cap in self._caps.values():
                cap.release()
            self._caps.clear()


__all__ = ["AnnotatedFrames"]
