"""How long the follower takes per frame (seed 001), with disparity given, and StereoSGBM apart.

Question: does one frame of following — depth from the disparity image, plan-view detection,
silhouettes, colour normalisation and histograms, the decision and the others' tracks — fit in
20 ms at 640×480 on one core (the paper: 50 ms on 2009 hardware at a lower resolution)? And what
does OpenCV's StereoSGBM add when only a stereo pair is given?

Frames: ``follow-target`` (development seed 300, the issue's hard settings) rendered at 640×480,
320×240 and 160×120, the right camera 0.12 m to the right for the stereo pair. Each size: the
sequence followed ``--repeats`` times from its first frame with a fresh follower; min and median
of the per-frame times (the first frame, which starts following, left out). Reference in the same
run: one ``cv2.createBackgroundSubtractorMOG2().apply`` at the same size. Run it pinned to one
core: ``taskset -c 1 .venv/bin/python benchmarks/follow_speed.py``. About 3 minutes (rendering
640×480 is most of it). Writes ``benchmarks/results/follow_speed.md``.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table, mog2_apply_time, save_result  # noqa: E402
from follow_common import SCENARIO  # noqa: E402

from worldtrack.follow import FollowTracker  # noqa: E402
from worldtrack.follow.colour import histograms, normalise_colour  # noqa: E402
from worldtrack.follow.planview import detect  # noqa: E402
from worldtrack.follow.silhouette import silhouettes  # noqa: E402
from worldtrack.follow.stereo import StereoMatcher, disparity_to_depth  # noqa: E402
from worldtrack.trackers.base import Frame  # noqa: E402
from worldtrack.synth import make_scenario  # noqa: E402

BASELINE = 0.12
#: The clock of every timing: wall time (``perf_counter``), or with ``--clock cpu`` this thread's CPU
#: time (``thread_time``), which waiting for a core on a crowded machine does not inflate.
clock = time.perf_counter


def render(size, frames: int):
    """(left views, right images) of the first ``frames`` frames (the sequence is cut at 400)."""
    sc = make_scenario("follow-target", size=size, frames=400, seed=300, **SCENARIO)
    right = make_scenario("follow-target", size=size, frames=400, seed=300, **SCENARIO)
    right.rigs["robot"].poses[:] = [(R, t - np.array([BASELINE, 0.0, 0.0])) for R, t in right.rigs["robot"].poses]
    views, rights = [], []
    for b, r in zip(sc.frames(), right.frames()):
        if b.frame >= frames:
            break
        views.append((b, b.views["robot"]))
        rights.append(r.views["robot"].image)
    return sc, views, rights


def time_follow(sc, views, repeats: int) -> tuple[list[float], dict]:
    """Per-frame times (s) of disparity → depth + FollowTracker.step, and a breakdown (median ms)."""
    fx = float(views[0][1].camera.K[0, 0])
    per_frame, parts = [], {"depth": [], "detect": [], "silhouettes": [], "colour": [], "decide": []}
    for _ in range(repeats):
        tracker = FollowTracker(scene=sc.scene)
        for b, v in views:
            t0 = clock()
            depth = disparity_to_depth(v.disparity, fx, BASELINE)
            frame = Frame(v.image, b.time, b.frame, depth, meta={"wb_gains": v.wb_gains})
            start = (b.gt[0]["x"], b.gt[0]["y"]) if b.frame == 0 else None
            tracker.follow(frame, v.camera, start_xy=start)
            if b.frame > 0:
                per_frame.append(clock() - t0)
    cfg = FollowTracker().config
    walk = sc.scene.distance_field(0.05)
    for b, v in views[1:]:
        t = [clock()]
        depth = disparity_to_depth(v.disparity, fx, BASELINE)
        t.append(clock())
        c = detect(depth, v.camera, cfg, walk)
        t.append(clock())
        sil = silhouettes(c.labels, c.stride, depth, c.depth)
        t.append(clock())
        img, _ = normalise_colour(v.image, v.wb_gains, cfg.normalise, sil > 0)
        histograms(img, sil, len(c), cfg)
        t.append(clock())
        for name, a, b_ in zip(("depth", "detect", "silhouettes", "colour"), t[:-1], t[1:]):
            parts[name].append(b_ - a)
    med = statistics.median(per_frame)
    parts = {k: 1000 * statistics.median(v) for k, v in parts.items() if v}
    parts["decide"] = 1000 * med - sum(parts.values())
    return per_frame, parts


def time_stereo(views, rights, repeats: int) -> list[float]:
    m = StereoMatcher(float(views[0][1].camera.K[0, 0]), BASELINE)
    out = []
    for _ in range(repeats):
        for (b, v), r in zip(views, rights):
            t0 = clock()
            m.disparity(v.image, r)
            out.append(clock() - t0)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=25, help="frames per size (default 25)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="8 frames, 320x240 and 160x120 only (prints only)")
    ap.add_argument("--clock", choices=("wall", "cpu"), default="wall",
                    help="wall time, or this thread's CPU time (a crowded machine; default wall)")
    args = ap.parse_args(argv)
    global clock
    clock = time.thread_time if args.clock == "cpu" else time.perf_counter
    t_start = time.perf_counter()
    sizes = [(320, 240), (160, 120)] if args.quick else [(640, 480), (320, 240), (160, 120)]
    frames = 8 if args.quick else args.frames
    rows = []
    for size in sizes:
        t0 = time.perf_counter()
        sc, views, rights = render(size, frames)
        print(f"{size[0]}x{size[1]}: rendered {frames} frame pairs in {time.perf_counter() - t0:.0f} s", file=sys.stderr)
        per, parts = time_follow(sc, views, args.repeats)
        stereo = time_stereo(views, rights, args.repeats)
        mog2 = mog2_apply_time(*size, clock=clock)
        med = statistics.median(per)
        rows.append([f"{size[0]}x{size[1]}", f"{1000 * min(per):.1f}", f"{1000 * med:.1f}",
                     " / ".join(f"{parts[k]:.1f}" for k in ("depth", "detect", "silhouettes", "colour", "decide")),
                     f"{1000 * min(stereo):.1f}", f"{1000 * statistics.median(stereo):.1f}", f"{1000 * mog2:.2f}",
                     f"{med / mog2:.1f}"])
        print(rows[-1], file=sys.stderr)
    table = markdown_table(["size", "follow min ms", "follow median ms",
                            "median ms: depth / detect / silhouettes / colour / decide", "StereoSGBM min ms",
                            "StereoSGBM median ms", "MOG2 apply ms (reference)", "follow / MOG2"], rows)
    text = (f"{frames} frames per size × {args.repeats} runs, one thread, {args.clock} clock "
            f"({'thread CPU time: the machine was shared' if args.clock == 'cpu' else 'wall time'}). 'follow': disparity → depth and one "
            f"FollowTracker step (the default configuration) per frame, disparity given; StereoSGBM (numDisparities "
            f"for 0.8 m, block 5) apart. Target: ≤ 20 ms per frame at 640x480 with disparity given.\n\n{table}\n")
    print(text)
    save_result("follow_speed", "Following: time per frame (seed 001)", text, args.quick, time.perf_counter() - t_start)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
