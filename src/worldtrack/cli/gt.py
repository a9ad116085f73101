"""``worldtrack gt import``: image-box ground truth (CVML XML, MOTChallenge) → world ``gt.csv``.

The I/O edge of :mod:`worldtrack.io.gt_import`: reads the boxes and the scene, back-projects the
foot points through the scene camera onto the floor, writes ``gt.csv`` and prints a summary.
"""

from __future__ import annotations

import argparse
import sys

from worldtrack.cli._args import parse_size, positive
from worldtrack.cli.eval import read_area
from worldtrack.errors import InputError

DESCRIPTION = """\
Turn ground truth annotated as boxes in one camera's image into world ground truth (metres on
the floor) that 'worldtrack eval' reads: each box's foot point (middle of its bottom edge) is
back-projected through the scene camera, lens distortion undone, onto the floor Z = 0.

GT formats: CVML XML (PETS 2009, Milan: <frame number><objectlist><object id><box xc yc w h>)
and MOTChallenge text (frame,id,bb_left,bb_top,bb_width,bb_height,...; frames and pixels from 1).

Writes gt.csv: frame,time,id,x,y,foot_u,foot_v,foot_outside,bb_left,bb_top,bb_width,bb_height
(time = frame / fps in seconds; foot_u, foot_v and the box in pixels of the scene camera's image;
foot_outside = 1 when the foot point lies outside the image - the annotator guessed where the
feet are, so the world position is less reliable. Those rows are kept (they are people in the
scene) unless --drop-outside.)
"""

EPILOG = """\
example (PETS 2009 S2.L1: GT in 768x576 pixels, video and scene camera at 480x360, 7 fps):
  worldtrack gt import PETS2009-S2L1.xml --scene examples/scenes/pets2009_view001.yaml \\
      --camera View_001 --scale 0.625 --fps 7 --out gt.csv
"""


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("gt", help="ground-truth tools: import image-box GT (CVML, MOTChallenge) as world GT",
                       description="Ground-truth tools.")
    verbs = p.add_subparsers(dest="gt_command", metavar="<gt command>", required=True)
    c = verbs.add_parser("import", help="image boxes (CVML XML, MOTChallenge) -> world gt.csv",
                         description=DESCRIPTION, epilog=EPILOG,
                         formatter_class=argparse.RawDescriptionHelpFormatter)
    c.add_argument("gt", metavar="GT", help="ground truth: CVML XML or MOTChallenge text")
    c.add_argument("--scene", required=True, metavar="SCENE.yaml", help="scene file with the camera")
    c.add_argument("--camera", metavar="CAM", help="scene camera the boxes were annotated in "
                                                   "(default: the scene's only camera)")
    c.add_argument("--out", required=True, metavar="gt.csv", help="world ground truth to write")
    c.add_argument("--scale", metavar="F", help="GT pixels -> camera pixels (e.g. 0.625 for 768x576 GT on "
                                                "a 480x360 camera); default 1")
    c.add_argument("--gt-size", metavar="WxH", help="or: the image size the GT was annotated at "
                                                    "(scale = camera width / W)")
    c.add_argument("--fps", default="7", metavar="FPS",
                   help="frame rate for the time column (default 7: PETS 2009 S2.L1's capture rate, as "
                        "MOTChallenge and Milan use; the AVI header's 10 is not)")
    c.add_argument("--area", metavar="AREA",
                   help="keep only people inside this floor polygon: a file (x1,y1,x2,y2,... metres, '#' "
                        "comments) or the numbers themselves")
    c.add_argument("--drop-outside", action="store_true",
                   help="leave out boxes whose foot point is outside the image")
    c.add_argument("--format", default="auto", metavar="auto|cvml|mot",
                   help="GT format (default auto: XML -> cvml, else mot)")
    c.add_argument("--pixel-origin", default=None, metavar="0|1",
                   help="pixel coordinate of the first pixel centre in MOTChallenge files (default 1)")
    c.set_defaults(func=run_import)


def run_import(args: argparse.Namespace) -> int:
    from worldtrack.io.gt_import import boxes_to_world, read_boxes
    from worldtrack.io.tracks import write_tracks
    from worldtrack.scene import load_scene

    fps = positive(args.fps, "--fps", "7")
    if args.scale is not None and args.gt_size is not None:
        raise InputError("give --scale or --gt-size, not both")
    area = read_area(args.area) if args.area else None
    scene = load_scene(args.scene)
    if args.camera is None:
        if len(scene.cameras) != 1:
            raise InputError(f"{args.scene}: has {len(scene.cameras)} cameras ({', '.join(scene.cameras)}); "
                             "choose the one the GT was annotated in with --camera")
        camera = next(iter(scene.cameras.values()))
    else:
        camera = scene.camera(args.camera)
    if args.gt_size is not None:
        gt_width, gt_height = parse_size(args.gt_size, "--gt-size", "768x576")
        scale = camera.width / gt_width
        if abs(gt_height * scale - camera.height) > 1:
            raise InputError(f"--gt-size {args.gt_size}: another aspect ratio than camera {camera.id!r} "
                             f"({camera.width}x{camera.height})")
    else:
        scale = positive(args.scale, "--scale", "0.625") if args.scale is not None else 1.0
    if args.pixel_origin not in (None, "0", "1"):
        raise InputError(f"--pixel-origin: expected 0 or 1, got {args.pixel_origin!r}")
    pixel_origin = None if args.pixel_origin is None else int(args.pixel_origin)
    boxes = read_boxes(args.gt, args.format, pixel_origin)
    result = boxes_to_world(boxes, camera, scale=scale, fps=fps, area=area,
                            keep_outside=not args.drop_outside)
    write_tracks(args.out, result.table)

    t = result.table
    print(f"read {result.boxes} boxes ({boxes.format.upper()}) from {args.gt}"
          + (f"; {boxes.dropped} rows with 'consider' = 0 left out" if boxes.dropped else ""))
    print(f"camera {camera.id!r} ({camera.width}x{camera.height} px), GT pixels scaled by {scale:g}, "
          f"time = frame / {fps:g} fps")
    outside_note = (f"{result.dropped_outside} left out (--drop-outside)" if args.drop_outside
                    else "kept, flagged foot_outside = 1")
    print(f"foot points outside the image: {result.outside} ({outside_note})")
    if result.unprojectable:
        print(f"foot points whose ray misses the floor (left out): {result.unprojectable}")
    if area is not None:
        print(f"outside the --area polygon (left out): {result.outside_area}")
    if result.id_offset:
        print(f"ids shifted by +{result.id_offset} so that they start at 1")
    if len(t):
        print(f"wrote {args.out}: {len(t)} rows, {len(t.ids())} ids, frames {t.frame.min()}-{t.frame.max()}, "
              f"x {t.x.min():.2f}..{t.x.max():.2f} m, y {t.y.min():.2f}..{t.y.max():.2f} m")
    else:
        print(f"wrote {args.out}: no rows")
    if result.outside > 0.2 * max(result.boxes, 1) and not args.drop_outside:
        print(f"warning: {result.outside / result.boxes:.0%} of the foot points are outside the image; "
              "is --scale (or --gt-size) right?", file=sys.stderr)
    return 0
