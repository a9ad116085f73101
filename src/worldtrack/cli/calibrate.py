"""``worldtrack calibrate``: fit a camera to world/image point pairs read from a CSV file.

The I/O edge of :mod:`worldtrack.geometry.calibrate`: reads the points, calls
:func:`~worldtrack.geometry.calibrate.calibrate`, prints the camera block for a scene file and
how well it fits, and optionally writes the block to a file.
"""

from __future__ import annotations

import argparse
import csv
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from worldtrack.errors import InputError
from worldtrack.geometry.calibrate import ADVISED_POINTS, CalibrationResult, calibrate
from worldtrack.scene.load import camera_to_dict

_HEADER = ("X", "Y", "Z", "x", "y")
_SIZE = re.compile(r"^\s*(\d+)\s*[xX×,]\s*(\d+)\s*$")
_SIZE_COMMENT = re.compile(r"^#\s*image[_ ]?size\s*[:=]\s*(.*)$", re.IGNORECASE)

DESCRIPTION = f"""\
Fit a camera (K, R, t and optionally radial lens distortion) to markers whose world positions
you measured and whose image positions you clicked, as the 1999 paper does with its
0.3 x 0.3 x 1.1 m box: a normalised DLT, then refinement of the reprojection error.

POINTS.csv: one header line, then one row per marker:

    # image_size: 640x480          (optional comment; or give --image-size)
    X,Y,Z,x,y
    -1.150,1.250,0.000,293.35,402.56
    ...

  X, Y, Z   world position in metres (Z up, floor Z = 0)
  x, y      image position in pixels (x right, y down, pixel centres at integers)

The header is case-insensitive and must be exactly these five columns in this order. Lines
starting with '#' are comments. At least 6 points, not all on one plane; the paper advises
>= {ADVISED_POINTS}, spread over the image and over heights. Markers on the floor (Z = 0) are also
used to report the floor back-projection error (metres), the paper's accuracy check. For
points all on the floor, give --intrinsics.

Prints the camera block to paste under 'cameras:' in a scene file, the camera centre, a table of
per-point reprojection errors, the RMS error and the floor back-projection error.
"""

EPILOG = """\
example:
  worldtrack calibrate examples/calibration/lab_cam1_points.csv --id cam1 --out cam1.yaml
  worldtrack calibrate examples/calibration/lab_cam2_points.csv --id cam2 --distortion
"""


@dataclass(frozen=True)
class PointsFile:
    """Contents of a calibration CSV.

    Attributes
    ----------
    world : (N, 3) ndarray, metres
    image : (N, 2) ndarray, pixels
    lines : list of int
        The file's line number (from 1) of each point.
    image_size : tuple of int or None
        ``(width, height)`` from an ``# image_size: WxH`` comment.
    """

    world: np.ndarray
    image: np.ndarray
    lines: list[int]
    image_size: tuple[int, int] | None


def _cells(line: str) -> list[str]:
    cells = [c.strip() for c in next(csv.reader([line]))]
    while cells and cells[-1] == "":
        cells.pop()
    return cells


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def read_points(path: str | Path) -> PointsFile:
    """Read a calibration CSV (see ``worldtrack calibrate --help``).

    Raises
    ------
    InputError
        Naming the file, the line and what was expected.
    """
    label = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise InputError(f"{label}: no such file") from None
    except IsADirectoryError:
        raise InputError(f"{label}: is a directory, expected a CSV file") from None
    except UnicodeDecodeError:
        raise InputError(f"{label}: not a text file (expected CSV with header X,Y,Z,x,y)") from None
    except OSError as e:
        raise InputError(f"{label}: cannot read ({e.strerror})") from None

    header_seen = False
    image_size: tuple[int, int] | None = None
    rows: list[list[float]] = []
    lines: list[int] = []
    for n, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line:
            continue
        if line.startswith("#"):
            m = _SIZE_COMMENT.match(line)
            if m:
                size = _SIZE.match(m.group(1))
                if not size or min(int(size.group(1)), int(size.group(2))) <= 0:
                    raise InputError(f"{label}: line {n}: image_size: expected WxH in pixels such as 640x480, "
                                     f"got {m.group(1).strip()!r}")
                image_size = (int(size.group(1)), int(size.group(2)))
            continue
        cells = _cells(line)
        if not header_seen:
            names = [c.lower() for c in cells]
            expected = [h.lower() for h in _HEADER]
            if names == expected:
                header_seen = True
                continue
            if cells and all(_is_number(c) for c in cells):
                raise InputError(f"{label}: line {n}: expected the header X,Y,Z,x,y before the numbers")
            if names[:5] == expected:
                extra = ", ".join(repr(c) for c in cells[5:])
                raise InputError(f"{label}: line {n}: unexpected column(s) {extra}; expected exactly X,Y,Z,x,y")
            raise InputError(f"{label}: line {n}: expected the header X,Y,Z,x,y (world metres, image pixels), "
                             f"got {','.join(cells)!r}")
        if len(cells) != 5:
            raise InputError(f"{label}: line {n}: expected 5 values X,Y,Z,x,y, got {len(cells)}")
        values = []
        for name, cell in zip(_HEADER, cells):
            try:
                values.append(float(cell))
            except ValueError:
                raise InputError(f"{label}: line {n}: column {name}: expected a number, got {cell!r}") from None
        rows.append(values)
        lines.append(n)
    if not header_seen:
        raise InputError(f"{label}: expected a header line X,Y,Z,x,y and at least 6 rows of points, "
                         "got no header")
    data = np.array(rows, dtype=float).reshape(-1, 5)
    return PointsFile(data[:, :3], data[:, 3:], lines, image_size)


def _parse_size(text: str) -> tuple[int, int]:
    m = _SIZE.match(text)
    if not m or min(int(m.group(1)), int(m.group(2))) <= 0:
        raise InputError(f"--image-size: expected WxH in pixels such as 640x480, got {text!r}")
    return int(m.group(1)), int(m.group(2))


def _parse_intrinsics(text: str) -> list[float]:
    parts = [p.strip() for p in text.split(",")]
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) != 4 or not all(math.isfinite(v) for v in values) or min(values[:2]) <= 0:
        raise InputError(f"--intrinsics: expected fx,fy,cx,cy in pixels with fx, fy > 0 "
                         f"(e.g. 554.3,554.3,319.5,239.5), got {text!r}")
    return values


def camera_block(result: CalibrationResult) -> str:
    """The fitted camera as YAML, a one-item list indented to paste under ``cameras:``."""
    text = yaml.safe_dump([camera_to_dict(result.camera)], sort_keys=False, default_flow_style=None)
    return "".join("  " + line for line in text.splitlines(keepends=True))


def _m(x: float, nd: int = 3) -> str:
    return "n/a" if not math.isfinite(x) else f"{x:.{nd}f} m"


def format_report(result: CalibrationResult, points: PointsFile, label: str) -> str:
    """Everything ``worldtrack calibrate`` prints to standard output."""
    cam = result.camera
    K = cam.K
    out = [f"calibrated {cam.id!r} from {result.n_points} points in {label} ({cam.width}x{cam.height} px)", "",
           "camera block (paste under 'cameras:' in a scene file):", camera_block(result).rstrip("\n"), ""]
    c = cam.centre
    hfov_deg = math.degrees(2 * math.atan2(cam.width / 2, K[0, 0]))
    out.append(f"camera centre: ({c[0]:.3f}, {c[1]:.3f}, {c[2]:.3f}) m")
    out.append(f"focal length: fx = {K[0, 0]:.2f} px, fy = {K[1, 1]:.2f} px (horizontal field of view "
               f"{hfov_deg:.1f} deg); principal point ({K[0, 2]:.2f}, {K[1, 2]:.2f}) px")
    if cam.has_distortion:
        k1, k2, _, _, k3 = cam.dist
        terms = f"k1 = {k1:.4f}, k2 = {k2:.4f}" + (f", k3 = {k3:.4f}" if k3 else "")
        out.append(f"lens distortion (radial): {terms}")
    else:
        out.append("lens distortion: none fitted (--distortion fits radial k1, k2)")
    out.append("")

    floor_err = np.full(result.n_points, np.nan)
    floor_err[result.on_floor] = result.floor_errors
    where = np.full(result.n_points, "", dtype=object)
    where[result.on_floor] = np.where(result.floor_in_centre, "centre", "edge")
    out.append("   #  line     X (m)    Y (m)    Z (m)    x (px)    y (px)  error (px)  floor error (m)")
    for i in range(result.n_points):
        X, Y, Z = points.world[i]
        u, v = points.image[i]
        fe = f"{floor_err[i]:15.3f} {where[i]}" if result.on_floor[i] else ""
        out.append(f"{i + 1:4d}  {points.lines[i]:4d}  {X:8.3f} {Y:8.3f} {Z:8.3f}  {u:8.2f}  {v:8.2f}"
                   f"  {result.per_point_error[i]:10.2f}  {fe}".rstrip())
    out.append("")
    worst = int(np.argmax(result.per_point_error))
    out.append(f"reprojection error: RMS {result.rms:.3f} px, max {result.per_point_error[worst]:.3f} px "
               f"(line {points.lines[worst]})")
    n_floor = int(result.on_floor.sum())
    if n_floor:
        n_centre = int(result.floor_in_centre.sum())
        out.append(f"floor back-projection error ({n_floor} points at Z = 0): mean {_m(result.floor_error_mean)}; "
                   f"image centre {_m(result.floor_error_centre)} ({n_centre} points), "
                   f"image edge {_m(result.floor_error_edge)} ({n_floor - n_centre} points)")
    else:
        out.append("floor back-projection error: n/a (no points at Z = 0)")
    out.append(f"result: {result.message}")
    if result.warnings:
        out.append("warnings:")
        out.extend(f"  - {w}" for w in result.warnings)
    return "\n".join(out) + "\n"


def run(args: argparse.Namespace) -> int:
    label = str(args.points)
    points = read_points(args.points)
    extra_warnings: list[str] = []
    if args.image_size is not None:
        size = _parse_size(args.image_size)
        if points.image_size is not None and points.image_size != size:
            extra_warnings.append(f"--image-size {size[0]}x{size[1]} overrides the file's image_size "
                                  f"{points.image_size[0]}x{points.image_size[1]}")
    elif points.image_size is not None:
        size = points.image_size
    else:
        raise InputError(f"{label}: image size unknown; give --image-size WxH (e.g. 640x480) or add a line "
                         "'# image_size: 640x480' to the file")
    intrinsics = _parse_intrinsics(args.intrinsics) if args.intrinsics is not None else None
    distortion: bool | int = bool(args.distortion)
    if args.radial_terms is not None:
        if args.radial_terms.strip() not in ("1", "2", "3"):
            raise InputError(f"--radial-terms: expected 1, 2 or 3, got {args.radial_terms!r}")
        distortion = int(args.radial_terms)
    try:
        result = calibrate(points.world, points.image, size[0], size[1], camera_id=args.id,
                           distortion=distortion, intrinsics=intrinsics,
                           point_names=[f"line {n}" for n in points.lines])
    except InputError as e:
        raise InputError(f"{label}: {e}") from None
    result.warnings.extend(extra_warnings)
    print(format_report(result, points, label), end="")
    if not result.success:
        raise InputError(f"{label}: calibration failed: {result.message}")
    if args.out is not None:
        c = result.camera.centre
        header = (f"# camera {result.camera.id!r} calibrated by worldtrack from {label}: centre "
                  f"({c[0]:.3f}, {c[1]:.3f}, {c[2]:.3f}) m, RMS {result.rms:.3f} px\n"
                  "# paste under 'cameras:' in a scene file\n")
        try:
            Path(args.out).write_text(header + camera_block(result))
        except OSError as e:
            raise InputError(f"{args.out}: cannot write ({e.strerror})") from None
        print(f"wrote {args.out}")
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("calibrate", help="fit a camera to world/image point pairs (CSV)",
                              description=DESCRIPTION, epilog=EPILOG,
                              formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("points", metavar="POINTS.csv", help="CSV with header X,Y,Z,x,y (metres, pixels)")
    p.add_argument("--image-size", metavar="WxH",
                   help="image size in pixels, e.g. 640x480 (default: the file's '# image_size:' comment)")
    p.add_argument("--id", default="cam", metavar="CAM", help="camera id in the printed block (default: cam)")
    p.add_argument("--distortion", action="store_true",
                   help="also fit radial lens distortion k1, k2 (wide-angle lenses)")
    p.add_argument("--radial-terms", metavar="N",
                   help="fit N radial distortion terms k1..kN (1-3; 3 needs >= 20 points); implies --distortion")
    p.add_argument("--intrinsics", metavar="fx,fy,cx,cy",
                   help="known intrinsics in pixels, held fixed; needed when all points lie on one plane")
    p.add_argument("--out", metavar="camera.yaml", help="also write the camera block to this file")
    p.set_defaults(func=run)
