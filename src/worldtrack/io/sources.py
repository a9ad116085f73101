"""Frame sources: synchronised bundles ``{camera_id: Frame}`` from videos, image folders or arrays.

A source checks what it reads against the scene's cameras (image size, before the first frame)
and turns decoding problems into messages with the camera, file and frame named:

* a frame that cannot be decoded is skipped (its camera is missing from that bundle), said once
  and counted (:attr:`VideoSource.skipped`); ``max_bad_frames`` in a row stop the run with an
  :class:`~worldtrack.errors.InputError`;
* a camera whose video ends before the others' is dropped: the others go on, and the source says
  which camera stopped at which frame and time.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable, Iterator, Mapping, Sequence

import cv2
import numpy as np

from worldtrack.errors import InputError
from worldtrack.foreground.estimate import estimate_background
from worldtrack.geometry.camera import Camera
from worldtrack.trackers.base import Frame

_IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")

#: Undecodable frames in a row after which a camera's input counts as broken and the run stops.
MAX_BAD_FRAMES = 25

# What :meth:`_CameraReader.read` found.
_OK, _BAD, _END = "ok", "bad", "end"


class _CameraReader:
    """Reads one camera's frames from a video file or a folder of images."""

    def __init__(self, camera_id: str, path: Path):
        self.camera_id = camera_id
        self.path = path
        self.files: list[Path] | None = None
        self.cap: cv2.VideoCapture | None = None
        self.size: tuple[int, int] | None = None     # (width, height) as the header says
        if path.is_dir():
            self.files = sorted(p for p in path.iterdir() if p.suffix.lower() in _IMAGE_SUFFIXES)
            if not self.files:
                raise InputError(f"{camera_id}: {path}: folder holds no images ({', '.join(_IMAGE_SUFFIXES)})")
            self.fps = None
            self.count = len(self.files)
            first = next((img for img in (cv2.imread(str(f), cv2.IMREAD_COLOR) for f in self.files[:3])
                          if img is not None), None)
            self.size = None if first is None else (first.shape[1], first.shape[0])
        elif path.is_file():
            self.cap = cv2.VideoCapture(str(path))
            if not self.cap.isOpened():
                raise InputError(f"{camera_id}: {path}: cannot open as a video")
            fps = self.cap.get(cv2.CAP_PROP_FPS)
            self.fps = float(fps) if fps and np.isfinite(fps) and fps > 0 else None
            n = int(self.cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
            self.count = n if n > 0 else None
            w, h = int(self.cap.get(cv2.CAP_PROP_FRAME_WIDTH) or 0), int(self.cap.get(cv2.CAP_PROP_FRAME_HEIGHT) or 0)
            self.size = (w, h) if w > 0 and h > 0 else None
        else:
            raise InputError(f"{camera_id}: {path}: no such file or folder")
        self.index = 0

    def read(self) -> tuple[str, np.ndarray | None]:
        """``("ok", image)`` (BGR uint8), ``("bad", None)`` for a frame that cannot be decoded (the
        reader moves past it), or ``("end", None)``."""
        i = self.index
        if self.files is not None:
            if i >= len(self.files):
                return _END, None
            self.index += 1
            img = cv2.imread(str(self.files[i]), cv2.IMREAD_COLOR)
            return (_OK, img) if img is not None else (_BAD, None)
        ok, img = self.cap.read()
        self.index += 1
        if ok and img is not None:
            return _OK, img
        if self.count is not None and i < self.count - 1:
            # The header promises more: step over the damaged frame (a seek re-syncs the demuxer).
            self.cap.set(cv2.CAP_PROP_POS_FRAMES, i + 1)
            return _BAD, None
        return _END, None

    def close(self) -> None:
        if self.cap is not None:
            self.cap.release()


def size_mismatch(camera_id: str, path: Path, size: tuple[int, int], camera: Camera, frame: int | None = None) -> str:
    """The message for a video whose frames are not the camera's size: the video is named as the
    input at fault, with what to do."""
    which = f"frame {frame} is" if frame is not None else "frames are"
    return (f"{camera_id}: {path}: {which} {size[0]}x{size[1]} but the scene's camera is "
            f"{camera.width}x{camera.height}: give the video this camera was calibrated for, or rescale "
            f"the camera to the video (worldtrack calibrate --import FILE --image-size {size[0]}x{size[1]})")


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
        Frame range ``[start, stop)``; ``stop=None`` reads until every input has ended.
    max_bad_frames : int
        Undecodable frames in a row (per camera) after which the run stops with an
        :class:`InputError`; fewer are skipped and counted.
    warn : callable, optional
        Called with one line for each event a user should hear about (the first skipped frame of
        a camera, a camera that stopped before the others); default: kept in :attr:`warnings`.

    Iterating yields ``(index, t, {camera_id: Frame})``; a bundle lacks the cameras whose frame
    was skipped or whose input has ended. :attr:`skipped` lists the skipped frames per camera,
    :attr:`ended` the frame at which each camera ran out.
    """

    def __init__(self, paths: Mapping[str, str | Path], cameras: Mapping[str, Camera], fps: float | None = None,
                 start: int = 0, stop: int | None = None, max_bad_frames: int = MAX_BAD_FRAMES,
                 warn: Callable[[str], None] | None = None):
        unknown = [c for c in paths if c not in cameras]
        if unknown:
            raise InputError(f"--video {unknown[0]}=…: no camera {unknown[0]!r} in the scene "
                             f"(cameras: {', '.join(cameras)})")
        if not paths:
            raise InputError("no video given (use --video CAMERA=PATH)")
        if fps is not None and not (np.isfinite(fps) and fps > 0):
            raise InputError(f"--fps: expected a positive frame rate, got {fps:g}")
        self.cameras = {c: cameras[c] for c in paths}
        self.readers: dict[str, _CameraReader] = {}
        try:
            for c, p in paths.items():
                self.readers[c] = reader = _CameraReader(c, Path(p))
                cam = self.cameras[c]
                if reader.size is not None and reader.size != (cam.width, cam.height):
                    raise InputError(size_mismatch(c, reader.path, reader.size, cam))
        except BaseException:
            self.close()
            raise
        header_fps = [r.fps for r in self.readers.values() if r.fps]
        self.fps = float(fps) if fps else (header_fps[0] if header_fps else 10.0)
        self.start, self.stop = start, stop
        self.max_bad_frames = max(1, int(max_bad_frames))
        self.warnings: list[str] = []
        self.warn = warn if warn is not None else self.warnings.append
        self.skipped: dict[str, list[int]] = {c: [] for c in self.readers}
        self.ended: dict[str, int] = {}
        counts = [r.count for r in self.readers.values() if r.count]
        self.length = max(counts) if counts else None
        if self.length is not None:
            self.length = max(0, min(self.length, stop if stop is not None else self.length) - start)

    def __iter__(self) -> Iterator[tuple[int, float, dict[str, Frame]]]:
        active = dict(self.readers)
        in_a_row = {c: 0 for c in active}
        i = 0
        try:
            while active and (self.stop is None or i < self.stop):
                bundle: dict[str, Frame] = {}
                for cid, reader in list(active.items()):
                    status, img = reader.read()
                    if status == _END:
                        del active[cid]
                        self.ended[cid] = i
                    elif status == _BAD:
                        in_a_row[cid] += 1
                        self._bad_frame(cid, i, in_a_row[cid])
                    else:
                        in_a_row[cid] = 0
                        cam = self.cameras[cid]
                        if img.shape[1] != cam.width or img.shape[0] != cam.height:
                            raise InputError(size_mismatch(cid, reader.path, (img.shape[1], img.shape[0]), cam, i))
                        bundle[cid] = Frame(img, i / self.fps, i)
                if active:
                    for cid in [c for c, at in self.ended.items() if at == i]:
                        self.warn(f"{cid}: {self.readers[cid].path}: no more frames after frame {i - 1} "
                                  f"(t = {(i - 1) / self.fps:.3f} s); going on with {', '.join(active)}")
                if bundle and i >= self.start:
                    yield i, i / self.fps, bundle
                i += 1
        finally:
            self.close()

    def _bad_frame(self, cid: str, i: int, in_a_row: int) -> None:
        self.skipped[cid].append(i)
        path = self.readers[cid].path
        if in_a_row >= self.max_bad_frames:
            raise InputError(f"{cid}: {path}: {in_a_row} frames in a row cannot be decoded (frames "
                             f"{i - in_a_row + 1}-{i}); stopping")
        if len(self.skipped[cid]) == 1:
            self.warn(f"{cid}: {path}: frame {i} cannot be decoded; skipped (further ones are counted; "
                      f"{self.max_bad_frames} in a row stop the run)")

    def skipped_summary(self) -> list[str]:
        """One line per camera that skipped frames: how many, and which (the first few)."""
        out = []
        for cid, frames in self.skipped.items():
            if frames:
                shown = ", ".join(map(str, frames[:10])) + (", …" if len(frames) > 10 else "")
                out.append(f"{cid}: {len(frames)} frame(s) could not be decoded and were skipped ({shown})")
        return out

    def close(self) -> None:
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
