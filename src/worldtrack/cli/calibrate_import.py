"""``worldtrack calibrate --import FILE``: a calibration another tool wrote, read, converted and reported.

Reads the file (:mod:`worldtrack.io.calibration_formats`), turns it into a worldtrack camera
(:mod:`worldtrack.io.calibration_import`: units stated, metres, OpenCV's lens model, the video's image
size), prints the camera block with how the units were decided and how well the lens conversion and
any ``--check`` points agree, and optionally writes the block with ``--out``. The point-fitting half
of the command, and its arguments, are in :mod:`worldtrack.cli.calibrate`.
"""

from __future__ import annotations

import argparse
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from worldtrack.cli._args import parse_size, positive
from worldtrack.cli.calibrate import _block, _camera_lines, _parse_radial_terms, _write_out
from worldtrack.errors import InputError

if TYPE_CHECKING:   # NumPy, and the import modules load SciPy: imported where they run
    import numpy as np

    from worldtrack.io.calibration_import import ImportedCamera


@dataclass(frozen=True)
class CheckPoint:
    """A ``--check X,Y,Z[,u,v]`` point: world (file units) and optionally its pixel."""

    world: np.ndarray
    pixel: np.ndarray | None
    text: str


def parse_check(text: str) -> CheckPoint:
    """``X,Y,Z`` or ``X,Y,Z,u,v`` → :class:`CheckPoint`."""


    import numpy as np
    parts = [p.strip() for p in text.split(",")]
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) not in (3, 5) or not all(math.isfinite(v) for v in values):
        raise InputError(f"--check: expected X,Y,Z or X,Y,Z,u,v (world in the file's unit, pixels), got {text!r}")
    return CheckPoint(np.array(values[:3]), np.array(values[3:]) if len(values) == 5 else None, text)


def _parse_scale(text: str | None) -> float | None:
    return None if text is None else positive(text, "--scale", "0.625")


def _fmt_uv(uv: np.ndarray) -> str:


    import numpy as np
    return "outside the lens model" if not np.all(np.isfinite(uv)) else f"({uv[0]:.2f}, {uv[1]:.2f}) px"


def import_command(args: argparse.Namespace) -> str:
    """The command line that reproduces this import (for the header of ``--out``)."""
    parts = ["worldtrack calibrate --import", str(args.import_file)]
    for flag, value in (("--camera", args.camera), ("--units", args.units), ("--image-size", args.image_size),
                        ("--scale", args.scale), ("--calibration-size", args.calibration_size),
                        ("--radial-terms", args.radial_terms), ("--id", args.id)):
        if value is not None:
            parts.append(f"{flag} {value}")
    parts += [f"--check={c}" for c in args.check]
    if args.out is not None:
        parts.append(f"--out {args.out}")
    return " ".join(parts)


def format_import_report(imp: ImportedCamera, checks: list[CheckPoint]) -> str:
    """Everything ``worldtrack calibrate --import`` prints to standard output."""


    import numpy as np
    cal, cam, native = imp.source, imp.camera, imp.native
    which = f" camera {cal.camera!r}" if len(cal.cameras) > 1 else ""
    out = [f"imported{which} from {cal.path}: {cal.format_name}, calibrated for "
           f"{native.width}x{native.height} px",
           f"units: {imp.units_note}"]
    conv = imp.conversion
    if conv is not None:
        terms = ", ".join(f"k{i}" for i in (1, 2, 3)[:conv.radial_terms])
        out.append(f"lens: Tsai kappa1 = {imp.tsai.kappa1_per_mm2:.6g} /mm^2 on distorted sensor coordinates, "
                   f"converted to OpenCV radial {terms} by least squares over the image "
                   f"(+{conv.margin:.0%} margin, {conv.n_points} points)")
        out.append(f"Tsai -> OpenCV fit error: max {conv.max_error_px:.4f} px over every image pixel "
                   f"(RMS {conv.rms_error_px:.4f} px); max {conv.max_error_margin_px:.4f} px including the margin")
    if imp.scale != 1.0:
        out.append(f"rescaled by {imp.scale:g} to {cam.width}x{cam.height} px (pixel centres at integers: "
                   "u' = s(u + 0.5) - 0.5)")
    out += ["", "camera block (paste under 'cameras:' in a scene file):",
            _block(cam).rstrip("\n"), ""]
    out += _camera_lines(cam, at=f" at {cam.width}x{cam.height}")
    if cam.has_distortion:
        k1, k2, p1, p2, k3 = cam.dist
        out.append(f"lens distortion: k1 = {k1:.5f}, k2 = {k2:.5f}, p1 = {p1:.5f}, p2 = {p2:.5f}, k3 = {k3:.5f}")
    else:
        out.append("lens distortion: none")
    for chk in checks:
        world_m = chk.world * imp.metres_per_unit
        X, Y, Z = chk.world
        line = f"check ({X:g}, {Y:g}, {Z:g}) {imp.units}: "
        uv = native.project(world_m)
        if imp.tsai is not None:
            exact = imp.tsai.project(world_m)
            line += f"Tsai model {_fmt_uv(exact)}, converted camera {_fmt_uv(uv)}"
        else:
            line += f"projects to {_fmt_uv(uv)}"
        line += f" at {native.width}x{native.height}"
        if chk.pixel is not None:
            ref = imp.tsai.project(world_m) if imp.tsai is not None else uv
            err = float(np.linalg.norm(ref - chk.pixel))
            line += f"; given ({chk.pixel[0]:g}, {chk.pixel[1]:g}): error {err:.2f} px" if math.isfinite(err) else ""
        if imp.scale != 1.0:
            line += f"; {_fmt_uv(cam.project(world_m))} at {cam.width}x{cam.height}"
        out.append(line)
    if imp.warnings:
        out.append("warnings:")
        out.extend(f"  - {w}" for w in imp.warnings)
    return "\n".join(out) + "\n"


def run_import(args: argparse.Namespace) -> int:
    from worldtrack.io.calibration_formats import read_calibration
    from worldtrack.io.calibration_import import UNITS, import_camera
    if args.distortion or args.intrinsics is not None:
        raise InputError("--distortion and --intrinsics fit points; they do not apply with --import")
    radial_terms = _parse_radial_terms(args.radial_terms)
    units = "auto" if args.units is None else args.units.strip().lower()
    if units not in UNITS:
        raise InputError(f"--units: expected mm, m or auto, got {args.units!r}")
    image_size = parse_size(args.image_size, "--image-size", "640x480") if args.image_size is not None else None
    calibration_size = (parse_size(args.calibration_size, "--calibration-size", "768x576")
                        if args.calibration_size is not None else None)
    scale = _parse_scale(args.scale)
    if scale is not None and image_size is not None:
        raise InputError("give --image-size or --scale, not both")
    checks = [parse_check(c) for c in args.check]
    cal = read_calibration(args.import_file, args.camera)
    try:
        imp = import_camera(cal, units=units, camera_id=args.id, image_size=image_size, scale=scale,
                            calibration_size=calibration_size, radial_terms=radial_terms)
    except InputError as e:          # about this file: name it once
        text = str(e)
        raise InputError(text if text.startswith(cal.path) else f"{cal.path}: {text}") from None
    print(format_import_report(imp, checks), end="")
    if args.out is not None:
        c = imp.camera.centre
        header = (f"# camera {imp.camera.id!r} imported by worldtrack from {cal.path}: {cal.format_name}\n"
                  f"# units: {imp.units_note}\n")
        if imp.conversion is not None:
            header += (f"# Tsai lens converted to OpenCV radial terms: max error {imp.conversion.max_error_px:.4f} px "
                       "over the image\n")
        header += (f"# centre ({c[0]:.3f}, {c[1]:.3f}, {c[2]:.3f}) m; {imp.camera.width}x{imp.camera.height} px\n"
                   f"# made with: {import_command(args)}\n"
                   "# paste under 'cameras:' in a scene file\n")
        _write_out(args.out, header + _block(imp.camera))
    return 0
