"""Image-box ground truth (CVML XML, MOTChallenge text) → world ground truth on the floor.

Other benchmarks annotate people as boxes in one camera's image. worldtrack evaluates in metres
on the floor, so each box's *foot point* — the middle of its bottom edge — is back-projected
through the scene's calibrated camera (lens distortion undone) onto the floor ``Z = 0``.

Inputs
------
* **CVML XML** (PETS 2009, Milan's annotations)::

      <dataset><frame number="0"><objectlist>
        <object id="9"><box xc="514.7" yc="195.3" w="31.0" h="75.2"/></object> …

  ``(xc, yc)`` is the box centre in pixels; the foot point is ``(xc, yc + h/2)``. Frame numbers
  are used as they are (PETS: from 0, matching the video's frame index). Pixel centres at
  integers (worldtrack's convention) are assumed.
* **MOTChallenge text**: ``frame,id,bb_left,bb_top,bb_width,bb_height,conf,…``; frames from 1
  (made 0-based), pixel coordinates from 1 as in the MOTChallenge devkit (1 is subtracted;
  ``pixel_origin=0`` keeps them). The foot point is ``(bb_left + bb_width/2, bb_top + bb_height)``.
  In MOT16-style ground truth (column 7 a 0/1 "consider" flag), rows flagged 0 are dropped.

Output: a :class:`~worldtrack.io.tracks.TrackTable` for ``gt.csv`` with columns
``frame,time,id,x,y,foot_u,foot_v,foot_outside,bb_left,bb_top,bb_width,bb_height`` — pixels in the
scene camera's image (after ``scale``), ``foot_outside`` 1 where the foot point lies outside the
image (the annotator guessed where the feet are, so the world position is less reliable; such
rows are kept unless ``keep_outside=False``).
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from worldtrack.errors import InputError
from worldtrack.geometry.camera import Camera
from worldtrack.io.text import read_text
from worldtrack.io.tracks import TrackTable
from worldtrack.scene.floor import points_in_polygon

#: PETS 2009 S2.L1 frame rate (MOTChallenge's seqinfo and Milan's scene files say 7 fps; the
#: AVI copies in circulation say 10 in their header, which is not the capture rate).
PETS_S2L1_FPS = 7.0

_SPLIT = re.compile(r"[,\s]+")


@dataclass(frozen=True, eq=False)
class BoxTable:
    """Image boxes, one row per person per frame.

    Attributes
    ----------
    frame : (N,) int64 — frame index from 0
    id : (N,) int64 — person id as annotated
    left, top, width, height : (N,) float64 — box in pixels of the annotated image (pixel
        centres at integers)
    source : str — file name, for messages
    format : str — ``"cvml"`` or ``"mot"``
    dropped : int — rows the reader left out (MOT "consider = 0")
    """

    frame: np.ndarray
    id: np.ndarray
    left: np.ndarray
    top: np.ndarray
    width: np.ndarray
    height: np.ndarray
    source: str = ""
    format: str = ""
    dropped: int = 0

    def __len__(self) -> int:
        return int(self.frame.shape[0])

    @property
    def foot(self) -> np.ndarray:
        """(N, 2) pixels: middle of each box's bottom edge."""
        return np.column_stack([self.left + self.width / 2.0, self.top + self.height])


def read_cvml(path: str | Path) -> BoxTable:
    """Read CVML XML ground truth (``<frame number><objectlist><object id><box xc yc w h>``).

    Raises
    ------
    InputError
        Not XML, no frames, a missing or non-numeric attribute, a negative size, or the same id
        twice in one frame — naming the file, frame and object.
    """
    return _parse_cvml(read_text(path, "CVML XML"), str(path))


def _parse_cvml(text: str, label: str) -> BoxTable:
    try:
        root = ET.fromstring(text)
    except ET.ParseError as e:
        raise InputError(f"{label}: not valid XML ({e})") from None
    frames = list(root.iter("frame"))
    if not frames:
        raise InputError(f"{label}: no <frame> elements (expected CVML: <frame number=N><objectlist>"
                         "<object id=K><box xc yc w h/>)")
    rows: list[tuple[int, int, float, float, float, float]] = []
    for fr in frames:
        number = _int_attr(fr, "number", f"{label}: <frame>")
        if number < 0:
            raise InputError(f"{label}: frame {number}: expected a frame number >= 0")
        seen: set[int] = set()
        for ob in fr.iter("object"):
            where = f"{label}: frame {number}: <object>"
            oid = _int_attr(ob, "id", where)
            where = f"{label}: frame {number}, object {oid}"
            if oid in seen:
                raise InputError(f"{where}: id appears twice in the frame")
            seen.add(oid)
            box = ob.find("box")
            if box is None:
                raise InputError(f"{where}: missing <box xc yc w h/>")
            xc, yc, w, h = (_float_attr(box, k, where) for k in ("xc", "yc", "w", "h"))
            if w < 0 or h < 0:
                raise InputError(f"{where}: expected a box with w, h >= 0, got w={w:g}, h={h:g}")
            rows.append((number, oid, xc - w / 2.0, yc - h / 2.0, w, h))
    return _boxes(rows, label, "cvml")


def read_mot_boxes(path: str | Path, pixel_origin: int = 1) -> BoxTable:
    """Read MOTChallenge text boxes ``frame,id,bb_left,bb_top,bb_width,bb_height[,conf,…]``.

    Parameters
    ----------
    pixel_origin : {1, 0}
        Pixel coordinate of the image's first pixel centre in the file (MOTChallenge: 1).
    """
    _check_pixel_origin(pixel_origin)
    return _parse_mot(read_text(path, "MOTChallenge text"), str(path), pixel_origin)


def _check_pixel_origin(pixel_origin: int) -> None:
    if pixel_origin not in (0, 1):
        raise InputError(f"pixel origin: expected 0 or 1, got {pixel_origin!r}")


def _parse_mot(text: str, label: str, pixel_origin: int) -> BoxTable:
    rows: list[list[float]] = []
    for n, line in enumerate(text.splitlines(), start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        tokens = [t for t in _SPLIT.split(line.strip()) if t]
        try:
            values = [float(t) for t in tokens]
        except ValueError:
            raise InputError(f"{label}: line {n}: expected numbers frame,id,bb_left,bb_top,bb_width,"
                             f"bb_height,… (MOTChallenge), got {line.strip()[:60]!r}") from None
        if len(values) < 6:
            raise InputError(f"{label}: line {n}: expected at least 6 values (frame,id,bb_left,bb_top,"
                             f"bb_width,bb_height), got {len(values)}")
        if not all(math.isfinite(v) for v in values[:6]):
            raise InputError(f"{label}: line {n}: expected finite numbers")
        if values[0] < 1 or values[0] != int(values[0]) or values[1] != int(values[1]):
            raise InputError(f"{label}: line {n}: expected an integer frame >= 1 and an integer id")
        if values[4] < 0 or values[5] < 0:
            raise InputError(f"{label}: line {n}: expected bb_width, bb_height >= 0")
        rows.append(values)
    if not rows:
        raise InputError(f"{label}: no boxes")
    width = min(len(r) for r in rows)
    a = np.array([r[:width] for r in rows], dtype=float)
    dropped = 0
    if width >= 9 and np.all(np.isin(a[:, 6], (0.0, 1.0))):    # MOT16+ GT: column 7 = consider
        keep = a[:, 6] == 1
        dropped = int((~keep).sum())
        a = a[keep]
    off = float(pixel_origin)
    out = [(int(r[0]) - 1, int(r[1]), r[2] - off, r[3] - off, r[4], r[5]) for r in a]
    return replace(_boxes(out, label, "mot"), dropped=dropped)


def read_boxes(path: str | Path, format: str = "auto", pixel_origin: int | None = None) -> BoxTable:
    """Read image-box ground truth: ``format`` ``"cvml"``, ``"mot"`` or ``"auto"`` (XML → CVML)."""
    if format not in ("auto", "cvml", "mot"):
        raise InputError(f"--format: expected auto, cvml or mot, got {format!r}")
    text = None
    if format == "auto":                 # read once: the text decides the format and is parsed
        text = read_text(path, "CVML XML or MOTChallenge text")
        format = "cvml" if text.lstrip().startswith("<") else "mot"
    if format == "cvml":
        if pixel_origin not in (None, 0):
            raise InputError("--pixel-origin 1 applies to MOTChallenge text; CVML is read with pixel "
                             "centres at integers from 0")
        return read_cvml(path) if text is None else _parse_cvml(text, str(path))
    origin = 1 if pixel_origin is None else pixel_origin
    if text is None:
        return read_mot_boxes(path, origin)
    _check_pixel_origin(origin)
    return _parse_mot(text, str(path), origin)


def _int_attr(el: ET.Element, key: str, where: str) -> int:
    text = el.get(key)
    if text is None:
        raise InputError(f"{where}: missing attribute {key!r}")
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (math.isfinite(value) and value == int(value)):
        raise InputError(f"{where}: {key}: expected an integer, got {text!r}")
    return int(value)


def _float_attr(el: ET.Element, key: str, where: str) -> float:
    text = el.get(key)
    if text is None:
        raise InputError(f"{where}: <box> is missing {key!r} (expected xc, yc, w, h)")
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not math.isfinite(value):
        raise InputError(f"{where}: {key}: expected a number, got {text!r}")
    return value


def _boxes(rows: list, label: str, fmt: str) -> BoxTable:
    a = np.array(rows, dtype=float).reshape(-1, 6)
    order = np.lexsort((a[:, 1], a[:, 0]))
    a = a[order]
    same = (np.diff(a[:, 0]) == 0) & (np.diff(a[:, 1]) == 0)
    if np.any(same):
        k = int(np.flatnonzero(same)[0])
        raise InputError(f"{label}: frame {int(a[k, 0]) + (1 if fmt == 'mot' else 0)}: id {int(a[k, 1])} "
                         "has two boxes")
    return BoxTable(a[:, 0].astype(np.int64), a[:, 1].astype(np.int64), a[:, 2], a[:, 3], a[:, 4],
                    a[:, 5], label, fmt)


# ---------------------------------------------------------------------------- to the floor

@dataclass(frozen=True, eq=False)
class GroundTruthImport:
    """World ground truth from image boxes, and what happened to every box.

    Attributes
    ----------
    table : TrackTable
        The rows kept (see the module docstring for the columns).
    boxes : int — boxes read
    outside : int — boxes whose foot point lies outside the image (after scaling)
    dropped_outside : int — of those, rows left out (``keep_outside=False``)
    unprojectable : int — rows left out because the foot's ray does not meet the floor
    outside_area : int — rows left out because the foot lies outside ``area``
    scale : float — pixel scale applied to the boxes
    fps : float — frame rate used for ``time``
    id_offset : int — added to every id so that ids start at 1 (0 when they already do)
    """

    table: TrackTable
    boxes: int
    outside: int
    dropped_outside: int
    unprojectable: int
    outside_area: int
    scale: float
    fps: float
    id_offset: int = 0


def boxes_to_world(boxes: BoxTable, camera: Camera, scale: float = 1.0, fps: float = PETS_S2L1_FPS,
                   area: ArrayLike | None = None, keep_outside: bool = True) -> GroundTruthImport:
    """Back-project every box's foot point onto the floor ``Z = 0`` through ``camera``.

    Parameters
    ----------
    boxes : BoxTable
        Boxes in pixels of the annotated image.
    camera : Camera
        The scene camera (its lens distortion is undone by :meth:`Camera.backproject`).
    scale : float
        Annotated image → camera image: ``u' = scale·(u + 0.5) − 0.5`` (pixel centres at
        integers, as :meth:`Camera.scaled`); 0.625 for PETS boxes (768x576) on 480x360 video.
    fps : float
        Frames per second; ``time = frame / fps`` seconds.
    area : (M, 2) array_like, metres, optional
        Keep only rows whose floor position lies inside this polygon.
    keep_outside : bool
        Keep rows whose foot point lies outside the image (flagged ``foot_outside = 1``).

    Returns
    -------
    GroundTruthImport
    """
    if not (math.isfinite(scale) and scale > 0):
        raise InputError(f"--scale: expected a positive number, got {scale}")
    if not (math.isfinite(fps) and fps > 0):
        raise InputError(f"--fps: expected a positive frame rate, got {fps}")
    s = float(scale)
    foot = s * (boxes.foot + 0.5) - 0.5                        # u' = s(u + 0.5) − 0.5
    left = s * (boxes.left + 0.5) - 0.5
    top = s * (boxes.top + 0.5) - 0.5
    outside = ~camera.in_image(foot) if len(boxes) else np.zeros(0, bool)
    world = camera.backproject(foot, 0.0) if len(boxes) else np.zeros((0, 3))
    ok = np.all(np.isfinite(world), axis=1)
    keep = ok.copy()
    if not keep_outside:
        keep &= ~outside
    unprojectable = int((~ok).sum())
    dropped_outside = int((ok & outside).sum()) if not keep_outside else 0
    in_area = np.ones(len(boxes), bool)
    if area is not None:
        in_area[ok] = points_in_polygon(world[ok, :2], np.asarray(area, dtype=float))
    outside_area = int((keep & ~in_area).sum())
    keep &= in_area
    extra = {
        "foot_u": foot[keep, 0], "foot_v": foot[keep, 1],
        "foot_outside": outside[keep].astype(np.int64),
        "bb_left": left[keep], "bb_top": top[keep],
        "bb_width": s * boxes.width[keep], "bb_height": s * boxes.height[keep],
    }
    frame = boxes.frame[keep]
    # worldtrack's track ids start at 1; shift annotations that count from 0 (or below).
    id_offset = max(0, 1 - int(boxes.id.min())) if len(boxes) else 0
    table = TrackTable(frame=frame, time=frame / float(fps), id=boxes.id[keep] + id_offset,
                       x=world[keep, 0], y=world[keep, 1], extra=extra, source=boxes.source)
    return GroundTruthImport(table.sorted(), len(boxes), int(outside.sum()), dropped_outside,
                             unprojectable, outside_area, s, float(fps), id_offset)
