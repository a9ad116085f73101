"""``worldtrack track SCENE --video CAM=PATH …``: track people and write tracks, videos and a plan.

The tracker's settings come from its defaults (or ``--preset paper``), a file (``--config``), the
named flags and ``--set PATH=VALUE``, in that order (:mod:`worldtrack.runconfig`);
``--print-config`` prints them all and stops. Every run writes ``run.yaml`` into its output folder
first: the version, the commit if known, the command line, the inputs and the resolved settings.

Before the clock starts the method's compiled kernels are prepared (:mod:`worldtrack.warmup`, one
line saying how long it took), so frames/s count tracking only. An output folder that holds a
previous run is refused unless ``--overwrite``, which removes that run's files first.
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


USAGE = ("worldtrack track SCENE --video CAM=PATH [--video CAM=PATH ...] [options]\n"
         "       worldtrack track --print-config [options]")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "track", help="track people in videos of a calibrated scene", usage=USAGE,
        description="Track people in world coordinates. Writes DIR/run.yaml (settings and inputs), "
                    "DIR/tracks.csv (one row per person per frame, flushed as it goes), "
                    "DIR/<camera>_annotated.mp4 and DIR/floorplan.png.")
    p.add_argument("scene", nargs="?", metavar="SCENE", help="scene YAML file (required unless --print-config)")
    p.add_argument("--video", action="append", default=[], metavar="CAM=PATH",
                   help="video file or folder of images for camera CAM (repeat for several cameras); or a live "
                        "camera: a device index (CAM=0) or a stream URL (rtsp://, http://, udp://)")
    p.add_argument("--map", metavar="URL", default=None,
                   help="work on a shared map on Redis (redis://[USER:PASSWORD@]HOST:PORT/DB or rediss://): own "
                        "the --cameras, publish what they see, take over the fusion if free")
    p.add_argument("--cameras", metavar="CAM,CAM", default=None,
                   help="with --map: the cameras this worker owns (default: every --video camera)")
    p.add_argument("--background", action="append", default=[], metavar="CAM=PNG",
                   help="empty-scene image for CAM; default: <video folder>/<CAM>_background.png if "
                        "present, else the temporal median of frames sampled over the video")
    p.add_argument("--out", default="out", metavar="DIR",
                   help="output folder (default: out); one that holds a previous run is refused unless --overwrite")
    p.add_argument("--overwrite", action="store_true",
                   help="replace the previous run's files in --out (run.yaml, tracks.csv, videos, floor plan)")
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
                        "default: the particle tracker's own 25, else 25 grey / 30 colour (30 suits compressed "
                        "video; try 20 for a clean camera)")
    p.add_argument("--init", action="append", default=[], metavar="ID,X,Y",
                   help="start a person at (X, Y) metres with this id (repeatable)")
    p.add_argument("--births", choices=("anywhere", "entry", "none"), default=None,
                   help="where new people may appear (default: anywhere in view)")
    p.add_argument("--fps", default=None, metavar="FPS", help="frame rate for time stamps, > 0 (default: video header)")
    p.add_argument("--frames", default=None, metavar="N", help="stop after N frames")
    p.add_argument("--max-bad-frames", default="25", metavar="N",
                   help="undecodable frames in a row that stop the run (fewer are skipped and counted; default 25)")
    p.add_argument("--json", action="store_true", help="print one JSON line per frame on stdout")
    p.add_argument("--mot", metavar="FILE", help="also write MOTChallenge rows: frame,id, the box the person "
                                                 "projects to in --mot-camera (pixels), conf, world x,y,z (metres)")
    p.add_argument("--mot-camera", metavar="CAM", help="camera of the --mot boxes (default: the scene's first)")
    p.add_argument("--area", metavar="AREA", help="tracking area to draw on the floor plan: a file of "
                                                  "x1,y1,x2,y2,... ('#' comments) or the numbers (metres)")
    p.add_argument("--no-video", action="store_true", help="do not write annotated videos")
    p.add_argument("--show-ring", action="store_true", help="draw the −1 ring and the foreground in the videos")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--verbose", action="store_true", help="let FFmpeg print its messages about damaged video")
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
    from worldtrack.cli._args import positive, positive_int
    from worldtrack.io.live import is_live, parse_source
    args.fps = positive(args.fps, "--fps", "25") if args.fps is not None else None
    args.frames = positive_int(args.frames, "--frames", "100") if args.frames is not None else None
    if args.map or any(is_live(parse_source(_pair(v, "--video")[1])) for v in args.video):
        from worldtrack.cli.track_live import run_live
        return run_live(args, cfg)
    from worldtrack.cli.eval import read_area
    from worldtrack.io.runinfo import prepare_output, write_run_info
    from worldtrack.io.sources import VideoSource
    from worldtrack.pipeline import progress_writer, run_tracking
    from worldtrack.scene import load_scene
    from worldtrack.warmup import say_warm_up

    fps, frames = args.fps, args.frames
    max_bad = positive_int(args.max_bad_frames, "--max-bad-frames", "25")
    area = read_area(args.area) if args.area else None
    scene = load_scene(args.scene)
    for line in scene.warnings:
        print(f"warning: {line}", file=sys.stderr)
    videos = dict(_pair(v, "--video") for v in args.video)
    if not videos:
        raise InputError("no video given: use --video CAMERA=PATH (cameras: " + ", ".join(scene.cameras) + ")")
    for cid, vpath in videos.items():
        scene.camera(cid)
        if not Path(vpath).exists():
            raise InputError(f"{cid}: {vpath}: no such file or folder")
    if args.mot_camera is not None:
        scene.camera(args.mot_camera)
    out = Path(args.out)
    prepare_output(out, args.overwrite, extra=[args.mot] if args.mot else ())
    source = VideoSource(videos, scene.cameras, fps=fps, stop=frames, max_bad_frames=max_bad,
                         warn=progress_writer(not args.quiet))
    backgrounds, background_files = _backgrounds(args, scene, videos)
    tracker = _tracker(args, cfg, scene, backgrounds)
    say_warm_up(cfg.method, cfg.section(), cfg.foreground)
    write_run_info(out, cfg.to_mapping(), inputs={
        "scene": args.scene, "videos": videos, "backgrounds": background_files,
        "init": list(args.init), "fps": fps, "frames": frames, "mot": args.mot}, argv=getattr(args, "command_line", None))
    result = run_tracking(scene, source, tracker, out, write_video=not args.no_video,
                          json_stream=sys.stdout if args.json else None, progress=not args.quiet,
                          show_ring=args.show_ring, mot_path=args.mot, mot_camera=args.mot_camera, area=area)
    _report(result, source)
    if result.error:
        raise InputError(result.error + f" (outputs up to frame {result.last_frame} kept in {result.out_dir})")
    if result.interrupted:
        raise source_interrupt(result)
    if result.broken_pipe:
        raise BrokenPipeError
    return 0


def _backgrounds(args: argparse.Namespace, scene, videos: dict[str, str]) -> tuple[dict, dict]:
    """The empty-scene image of every camera: given, found beside the video, or estimated from it."""
    from worldtrack.io.sources import background_from_video, read_image

    explicit = dict(_pair(b, "--background") for b in args.background)
    backgrounds, files = {}, {}
    for cid, vpath in videos.items():
        cam = scene.camera(cid)
        guess = Path(vpath).parent / f"{cid}_background.png"
        if cid in explicit:
            backgrounds[cid], files[cid] = read_image(explicit[cid], cam, "background"), explicit[cid]
        elif guess.is_file():
            backgrounds[cid], files[cid] = read_image(guess, cam, "background"), str(guess)
            print(f"{cid}: background {guess}", file=sys.stderr)
        elif Path(vpath).is_file():
            backgrounds[cid] = background_from_video(vpath)
            files[cid] = "estimated from the video (temporal median)"
            print(f"{cid}: no background image given; estimated from the video (temporal median)", file=sys.stderr)
        else:
            raise InputError(f"{cid}: no background image: give --background {cid}=PNG")
    return backgrounds, files


def _tracker(args: argparse.Namespace, cfg, scene, backgrounds: dict):
    from worldtrack.foreground import foregrounds_from_config
    from worldtrack.trackers import make_tracker

    tracker = make_tracker(cfg.method, scene, foregrounds_from_config(scene, backgrounds, cfg.foreground), cfg.section())
    for text in args.init:
        tid, x, y = _init(text)
        tracker.init_track(x, y, track_id=tid)
    return tracker


def _report(result, source) -> None:
    """What the run wrote, and what the source had to say about its inputs (standard error)."""
    print(f"{result.frames} frames in {result.seconds:.1f} s ({result.fps:.1f} frames/s), "
          f"{len(result.track_ids)} tracks", file=sys.stderr)
    for line in source.skipped_summary():
        print(line, file=sys.stderr)
    print(f"tracks: {result.tracks_csv}", file=sys.stderr)
    if result.mot is not None:
        print(f"MOTChallenge rows: {result.mot}", file=sys.stderr)
    for cid, v in result.videos.items():
        print(f"video {cid}: {v}", file=sys.stderr)
    print(f"floor plan: {result.floorplan}", file=sys.stderr)


def source_interrupt(result) -> KeyboardInterrupt:
    """The interrupt to raise for a run a signal stopped (the command line turns it into 130/143)."""
    from worldtrack.interrupts import Terminated
    return Terminated() if result.stop_signal == 15 else KeyboardInterrupt()
