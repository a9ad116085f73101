"""``worldtrack calibrate``: fit a camera to world/image point pairs, or import a calibration file.

The I/O edge of :mod:`worldtrack.geometry.calibrate`: reads the points, calls
:func:`~worldtrack.geometry.calibrate.calibrate`, prints the camera block for a scene file and
how well it fits, and optionally writes the block to a file.

With ``--import FILE`` it instead reads a calibration another tool wrote (Tsai XML as PETS ships
it, OpenCV FileStorage YAML/XML, JSON K/R/t, 3x4 matrices as text; see
:mod:`worldtrack.io.calibration_formats`), states the units it found, converts to metres and to
worldtrack's OpenCV camera model, rescales to the video's size and prints the same camera block.
"""

from __future__ import annotations

import argparse
import csv
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from worldtrack.cli._args import parse_size
from worldtrack.errors import InputError
from worldtrack.io.text import is_number, read_text

if TYPE_CHECKING:   # NumPy, and the fitting and import modules load SciPy: imported where they run
    import numpy as np

    from worldtrack.geometry.calibrate import CalibrationResult
    from worldtrack.geometry.camera import Camera

#: worldtrack.geometry.calibrate.ADVISED_POINTS, repeated here so ``--help`` need not load SciPy
#: (tests/cli check that the two agree).
ADVISED_POINTS = 20
#: Largest points file read (bytes; 100 000 points take about 4 MB).
MAX_POINTS_FILE_BYTES = 20_000_000

_HEADER = ("X", "Y", "Z", "x", "y")
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

--import FILE instead reads a calibration made by another tool and prints the same block:
  Tsai XML (PETS 2009 View_00N.xml; its radial lens model is converted to OpenCV k1, k2, k3 by a
  least-squares fit over the image, whose error is printed), OpenCV FileStorage YAML/XML
  (camera_matrix, distortion_coefficients, rvec/tvec or R/t), JSON with K, R, t (+ dist), one
  camera or several by name (--camera), or 3x4 projection matrices as text. The world unit is
  declared with --units or detected from the size of the translation (|t| > 1000 means
  millimetres, < 100 metres) and stated. --image-size WxH (or --scale F) rescales the camera to
  the images you track on (e.g. a 768x576 calibration for a 480x360 video). --check X,Y,Z,u,v
  reprojects a known point (X, Y, Z in the file's unit; u, v in pixels of the calibration's image).
"""

EPILOG = """\
examples:
  worldtrack calibrate examples/calibration/lab_cam1_points.csv --id cam1 --out cam1.yaml
  worldtrack calibrate examples/calibration/lab_cam2_points.csv --id cam2 --distortion
  worldtrack calibrate --import View_001.xml --image-size 480x360 --check=-4140,-7400,0,514.8,232.0
  worldtrack calibrate --import calibration.json --camera View_001 --calibration-size 768x576 --scale 0.625
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


def read_points(path: str | Path) -> PointsFile:
    """Read a calibration CSV (see ``worldtrack calibrate --help``).

    Raises
    ------
    InputError
        Naming the file, the line and what was expected.
    """
    import numpy as np

    label = str(path)
    try:
        size = Path(path).stat().st_size
    except OSError:
        size = 0                                # read_text names the problem
    if size > MAX_POINTS_FILE_BYTES:
        raise InputError(f"{label}: {size:,} bytes; a points file may have at most {MAX_POINTS_FILE_BYTES:,}")
    text = read_text(path, "CSV with header X,Y,Z,x,y", directory="a CSV file")

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
                image_size = parse_size(m.group(1).strip(), f"{label}: line {n}: image_size", "640x480")
            continue
        try:
            cells = _cells(line)
        except csv.Error as e:
            raise InputError(f"{label}: line {n}: not valid CSV ({e})") from None
        if not header_seen:
            names = [c.lower() for c in cells]
            expected = [h.lower() for h in _HEADER]
            if names == expected:
                header_seen = True
                continue
            if cells and all(is_number(c) for c in cells):
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


def _parse_radial_terms(text: str | None) -> int | None:
    """``--radial-terms``: 1, 2 or 3, or None when not given."""
    if text is None:
        return None
    if text.strip() not in ("1", "2", "3"):
        raise InputError(f"--radial-terms: expected 1, 2 or 3, got {text!r}")
    return int(text)


def camera_block(result: CalibrationResult) -> str:
    """The fitted camera as YAML, a one-item list indented to paste under ``cameras:``."""
    return _block(result.camera)


def _m(x: float, nd: int = 3) -> str:
    return "n/a" if not math.isfinite(x) else f"{x:.{nd}f} m"


def format_report(result: CalibrationResult, points: PointsFile, label: str) -> str:
    """Everything ``worldtrack calibrate`` prints to standard output."""


    import numpy as np
    cam = result.camera
    out = [f"calibrated {cam.id!r} from {result.n_points} points in {label} ({cam.width}x{cam.height} px)", "",
           "camera block (paste under 'cameras:' in a scene file):", camera_block(result).rstrip("\n"), ""]
    out += _camera_lines(cam)
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
    import numpy as np

    if args.import_file is not None:
        if args.points is not None:
            raise InputError(f"give either POINTS.csv ({args.points}) or --import FILE, not both")
        from worldtrack.cli.calibrate_import import run_import
        return run_import(args)
    if args.points is None:
        raise InputError("expected POINTS.csv (world/image point pairs) or --import FILE (a calibration file)")
    stray = [flag for flag, value in (("--camera", args.camera), ("--units", args.units),
                                      ("--scale", args.scale), ("--check", args.check),
                                      ("--calibration-size", args.calibration_size)) if value]
    if stray:
        raise InputError(f"{stray[0]} only applies with --import FILE")
    if args.id is None:
        args.id = "cam"
    label = str(args.points)
    points = read_points(args.points)
    extra_warnings: list[str] = []
    if args.image_size is not None:
        size = parse_size(args.image_size, "--image-size", "640x480")
        if points.image_size is not None and points.image_size != size:
            extra_warnings.append(f"--image-size {size[0]}x{size[1]} overrides the file's image_size "
                                  f"{points.image_size[0]}x{points.image_size[1]}")
    elif points.image_size is not None:
        size = points.image_size
    else:
        raise InputError(f"{label}: image size unknown; give --image-size WxH (e.g. 640x480) or add a line "
                         "'# image_size: 640x480' to the file")
    intrinsics = _parse_intrinsics(args.intrinsics) if args.intrinsics is not None else None
    radial_terms = _parse_radial_terms(args.radial_terms)
    distortion: bool | int = bool(args.distortion) if radial_terms is None else radial_terms
    from worldtrack.geometry.calibrate import calibrate
    try:
        result = calibrate(points.world, points.image, size[0], size[1], camera_id=args.id,
                           distortion=distortion, intrinsics=intrinsics,
                           point_names=[f"line {n}" for n in points.lines])
    except InputError as e:
        raise InputError(f"{label}: {e}") from None
    except (np.linalg.LinAlgError, FloatingPointError, OverflowError) as e:   # degenerate beyond the checks
        raise InputError(f"{label}: these points do not determine a camera (the fit failed numerically: "
                         f"{e}); check for repeated or mistyped points") from None
    result.warnings.extend(extra_warnings)
    print(format_report(result, points, label), end="")
    if not result.success:
        raise InputError(f"{label}: calibration failed: {result.message}")
    if args.out is not None:
        c = result.camera.centre
        header = (f"# camera {result.camera.id!r} calibrated by worldtrack from {label}: centre "
                  f"({c[0]:.3f}, {c[1]:.3f}, {c[2]:.3f}) m, RMS {result.rms:.3f} px\n"
                  "# paste under 'cameras:' in a scene file\n")
        _write_out(args.out, header + camera_block(result))
    return 0


def _camera_lines(cam: Camera, at: str = "") -> list[str]:
    """The camera centre and focal-length lines of both reports; ``at`` follows ``fy = … px``."""
    c, K = cam.centre, cam.K
    hfov_deg = math.degrees(2 * math.atan2(cam.width / 2, K[0, 0]))
    return [f"camera centre: ({c[0]:.3f}, {c[1]:.3f}, {c[2]:.3f}) m",
            f"focal length: fx = {K[0, 0]:.2f} px, fy = {K[1, 1]:.2f} px{at} (horizontal field of view "
            f"{hfov_deg:.1f} deg); principal point ({K[0, 2]:.2f}, {K[1, 2]:.2f}) px"]


def _write_out(path: str, text: str) -> None:
    """Write ``--out`` and say so."""
    try:
        Path(path).write_text(text)
    except OSError as e:
        raise InputError(f"{path}: cannot write ({e.strerror})") from None
    print(f"wrote {path}")


def _block(camera: Camera) -> str:
    """A camera as YAML, a one-item list indented to paste under ``cameras:``."""
    import yaml

    from worldtrack.scene.load import camera_to_dict
    text = yaml.safe_dump([camera_to_dict(camera)], sort_keys=False, default_flow_style=None)
    return "".join("  " + line for line in text.splitlines(keepends=True))


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("calibrate", help="fit a camera to point pairs (CSV) or import a calibration file",
                              usage="worldtrack calibrate POINTS.csv [options]\n"
                                    "       worldtrack calibrate --import FILE [options]",
                              description=DESCRIPTION, epilog=EPILOG,
                              formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("points", metavar="POINTS.csv", nargs="?",
                   help="CSV with header X,Y,Z,x,y (metres, pixels); required unless --import")
    p.add_argument("--image-size", metavar="WxH",
                   help="image size in pixels, e.g. 640x480 (default: the file's '# image_size:' comment); "
                        "with --import: the size of the images you track on (the camera is rescaled)")
    p.add_argument("--id", default=None, metavar="CAM",
                   help="camera id in the printed block (default: cam; with --import the file's camera name)")
    p.add_argument("--distortion", action="store_true",
                   help="also fit radial lens distortion k1, k2 (wide-angle lenses)")
    p.add_argument("--radial-terms", metavar="N",
                   help="fit N radial distortion terms k1..kN (1-3; 3 needs >= 20 points); implies --distortion. "
                        "With --import of a Tsai file: the OpenCV terms fitted to its lens (default: chosen)")
    p.add_argument("--intrinsics", metavar="fx,fy,cx,cy",
                   help="known intrinsics in pixels, held fixed; needed when all points lie on one plane")
    p.add_argument("--out", metavar="camera.yaml", help="also write the camera block to this file")
    g = p.add_argument_group("importing a calibration file")
    g.add_argument("--import", dest="import_file", metavar="FILE",
                   help="read a calibration file instead of fitting points")
    g.add_argument("--camera", metavar="NAME", help="camera of a multi-camera file (e.g. View_001)")
    g.add_argument("--units", metavar="mm|m|auto", help="world unit of the file (default: auto, detected "
                                                        "from |t| and stated)")
    g.add_argument("--scale", metavar="F", help="rescale the camera by F (e.g. 0.625 for 768x576 -> 480x360); "
                                                "or give --image-size")
    g.add_argument("--calibration-size", metavar="WxH",
                   help="image size the calibration was made for, when the file does not say")
    g.add_argument("--check", action="append", default=[], metavar="X,Y,Z[,u,v]",
                   help="reproject a world point (file units, see --units) and compare with pixel (u, v) "
                        "of the calibration's image; repeatable. Write --check=-4140,... for a negative X")
    p.set_defaults(func=run)
