"""Colour + depth input for following (seed 001): depth, disparity or a stereo pair, gains and poses per frame.

One camera. Per frame the colour image comes from a video or a folder of images; the depth from
a folder of 16-bit PNGs in millimetres (``--depth``), a folder of 16-bit PNGs of disparity in 1/16
pixel (``--disparity``, OpenCV's and ``worldtrack synth``'s convention; needs the baseline), or a
right-camera video/folder matched with StereoSGBM (``--right``, needs the baseline). Beside them:

* ``frames.csv`` (``worldtrack synth``): ``time`` and the white-balance gains ``wb_r_<camera>``,
  ``wb_b_<camera>`` (0…1023, 512 = ×1) of every frame;
* ``camera_poses.csv``: the moving camera's pose per frame (``rvec_*``, ``t_*``: world → camera).

Every mismatch is an :class:`~worldtrack.errors.InputError` naming the file, frame and sizes.
"""

from __future__ import annotations

import csv
import io
import time
from pathlib import Path
from typing import Iterator

import cv2
import numpy as np

from worldtrack.errors import InputError
from worldtrack.follow.stereo import StereoMatcher, disparity_to_depth
from worldtrack.geometry.camera import Camera
from worldtrack.geometry.rotation import rodrigues
from worldtrack.io.sources import _CameraReader
from worldtrack.trackers.base import Frame
from worldtrack.io.text import read_text


def _table(path: str | Path, what: str) -> tuple[list[str], list[dict]]:
    reader = csv.DictReader(io.StringIO(read_text(path, what)))
    rows = list(reader)
    if not rows:
        raise InputError(f"{path}: no rows (expected {what})")
    return [c for c in reader.fieldnames or [] if c is not None], rows


def _number(row: dict, key: str, path, line: int) -> float:
    try:
        return float(row[key])
    except (TypeError, ValueError):
        raise InputError(f"{path}: line {line}: {key}: expected a number, got {row.get(key)!r}") from None


def read_gains(path: str | Path, camera_id: str) -> tuple[np.ndarray, np.ndarray | None]:
    """(gains (n, 2) as (r, b), times (n,) s or None) from a frames.csv with ``wb_r_<cam>``, ``wb_b_<cam>``."""
    cols, rows = _table(path, "a frames.csv with white-balance gains per frame")
    need = [f"wb_r_{camera_id}", f"wb_b_{camera_id}"]
    missing = [c for c in need if c not in cols]
    if missing:
        raise InputError(f"{path}: no column {missing[0]!r} (white-balance gains of camera {camera_id!r}; "
                         f"columns: {', '.join(cols)})")
    gains = np.array([[_number(r, need[0], path, i + 2), _number(r, need[1], path, i + 2)] for i, r in enumerate(rows)])
    times = np.array([_number(r, "time", path, i + 2) for i, r in enumerate(rows)]) if "time" in cols else None
    return gains, times


def read_poses(path: str | Path, camera_id: str) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """frame → (R, t) world → camera of ``camera_id`` from a camera_poses.csv."""
    cols, rows = _table(path, "a camera_poses.csv (frame, camera, rvec_x..z, t_x..z)")
    need = ["frame", "rvec_x", "rvec_y", "rvec_z", "t_x", "t_y", "t_z"]
    missing = [c for c in need if c not in cols]
    if missing:
        raise InputError(f"{path}: no column {missing[0]!r} (expected {', '.join(need)})")
    out = {}
    for i, r in enumerate(rows):
        if "camera" in cols and r["camera"] != camera_id:
            continue
        v = [_number(r, c, path, i + 2) for c in need]
        out[int(v[0])] = (rodrigues(np.array(v[1:4])), np.array(v[4:7]))
    if not out:
        raise InputError(f"{path}: no pose of camera {camera_id!r}")
    return out


def _png_folder(path: str | Path, flag: str) -> list[Path]:
    p = Path(path)
    if not p.is_dir():
        raise InputError(f"{flag} {path}: no such folder (expected 16-bit PNG images, one per frame)")
    files = sorted(f for f in p.iterdir() if f.suffix.lower() == ".png")
    if not files:
        raise InputError(f"{flag} {path}: folder holds no PNG images")
    return files


class RGBDSource:
    """Frames (colour, depth in metres, gains) and the camera at each frame; see the module docstring.

    Iterating yields ``(Frame, Camera)``; ``Frame.meta["wb_gains"]`` is (r, b) when gains are known.
    """

    def __init__(self, camera: Camera, rgb: str | Path, depth: str | Path | None = None,
                 disparity: str | Path | None = None, right: str | Path | None = None,
                 baseline: float | None = None, gains: np.ndarray | None = None, times: np.ndarray | None = None,
                 poses: dict | None = None, fps: float | None = None, stop: int | None = None):
        given = [x is not None for x in (depth, disparity, right)]
        if sum(given) != 1:
            raise InputError("give exactly one of --depth, --disparity or --right")
        if (disparity is not None or right is not None) and not (baseline and baseline > 0):
            raise InputError("--baseline: the stereo baseline in metres is needed with --disparity or --right")
        self.camera = camera
        self.reader = _CameraReader(camera.id, Path(rgb))
        self.depth_files = _png_folder(depth, "--depth") if depth is not None else None
        self.disp_files = _png_folder(disparity, "--disparity") if disparity is not None else None
        self.right = _CameraReader(camera.id + " (right)", Path(right)) if right is not None else None
        self.matcher = StereoMatcher(float(camera.K[0, 0]), baseline) if right is not None else None
        self.baseline = baseline
        self.gains, self.times, self.poses = gains, times, poses
        self.fps = float(fps) if fps else (self.reader.fps or 10.0)
        self.stop = stop
        self.stereo_seconds = 0.0     # time spent in StereoSGBM (reported apart)

    def _depth(self, i: int, left: np.ndarray) -> np.ndarray:
        shape = left.shape[:2]
        if self.right is not None:
            status, right = self.right.read()
            if status == "end":
                raise InputError(f"--right: no frame {i} (the right camera's input is shorter)")
            if right is None:
                raise InputError(f"--right: frame {i} cannot be decoded")
            t0 = time.perf_counter()
            depth = self.matcher.depth(left, self._fit(right, shape, "--right", i))
            self.stereo_seconds += time.perf_counter() - t0
            return depth
        files = self.depth_files if self.depth_files is not None else self.disp_files
        flag = "--depth" if self.depth_files is not None else "--disparity"
        if i >= len(files):
            raise InputError(f"{flag}: no image for frame {i} (the folder holds {len(files)})")
        raw = cv2.imread(str(files[i]), cv2.IMREAD_ANYDEPTH)
        if raw is None:
            raise InputError(f"{flag} {files[i]}: cannot be decoded as an image")
        self._fit(raw, shape, flag, i, files[i])
        if self.depth_files is not None:
            return raw.astype(np.float32) / 1000.0                          # millimetres → metres
        return disparity_to_depth(raw.astype(np.float32) / 16.0, float(self.camera.K[0, 0]), self.baseline)

    @staticmethod
    def _fit(img: np.ndarray, shape: tuple[int, int], flag: str, i: int, path=None) -> np.ndarray:
        if img.shape[:2] != shape:
            where = f" {path}" if path is not None else ""
            raise InputError(f"{flag}{where}: frame {i} is {img.shape[1]}x{img.shape[0]} but the colour image "
                             f"is {shape[1]}x{shape[0]}")
        return img

    def __iter__(self) -> Iterator[tuple[Frame, Camera]]:
        i = 0
        try:
            while self.stop is None or i < self.stop:
                status, img = self.reader.read()
                if status == "end":
                    return
                if img is None:         # a frame the decoder cannot read: its depth would pair with the next
                    raise InputError(f"--rgb: frame {i} cannot be decoded")
                if (img.shape[1], img.shape[0]) != (self.camera.width, self.camera.height):
                    raise InputError(f"--rgb: frame {i} is {img.shape[1]}x{img.shape[0]} but camera "
                                     f"{self.camera.id!r} is {self.camera.width}x{self.camera.height}")
                depth = self._depth(i, img)
                meta = {}
                if self.gains is not None:
                    if i >= len(self.gains):
                        raise InputError(f"frames.csv: no white-balance gains for frame {i} (it has {len(self.gains)} rows)")
                    meta["wb_gains"] = (float(self.gains[i, 0]), float(self.gains[i, 1]))
                t = float(self.times[i]) if self.times is not None and i < len(self.times) else i / self.fps
                cam = self.camera
                if self.poses is not None:
                    if i not in self.poses:
                        raise InputError(f"camera_poses.csv: no pose of camera {cam.id!r} for frame {i}")
                    cam = cam.moved(*self.poses[i])
                yield Frame(img, t, i, depth, meta=meta), cam
                i += 1
        finally:
            self.reader.close()
            if self.right is not None:
                self.right.close()
