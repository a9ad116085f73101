"""A calibration file read by :mod:`worldtrack.io.calibration_formats`, turned into a worldtrack camera:
the world unit decided (declared, or detected from the size of the translation), converted to metres,
Tsai converted to OpenCV's model, and the image rescaled to the video's size.

>>> decide_units(35614.0)[0], decide_units(3.2)[0]
('mm', 'm')
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from worldtrack.errors import InputError
from worldtrack.geometry.camera import Camera
from worldtrack.geometry.tsai import TsaiCamera, TsaiConversion, tsai_to_camera
from worldtrack.io.calibration_formats import CalibrationFile


UNITS = ("auto", "mm", "m")
_TO_METRES = {"mm": 1e-3, "m": 1.0}
_UNIT_NAMES = {"mm": "millimetres", "m": "metres"}
#: ``--units auto``: |t| above this (file units) is millimetres, below ``_METRES_BELOW`` metres.
_MM_ABOVE = 1000.0
_METRES_BELOW = 100.0
#: ``--units mm`` with 0 < |t| below this is a camera within a centimetre of the origin: refused.
_MM_IMPLAUSIBLE = 10.0


@dataclass(frozen=True, eq=False)
class ImportedCamera:
    """A calibration file turned into a worldtrack camera.

    Attributes
    ----------
    camera : Camera
        In metres, for the requested image size.
    native : Camera
        The same camera at the calibration's own image size.
    source : CalibrationFile
    units : {"mm", "m"}
        The world unit of the file.
    units_note : str
        How the units were decided, e.g. ``"millimetres (detected from |t| = 35614), converted
        to metres"``.
    scale : float
        Image scale from the calibration's size to ``camera``'s (1 = none).
    tsai : TsaiCamera or None
        The exact Tsai model (metres) for Tsai files.
    conversion : TsaiConversion or None
        How well the OpenCV model reproduces the Tsai one.
    warnings : list of str
    """

    camera: Camera
    native: Camera
    source: CalibrationFile
    units: str
    units_note: str
    scale: float
    tsai: TsaiCamera | None = None
    conversion: TsaiConversion | None = None
    warnings: list[str] = field(default_factory=list)

    @property
    def metres_per_unit(self) -> float:
        return _TO_METRES[self.units]


def decide_units(translation_norm: float, units: str = "auto") -> tuple[str, str]:
    """The world unit of a calibration and a sentence saying how it was decided.

    Parameters
    ----------
    translation_norm : float
        |t| in the file's units (distance from the camera to the world origin).
    units : {"auto", "mm", "m"}

    Raises
    ------
    InputError
        Unknown ``units``; ``auto`` when |t| is between 100 and 1000 (either unit is
        plausible); ``m`` declared for a camera more than 1 km from the origin, or ``mm`` for one
        less than 1 cm from it (but not at it).
    """
    if units not in UNITS:
        raise InputError(f"--units: expected one of {', '.join(UNITS)}, got {units!r}")
    n = float(translation_norm)
    if units == "auto":
        if n > _MM_ABOVE:
            return "mm", f"millimetres (detected from |t| = {n:.0f}), converted to metres"
        if n < _METRES_BELOW:
            if n == 0:
                return "m", "metres (|t| = 0, the camera is at the world origin; units only affect --check)"
            return "m", f"metres (detected from |t| = {n:.3g})"
        raise InputError(f"cannot tell the units from |t| = {n:.0f} (a camera {n:.0f} m or {n / 1000:.2f} m "
                         "from the world origin); give --units mm or --units m")
    if units == "m" and n > _MM_ABOVE:
        raise InputError(f"--units m puts the camera {n / 1000:.1f} km from the world origin "
                         f"(|t| = {n:.0f}); the file looks like millimetres: use --units mm or auto")
    if units == "mm" and 0 < n < _MM_IMPLAUSIBLE:
        raise InputError(f"--units mm puts the camera {n:.3g} mm from the world origin (|t| = {n:.3g}); "
                         "the file looks like metres: use --units m or auto")
    declared = f"{_UNIT_NAMES[units]} (declared with --units {units}, |t| = {n:.4g})"
    return units, declared + (", converted to metres" if units == "mm" else "")


def import_camera(cal: CalibrationFile, units: str = "auto", camera_id: str | None = None,
                  image_size: tuple[int, int] | None = None, scale: float | None = None,
                  calibration_size: tuple[int, int] | None = None,
                  radial_terms: int | None = None) -> ImportedCamera:
    """Build a worldtrack :class:`Camera` (metres) from a calibration file's parameters.

    Parameters
    ----------
    cal : CalibrationFile
        From :func:`read_calibration`.
    units : {"auto", "mm", "m"}
        World unit of the file (see :func:`decide_units`).
    camera_id : str, optional
        Id of the camera (default: its name in the file; ``cam1``, ``cam2``… for unnamed ones).
    image_size : (int, int), optional
        Size of the images to track on; the camera is rescaled (``Camera.scaled``) to it.
    scale : float, optional
        Or the rescaling factor directly (e.g. 0.625 for 768x576 → 480x360).
    calibration_size : (int, int), optional
        Image size the calibration was made for, when the file does not say.
    radial_terms : {1, 2, 3}, optional
        OpenCV radial terms fitted to a Tsai lens (default: chosen by the fit).

    Raises
    ------
    InputError
        One line: unknown units, image size unknown or of another aspect ratio, a camera below
        the floor…
    """
    label = cal.path if len(cal.cameras) == 1 else f"{cal.path}: camera {cal.camera!r}"
    warnings = list(cal.notes)
    size = cal.image_size
    if calibration_size is not None:
        if size is not None and tuple(size) != tuple(calibration_size):
            warnings.append(f"--calibration-size {calibration_size[0]}x{calibration_size[1]} overrides "
                            f"the file's {size[0]}x{size[1]}")
        size = tuple(calibration_size)
    if size is None:
        raise InputError(f"{label}: the file does not state the image size the calibration is for; "
                         "give --calibration-size WxH (e.g. 768x576); --image-size is the size of "
                         "the images you track on")
    unit, note = decide_units(cal.translation_norm, units)
    k = _TO_METRES[unit]
    cid = camera_id or (f"cam{cal.camera}" if cal.camera.isdigit() else cal.camera)   # unnamed: cam1, cam2…
    tsai = conversion = None
    try:
        if cal.tsai is not None:
            v = cal.tsai
            tsai = TsaiCamera(cid, size[0], size[1], rx=v["rx"], ry=v["ry"], rz=v["rz"],
                              T=np.array([v["tx"], v["ty"], v["tz"]]) * k, focal_mm=v["focal"],
                              kappa1_per_mm2=v["kappa1"], dpx_mm=v["dpx"], dpy_mm=v["dpy"], sx=v["sx"],
                              cx=v["cx"], cy=v["cy"])
            conversion = tsai_to_camera(tsai, radial_terms=radial_terms)
            native = conversion.camera
            if not conversion.monotonic:
                warnings.append("the fitted OpenCV distortion is not monotonic over the image: "
                                "back-projection near the edges is unreliable")
        elif cal.P is not None:
            native = Camera.from_projection(cid, size[0], size[1], cal.P, cal.dist)
            native = Camera(cid, size[0], size[1], native.K, native.R, native.t * k, native.dist)
        else:
            native = Camera(cid, size[0], size[1], cal.K, cal.R, cal.t * k, cal.dist)
    except ValueError as e:
        raise InputError(f"{label}: {e}") from None
    if native.centre[2] <= 0:
        raise InputError(f"{label}: camera centre at Z = {native.centre[2]:.3f} m is at or below the floor "
                         "(expected Z up with the floor at Z = 0)")
    factor = _scale_factor(size, image_size, scale)
    camera = native if factor == 1.0 else native.scaled(factor)
    if image_size is not None and (camera.width, camera.height) != tuple(image_size):
        camera = Camera(cid, image_size[0], image_size[1], camera.K, camera.R, camera.t, camera.dist)
    cx, cy = native.K[0, 2], native.K[1, 2]
    if not (0 <= cx <= size[0] and 0 <= cy <= size[1]):
        warnings.append(f"principal point ({cx:.1f}, {cy:.1f}) px lies outside the {size[0]}x{size[1]} image: "
                        "is the calibration size right?")
    return ImportedCamera(camera, native, cal, unit, note, factor, tsai, conversion, warnings)


def _scale_factor(size: tuple[int, int], image_size: tuple[int, int] | None, scale: float | None) -> float:
    if image_size is not None and scale is not None:
        raise InputError("give --image-size or --scale, not both")
    if scale is not None:
        if not (math.isfinite(scale) and scale > 0):
            raise InputError(f"--scale: expected a positive number, got {scale}")
        return float(scale)
    if image_size is None:
        return 1.0
    sx, sy = image_size[0] / size[0], image_size[1] / size[1]
    if abs(round(size[1] * sx) - image_size[1]) > 1:
        raise InputError(f"--image-size {image_size[0]}x{image_size[1]} has another aspect ratio than the "
                         f"calibration's {size[0]}x{size[1]} (scales {sx:.4f} and {sy:.4f}); worldtrack "
                         "rescales both axes alike")
    return sx
