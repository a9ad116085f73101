"""``worldtrack track SCENE --video CAM=PATH …``: track people and write tracks, videos and a plan."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from worldtrack.errors import InputError
from worldtrack.io.sources import VideoSource, read_image
from worldtrack.pipeline import FOREGROUNDS, background_from_video, make_foregrounds, run_tracking
from worldtrack.scene import load_scene
from worldtrack.trackers import METHODS, make_tracker


def _pair(text: str, what: str) -> tuple[str, str]:
    if "=" not in text:
        raise InputError(f"{what} {text!r}: expected CAMERA=PATH")
    cam, path = text.split("=", 1)
    return cam.strip(), path.strip()


def _init(text: str) -> tuple[int, float, float]:
    parts = text.split(",")
    try:
        tid, x, y = int(parts[0]), float(parts[1]), float(parts[2])
    except (ValueError, IndexError):
        raise InputError(f"--init {text!r}: expected ID,X,Y (integer id, metres)") from None
    if tid < 1 or len(parts) != 3:
        raise InputError(f"--init {text!r}: expected ID,X,Y with an id from 1")
    return tid, x, y


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "track", help="track people in videos of a calibrated scene",
        description="Track people in world coordinates. Writes DIR/tracks.csv (one row per person per "
                    "frame, flushed as it goes), DIR/<camera>_annotated.mp4 and DIR/floorplan.png.")
    p.add_argument("scene", help="scene YAML file")
    p.add_argument("--video", action="append", default=[], metavar="CAM=PATH",
                   help="video file or folder of images for camera CAM (repeat for several cameras)")
    p.add_argument("--background", action="append", default=[], metavar="CAM=PNG",
                   help="empty-scene image for CAM; default: <video folder>/<CAM>_background.png if "
                        "present, else the temporal median of frames sampled over the video")
    p.add_argument("--out", default="out", metavar="DIR", help="output folder (default: out)")
    p.add_argument("--method", choices=METHODS, default="ellipsoid", help="tracker (default: ellipsoid)")
    p.add_argument("--preset", choices=("default", "paper"), default="default",
                   help="'paper': the method exactly as published; 'default': with worldtrack's extensions")
    p.add_argument("--foreground", choices=FOREGROUNDS, default="colour",
                   help="foreground model: colour (default; with cast shadows set aside) or grey difference "
                        "against the background with a fixed threshold (the paper's), or OpenCV's adaptive "
                        "mog2/knn with shadow detection")
    p.add_argument("--threshold", type=float, default=None,
                   help="difference threshold (grey levels, or RGB distance for colour); default 25 / 30 "
                        "(30 suits compressed video; try 20 for a clean camera)")
    p.add_argument("--init", action="append", default=[], metavar="ID,X,Y",
                   help="start a person at (X, Y) metres with this id (repeatable)")
    p.add_argument("--births", choices=("anywhere", "entry", "none"), default=None,
                   help="where new people may appear (default: anywhere in view)")
    p.add_argument("--fps", type=float, default=None, help="frame rate for time stamps (default: video header)")
    p.add_argument("--frames", type=int, default=None, metavar="N", help="stop after N frames")
    p.add_argument("--json", action="store_true", help="print one JSON line per frame on stdout")
    p.add_argument("--no-video", action="store_true", help="do not write annotated videos")
    p.add_argument("--show-ring", action="store_true", help="draw the −1 ring and the foreground in the videos")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    scene = load_scene(args.scene)
    videos = dict(_pair(v, "--video") for v in args.video)
    if not videos:
        raise InputError("no video given: use --video CAMERA=PATH (cameras: " + ", ".join(scene.cameras) + ")")
    for cid, vpath in videos.items():
        scene.camera(cid)
        if not Path(vpath).exists():
            raise InputError(f"{cid}: {vpath}: no such file or folder")
    explicit = dict(_pair(b, "--background") for b in args.background)
    backgrounds = {}
    for cid, vpath in videos.items():
        cam = scene.camera(cid)
        if cid in explicit:
            backgrounds[cid] = read_image(explicit[cid], cam, "background")
            continue
        guess = Path(vpath).parent / f"{cid}_background.png"
        if guess.is_file():
            backgrounds[cid] = read_image(guess, cam, "background")
            print(f"{cid}: background {guess}", file=sys.stderr)
        elif Path(vpath).is_file():
            backgrounds[cid] = background_from_video(vpath)
            print(f"{cid}: no background image given; estimated from the video (temporal median)", file=sys.stderr)
        else:
            raise InputError(f"{cid}: no background image: give --background {cid}=PNG")
    options = {}
    if args.births is not None:
        options["births"] = args.births
    foregrounds = make_foregrounds(scene, backgrounds, args.foreground, args.threshold)
    tracker = make_tracker(args.method, scene, foregrounds, preset=args.preset, **options)
    for text in args.init:
        tid, x, y = _init(text)
        if not hasattr(tracker, "init_track"):
            raise InputError(f"--init: the {args.method} tracker starts tracks by itself")
        tracker.init_track(x, y, track_id=tid)
    source = VideoSource(videos, scene.cameras, fps=args.fps, stop=args.frames)
    result = run_tracking(scene, source, tracker, args.out, write_video=not args.no_video,
                          json_stream=sys.stdout if args.json else None, progress=not args.quiet,
                          show_ring=args.show_ring)
    print(f"{result.frames} frames in {result.seconds:.1f} s ({result.fps:.1f} frames/s), "
          f"{len(result.track_ids)} tracks", file=sys.stderr)
    print(f"tracks: {result.tracks_csv}", file=sys.stderr)
    for cid, v in result.videos.items():
        print(f"video {cid}: {v}", file=sys.stderr)
    print(f"floor plan: {result.floorplan}", file=sys.stderr)
    if result.error:
        raise InputError(result.error + f" (outputs up to frame {result.frames - 1} kept in {result.out_dir})")
    if result.interrupted:
        raise KeyboardInterrupt
    return 0
