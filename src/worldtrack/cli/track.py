"""``worldtrack track SCENE --video CAM=PATH …``: track people and write tracks, videos and a plan.

The tracker's settings come from its defaults (or ``--preset paper``), a file (``--config``), the
named flags and ``--set PATH=VALUE``, in that order (:mod:`worldtrack.runconfig`);
``--print-config`` prints them all and stops. Every run writes ``run.yaml`` into its output folder
first: the version, the commit if known, the command line, the inputs and the resolved settings.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from worldtrack.errors import InputError


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
        description="Track people in world coordinates. Writes DIR/run.yaml (settings and inputs), "
                    "DIR/tracks.csv (one row per person per frame, flushed as it goes), "
                    "DIR/<camera>_annotated.mp4 and DIR/floorplan.png.")
    p.add_argument("scene", nargs="?", help="scene YAML file (required unless --print-config)")
    p.add_argument("--video", action="append", default=[], metavar="CAM=PATH",
                   help="video file or folder of images for camera CAM (repeat for several cameras)")
    p.add_argument("--background", action="append", default=[], metavar="CAM=PNG",
                   help="empty-scene image for CAM; default: <video folder>/<CAM>_background.png if "
                        "present, else the temporal median of frames sampled over the video")
    p.add_argument("--out", default="out", metavar="DIR", help="output folder (default: out)")
    p.add_argument("--method", choices=("ellipsoid", "particle", "blobs"), default=None,
                   help="tracker (default: ellipsoid, or the --config file's)")
    p.add_argument("--preset", choices=("default", "paper"), default=None,
                   help="'paper': the method exactly as published; 'default': with worldtrack's extensions")
    p.add_argument("--config", metavar="YAML", default=None,
                   help="settings file (as --print-config writes it; any subset of it)")
    p.add_argument("--set", action="append", default=[], metavar="PATH=VALUE", dest="sets",
                   help="one setting by its path, e.g. particle.motion.noise_m=0.05 or foreground.threshold=20 "
                        "(repeatable; applied last)")
    p.add_argument("--print-config", action="store_true",
                   help="print every setting (with a comment on each) as YAML and stop")
    p.add_argument("--foreground", choices=("grey", "colour", "mog2", "knn"), default=None,
                   help="foreground model: colour (default; with cast shadows set aside) or grey difference "
                        "against the background with a fixed threshold (the paper's), or OpenCV's adaptive "
                        "mog2/knn with shadow detection")
    p.add_argument("--threshold", type=float, default=None,
                   help="difference threshold (grey levels, or RGB distance for colour) for every method; "
                        "default 25 / 30 (30 suits compressed video; try 20 for a clean camera)")
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


def settings(args: argparse.Namespace):
    """The run's resolved configuration from the file, the flags and ``--set``."""
    from worldtrack.config import load_yaml, parse_assignment
    from worldtrack.runconfig import resolve_run_config

    data = load_yaml(args.config) if args.config else None
    sets = [parse_assignment(text) for text in args.sets]
    flags = {"foreground": args.foreground, "threshold": args.threshold, "births": args.births}
    try:
        cfg = resolve_run_config(data, method=args.method, preset=args.preset, flags=flags)
    except InputError as e:
        raise InputError(f"{args.config}: {e}" if args.config else str(e)) from None
    return resolve_run_config(data, method=args.method, preset=args.preset, flags=flags, sets=sets) if sets else cfg


def run(args: argparse.Namespace) -> int:
    from worldtrack.runconfig import dump_run_config

    cfg = settings(args)
    if args.print_config:
        sys.stdout.write(dump_run_config(cfg))
        return 0
    if not args.scene:
        raise InputError("track: give a scene file (worldtrack track SCENE --video CAM=PATH …)")
    from worldtrack.foreground import foregrounds_from_config
    from worldtrack.io.runinfo import write_run_info
    from worldtrack.io.sources import VideoSource, background_from_video, read_image
    from worldtrack.pipeline import run_tracking
    from worldtrack.scene import load_scene
    from worldtrack.trackers import make_tracker

    scene = load_scene(args.scene)
    videos = dict(_pair(v, "--video") for v in args.video)
    if not videos:
        raise InputError("no video given: use --video CAMERA=PATH (cameras: " + ", ".join(scene.cameras) + ")")
    for cid, vpath in videos.items():
        scene.camera(cid)
        if not Path(vpath).exists():
            raise InputError(f"{cid}: {vpath}: no such file or folder")
    explicit = dict(_pair(b, "--background") for b in args.background)
    backgrounds, background_files = {}, {}
    for cid, vpath in videos.items():
        cam = scene.camera(cid)
        if cid in explicit:
            backgrounds[cid] = read_image(explicit[cid], cam, "background")
            background_files[cid] = explicit[cid]
            continue
        guess = Path(vpath).parent / f"{cid}_background.png"
        if guess.is_file():
            backgrounds[cid] = read_image(guess, cam, "background")
            background_files[cid] = str(guess)
            print(f"{cid}: background {guess}", file=sys.stderr)
        elif Path(vpath).is_file():
            backgrounds[cid] = background_from_video(vpath)
            background_files[cid] = "estimated from the video (temporal median)"
            print(f"{cid}: no background image given; estimated from the video (temporal median)", file=sys.stderr)
        else:
            raise InputError(f"{cid}: no background image: give --background {cid}=PNG")
    foregrounds = foregrounds_from_config(scene, backgrounds, cfg.foreground)
    tracker = make_tracker(cfg.method, scene, foregrounds, cfg.section())
    for text in args.init:
        tid, x, y = _init(text)
        tracker.init_track(x, y, track_id=tid)
    write_run_info(Path(args.out), cfg.to_mapping(), inputs={
        "scene": args.scene, "videos": videos, "backgrounds": background_files,
        "init": list(args.init), "fps": args.fps, "frames": args.frames},
        argv=getattr(args, "command_line", None))
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
