"""``worldtrack demo``: synthesise a scene, track it from its video files, score it, show where it all is.

Run again, it replaces its own previous output folder (``synth/`` and ``track/``); a folder that
holds anything else is refused. The tracker's kernels are compiled (first run) or loaded before
its clock starts, so the frames/s it prints are tracking alone.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from worldtrack.errors import InputError


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "demo", help="synthesise a scene, track it, evaluate against ground truth (the README's first command)",
        description="Renders a synthetic scene with exact ground truth (articulated people, shadows, noise, "
                    "MP4 compression), tracks it from the video files exactly as `worldtrack track` would, "
                    "evaluates it with `worldtrack eval` metrics, and prints where the annotated videos "
                    "and the floor plan are.")
    p.add_argument("--out", default="demo_out", metavar="DIR", help="output folder (default: demo_out)")
    p.add_argument("--scenario", default="two-crossing", help="synthetic scenario (default: two-crossing; "
                                                              "see `worldtrack synth --list`)")
    p.add_argument("--size", default="640x480", metavar="WxH", help="image size (default: 640x480)")
    p.add_argument("--frames", default=None, metavar="N", help="number of frames (default: the scenario's)")
    p.add_argument("--seed", type=int, default=0, help="random seed of the synthetic scene (default 0)")
    p.add_argument("--method", default="ellipsoid", choices=("ellipsoid", "particle", "blobs"),
                   help="tracker (default: ellipsoid)")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    p.set_defaults(func=run)


def _clear_previous(out: Path) -> None:
    """Remove a previous demo in ``out`` (its ``synth/`` and ``track/``); refuse any other content."""
    import shutil

    if not out.exists():
        return
    if not out.is_dir():
        raise InputError(f"--out {out}: is a file, expected a folder")
    content = {p.name for p in out.iterdir()}
    if content - {"synth", "track"}:
        raise InputError(f"--out {out}: holds other files than a previous demo ({', '.join(sorted(content)[:4])}); "
                         "give a new or empty folder")
    if content:
        print(f"replacing the previous demo in {out}", file=sys.stderr)
    for name in content:
        shutil.rmtree(out / name)


def run(args: argparse.Namespace) -> int:
    from worldtrack.eval.mot import drop_ignored, evaluate
    from worldtrack.eval.tables import position_errors
    from worldtrack.experiment import visibility
    from worldtrack.io.sources import VideoSource, read_image
    from worldtrack.io.tracks import read_tracks
    from worldtrack.foreground import SYNTHETIC_COLOUR_THRESHOLD, foregrounds_from_config
    from worldtrack.io.runinfo import write_run_info
    from worldtrack.runconfig import resolve_run_config
    from worldtrack.pipeline import run_tracking
    from worldtrack.scene import load_scene
    from worldtrack.synth import make_scenario, write_sequence
    from worldtrack.trackers import make_tracker

    from worldtrack.cli._args import positive_int
    from worldtrack.warmup import say_warm_up

    out = Path(args.out)
    frames = positive_int(args.frames, "--frames", "40") if args.frames is not None else None
    _clear_previous(out)
    t0 = time.perf_counter()
    scenario = make_scenario(args.scenario, size=args.size, frames=frames, seed=args.seed)
    synth_dir = write_sequence(scenario, out / "synth", png=False, progress=not args.quiet)
    t_synth = time.perf_counter() - t0
    print(f"synthesised {args.scenario}: {scenario.n_frames} frames, cameras {', '.join(scenario.camera_ids)} "
          f"→ {synth_dir} ({t_synth:.0f} s)", file=sys.stderr)

    scene = load_scene(synth_dir / "scene.yaml")
    videos = {c: synth_dir / f"{c}.mp4" for c in scenario.camera_ids}
    backgrounds = {c: read_image(synth_dir / f"{c}_background.png", scene.camera(c), "background") for c in videos}
    cfg = resolve_run_config({"foreground": {"kind": "colour", "threshold": SYNTHETIC_COLOUR_THRESHOLD}},
                             method=args.method)
    tracker = make_tracker(cfg.method, scene, foregrounds_from_config(scene, backgrounds, cfg.foreground),
                           cfg.section())
    source = VideoSource(videos, scene.cameras, fps=scenario.fps)
    gt_all = read_tracks(synth_dir / "gt.csv")
    gt_paths = {int(i): gt_all.xy[gt_all.id == i] for i in set(gt_all.id.tolist())}
    say_warm_up(cfg.method, cfg.section(), cfg.foreground)
    write_run_info(out / "track", cfg.to_mapping(), inputs={
        "scene": synth_dir / "scene.yaml", "videos": videos, "backgrounds": {c: synth_dir / f"{c}_background.png"
                                                                             for c in videos},
        "synthetic": {"scenario": args.scenario, "size": args.size, "frames": scenario.n_frames, "seed": args.seed}})
    result = run_tracking(scene, source, tracker, out / "track", gt_paths=gt_paths, show_ring=True,
                          progress=not args.quiet)
    if result.error:
        raise InputError(result.error)
    if result.interrupted:
        from worldtrack.cli.track import source_interrupt
        raise source_interrupt(result)

    pred = read_tracks(result.tracks_csv)
    gt, pred = drop_ignored(gt_all, pred, visibility(gt_all) < 0.2, gate=0.5)
    m = evaluate(gt, pred, gate=0.5)
    err = position_errors(gt, pred, gate=0.5)
    rows = [("MOTA", f"{m['mota']:.3f}"), ("IDF1", f"{m['idf1']:.3f}"), ("ID switches", f"{m['num_switches']}"),
            ("mean position error", f"{err.mean_m:.3f} m  (|dX| {err.mean_abs_dx_m:.3f}, |dY| {err.mean_abs_dy_m:.3f})"),
            ("tracking speed", f"{result.fps:.1f} frames/s (decode + foreground + tracking + drawing)"),
            ("people / frames", f"{len(set(gt.id.tolist()))} / {result.frames}")]
    print()
    print(f"worldtrack demo — {args.method} tracker on '{args.scenario}' ({args.size}, 0.5 m gate)")
    for name, value in rows:
        print(f"  {name:<22}{value}")
    print()
    for cid, path in result.videos.items():
        print(f"  video {cid:<16}{path}")
    print(f"  floor plan            {result.floorplan}")
    print(f"  tracks                {result.tracks_csv}")
    print(f"  ground truth          {synth_dir / 'gt.csv'}")
    print(f"  (total {time.perf_counter() - t0:.0f} s)")
    return 0
