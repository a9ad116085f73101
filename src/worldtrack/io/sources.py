"""Frame sources: synchronised bundles ``{camera_id: Frame}`` from videos, image folders or arrays.

A source checks what it reads against the scene's cameras (image size) and turns decoding
problems into :class:`~worldtrack.errors.InputError` with the camera, file and frame named.
"""

from __future__ import annotations

from pathlib import Path
from typing import Iterator, Mapping, Sequence

import cv2
import numpy as np

from worldtrack.errors import InputError
from worldtrack.foreground.estimate import estimate_background
from worldtrack.geometry.camera import Camera
from worldtrack.trackers.base import Frame

_IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")


class _CameraReader:
    """Reads one camera's frames from a video file or a folder of images."""

    def __init__(self, camera_id: str, path: Path):
        self.camera_id = camera_id
        self.path = path
        self.files: list[Path] | None = None
        self.cap: cv2.VideoCapture | None = None
        if path.is_dir():
            self.files = sorted(p for p in path.iterdir() if p.suffix.lower() in _IMAGE_SUFFIXES)
            if not self.files:
                raise InputError(f"{camera_id}: {path}: folder holds no images ({', '.join(_IMAGE_SUFFIXES)})")
            self.fps = None
            self.count = len(self.files)
        elif path.is_file():
            self.cap = cv2.VideoCapture(str(path))
            if not self.cap.isOpened():
                raise InputError(f"{camera_id}: {path}: cannot open as a video")
            fps = self.cap.get(cv2.CAP_PROP_FPS)
            self.fps = float(fps) if fps and np.isfinite(fps) and fps > 0 else None
            n = int(self.cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
            self.count = n if n > 0 else None
        else:
            raise InputError(f"{camera_id}: {path}: no such file or folder")
        self.index = 0

    def read(self) -> np.ndarray | None:
        """Next image (BGR uint8), or None at the end. A frame that fails inside the stream raises."""
        i = self.index
        if self.files is not None:
            if i >= len(self.files):
                return None
            img = cv2.imread(str(self.files[i]), cv2.IMREAD_COLOR)
            if img is None:
                raise InputError(f"{self.camera_id}: {self.files[i]}: frame {i} cannot be decoded")
        else:
            ok, img = self.cap.read()
            if not ok or img is None:
                if self.count is not None and i < self.count - 1:
                    raise InputError(f"{self.camera_id}: {self.path}: frame {i} cannot be decoded "
                                     f"(the file says it has {self.count} frames)")
                return None
        self.index += 1
        return img

    def close(self) -> None:
        if self.cap is not None:
            self.cap.release()


class VideoSource:
    """Synchronised frames from one video (or image folder) per camera.

    Parameters
    ----------
    paths : {camera_id: path}
        A video file or a folder of images (sorted by name) per camera.
    cameras : {camera_id: Camera}
        The scene's cameras; every image must have the camera's size.
    fps : float, optional
        Frame rate for time stamps; default: the video header, else 10 fps.
    start, stop : int
        Frame range ``[start, stop)``; ``stop=None`` reads to the end of the shortest input.

    Iterating yields ``(index, t, {camera_id: Frame})``. The bundle ends with the shortest input.
    """

    def __init__(self, paths: Mapping[str, str | Path], cameras: Mapping[str, Camera], fps: float | None = None,
                 start: int = 0, stop: int | None = None):
        unknown = [c for c in paths if c not in cameras]
        if unknown:
            raise InputError(f"--video {unknown[0]}=…: no camera {unknown[0]!r} in the scene "
                             f"(cameras: {', '.join(cameras)})")
        if not paths:
            raise InputError("no video given (use --video CAMERA=PATH)")
        self.cameras = {c: cameras[c] for c in paths}
        self.readers = {c: _CameraReader(c, Path(p)) for c, p in paths.items()}
        header_fps = [r.fps for r in self.readers.values() if r.fps]
        self.fps = float(fps) if fps else (header_fps[0] if header_fps else 10.0)
        if self.fps <= 0:
            raise InputError(f"--fps: expected a positive frame rate, got {self.fps}")
        self.start, self.stop = start, stop
        counts = [r.count for r in self.readers.values() if r.count]
        self.length = min(counts) if counts else None
        if self.length is not None:
            self.length = max(0, min(self.length, stop if stop is not None else self.length) - start)

    def __iter__(self) -> Iterator[tuple[int, float, dict[str, Frame]]]:
        i = 0
        try:
            while self.stop is None or i < self.stop:
                bundle: dict[str, Frame] = {}
                for cid, reader in self.readers.items():
                    img = reader.read()
                    if img is None:
                        return
                    cam = self.cameras[cid]
                    if img.shape[1] != cam.width or img.shape[0] != cam.height:
                        raise InputError(f"{cid}: {reader.path}: frame {i} is {img.shape[1]}x{img.shape[0]} "
                                         f"but the scene's camera is {cam.width}x{cam.height}")
                    bundle[cid] = Frame(img, i / self.fps, i)
                if i >= self.start:
                    yield i, i / self.fps, bundle
                i += 1
        finally:
            for r in self.readers.values():
                r.close()


class ArraySource:
    """Frames already in memory (tests, the synthetic world): a sequence of ``{camera_id: image}``."""

    def __init__(self, images: Sequence[Mapping[str, np.ndarray]], fps: float = 10.0):
        self.images = images
        self.fps = float(fps)
        self.length = len(images)

    def __iter__(self) -> Iterator[tuple[int, float, dict[str, Frame]]]:
        for i, bundle in enumerate(self.images):
            t = i / self.fps
            yield i, t, {c: Frame(img, t, i) for c, img in bundle.items()}


def read_image(path: str | Path, camera: Camera | None = None, what: str = "image") -> np.ndarray:
    """Read a colour image (BGR uint8), checking its size against ``camera`` when given."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such {what} file")
    img = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if img is None:
        raise InputError(f"{path}: cannot be decoded as an image")
    if camera is not None and (img.shape[1], img.shape[0]) != (camera.width, camera.height):
        raise InputError(f"{path}: {what} is {img.shape[1]}x{img.shape[0]} but camera {camera.id!r} "
                         f"is {camera.width}x{camera.height}")
    return img


def background_from_video(path: str | Path, samples: int = 50) -> np.ndarray:
    """Temporal median of ``samples`` frames spread over a video (people must keep moving)."""
    cap = cv2.VideoCapture(str(path))
    if not cap.isOpened():
        raise InputError(f"{path}: cannot open as a video")
    n = int(cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
    frames = []
    if n > 0:
        for idx in np.linspace(0, n - 1, min(samples, n)).astype(int):
            cap.set(cv2.CAP_PROP_POS_FRAMES, int(idx))
            ok, img = cap.read()
            if ok:
                frames.append(img)
    cap.release()
    if not frames:
        raise InputError(f"{path}: no frames could be read to estimate a background")
    return estimate_background(frames)
