"""``worldtrack follow SCENE --rgb … --depth|--disparity|--right … --target ID|X,Y --out DIR``: follow one person.

Seed 001: a (moving) stereo or RGB-D camera follows one target person among others under changing
light. Writes, as it goes (a Ctrl-C or a bad frame keeps what was written):

* ``DIR/target.csv`` — per frame: time, the target's filtered position and velocity, whether it was
  found, its D, RBhat, E (eqs. 1–3), α, |W|, the measured position, and the other people tracked;
* ``DIR/commands.csv`` — the follower's (v, ω) per frame and whether somebody blocked its path;
* ``DIR/follow.mp4`` — the frames with silhouettes, every candidate's D and the chosen one;
* ``DIR/planview.png`` — the floor plan with the target's path, the others and the camera's path.
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

import cv2
import numpy as np

from worldtrack.errors import InputError


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "follow", help="follow one person with a moving stereo / RGB-D camera (paper 001)",
        description="Follow one target person among others with a stereo or RGB-D camera under changing "
                    "light. Writes DIR/target.csv, DIR/commands.csv, DIR/follow.mp4 and DIR/planview.png.")
    p.add_argument("scene", help="scene YAML file (the camera's intrinsics; walls and obstacles help)")
    p.add_argument("--rgb", required=True, metavar="PATH", help="colour video or folder of images")
    p.add_argument("--depth", metavar="DIR", help="folder of 16-bit PNG depth images in millimetres")
    p.add_argument("--disparity", metavar="DIR", help="folder of 16-bit PNG disparity images in 1/16 pixel")
    p.add_argument("--right", metavar="PATH", help="right camera video or folder (disparity by StereoSGBM)")
    p.add_argument("--baseline", type=float, metavar="M", help="stereo baseline in metres (--disparity, --right)")
    p.add_argument("--target", required=True, metavar="ID|X,Y",
                   help="the person to follow: an id of gt.csv at the first frame, or a floor position X,Y (m)")
    p.add_argument("--out", default="follow_out", metavar="DIR", help="output folder (default: follow_out)")
    p.add_argument("--camera", help="camera id in the scene (default: its only camera)")
    p.add_argument("--frames-csv", metavar="CSV", help="per-frame time and white-balance gains "
                   "(wb_r_<camera>, wb_b_<camera>); default: frames.csv beside --rgb if present")
    p.add_argument("--poses", metavar="CSV", help="per-frame camera poses; default: camera_poses.csv beside "
                   "--rgb if present, else the scene's fixed camera")
    p.add_argument("--gt", metavar="CSV", help="ground truth for --target ID (default: gt.csv beside --rgb)")
    p.add_argument("--preset", default="default", help="default, paper, colour-only, position-only, paper+undo, "
                   "paper+undo+others (default: default)")
    p.add_argument("--distance", type=float, default=1.8, help="following distance for the commands, m (1.8)")
    p.add_argument("--follower", choices=("pid+depth", "pid+walkers", "pid", "planner"), default="pid+depth",
                   help="what turns the track into (v, ω): pid+depth (the paper's PID on distance and bearing with "
                        "a stop for near depth points, default), pid+walkers (the same, and the other people's "
                        "velocities: someone walking out of the path does not hold it), pid (the paper's), planner "
                        "(local planner round the scene's obstacles and people)")
    p.add_argument("--fps", type=float, help="frame rate when frames.csv gives no times (default: video, else 10)")
    p.add_argument("--frames", type=int, metavar="N", help="stop after N frames")
    p.add_argument("--no-video", action="store_true", help="do not write follow.mp4")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def parse_target(text: str) -> int | tuple[float, float]:
    """``"3"`` → 3; ``"4.2,3.0"`` → (4.2, 3.0)."""
    parts = text.split(",")
    try:
        if len(parts) == 1:
            value = int(parts[0])
            if value < 1:
                raise ValueError
            return value
        if len(parts) == 2:
            return float(parts[0]), float(parts[1])
    except ValueError:
        pass
    raise InputError(f"--target {text!r}: expected a person id (integer from 1) or a floor position X,Y in metres")


def target_position(gt_path: Path, person: int, frame: int = 0) -> tuple[float, float]:
    """(x, y) of ``person`` in gt.csv at ``frame``; InputError naming the ids there if absent."""
    from worldtrack.io.text import read_text
    rows = list(csv.DictReader(read_text(gt_path, "a gt.csv (frame, id, x, y)").splitlines()))
    if not rows or not {"frame", "id", "x", "y"} <= set(rows[0]):
        raise InputError(f"{gt_path}: expected columns frame, id, x, y")
    here = [r for r in rows if r["frame"].strip() == str(frame)]
    for r in here:
        if r["id"].strip() == str(person):
            return float(r["x"]), float(r["y"])
    ids = ", ".join(sorted({r["id"].strip() for r in here}, key=lambda s: (len(s), s))) or "none"
    raise InputError(f"--target {person}: no person {person} in {gt_path} at frame {frame} (ids there: {ids})")


def _beside(rgb: str, name: str) -> Path | None:
    p = Path(rgb)
    for folder in (p.parent, p.parent.parent):
        if (folder / name).is_file():
            return folder / name
    return None


class _Outputs:
    """target.csv, commands.csv and follow.mp4, written row by row; the plan-view plot at the end."""

    TARGET = ["frame", "time", "x", "y", "vx", "vy", "found", "D", "RBhat", "E", "alpha", "w_steps",
              "measured_x", "measured_y", "candidates", "others"]

    def __init__(self, out: Path, video: bool, fps: float):
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise InputError(f"--out: cannot create folder {out} ({e.strerror})") from None
        self.out, self.fps = out, fps
        self.files = [open(out / "target.csv", "w", newline=""), open(out / "commands.csv", "w", newline="")]
        self.target = csv.writer(self.files[0], lineterminator="\n")
        self.commands = csv.writer(self.files[1], lineterminator="\n")
        self.target.writerow(self.TARGET)
        self.commands.writerow(["frame", "time", "v", "omega", "blocked"])
        self.video = None if not video else False
        self.path = {k: [] for k in ("xy", "found", "cam", "others")}

    def write(self, frame, camera, step, command, blocked: bool, image: np.ndarray | None) -> None:
        from worldtrack.viz.follow import draw_follow_step
        c = step.chosen
        pick = (lambda a: f"{a[c]:.4f}" if c >= 0 else "")
        others = ";".join(f"{i}:{x:.3f}:{y:.3f}" for i, (x, y) in zip(step.others_ids, step.others_xy))
        self.target.writerow([frame.index, f"{frame.t:.4f}", f"{step.xy[0]:.4f}", f"{step.xy[1]:.4f}",
                              f"{step.velocity[0]:.4f}", f"{step.velocity[1]:.4f}", int(step.found), pick(step.D),
                              pick(step.RBhat), pick(step.E), f"{step.alpha:.4f}", f"{step.w_steps:.1f}",
                              *(f"{v:.4f}" if step.found else "" for v in step.measured), len(step.candidates),
                              others])
        self.commands.writerow([frame.index, f"{frame.t:.4f}", f"{command[0]:.4f}", f"{command[1]:.4f}", int(blocked)])
        for f in self.files:
            f.flush()
        self.path["xy"].append(step.xy.copy())
        self.path["found"].append(step.found)
        self.path["cam"].append(camera.centre[:2].copy())
        for i, xy in zip(step.others_ids, step.others_xy):
            self.path["others"].append((int(i), xy.copy()))
        if self.video is not None and image is not None:
            shot = draw_follow_step(image, step, camera, f"#{frame.index}")
            if shot.shape[1] < 480:
                shot = cv2.resize(shot, None, fx=2, fy=2, interpolation=cv2.INTER_NEAREST)
            if self.video is False:
                self.video = cv2.VideoWriter(str(self.out / "follow.mp4"), cv2.VideoWriter_fourcc(*"mp4v"),
                                             self.fps, (shot.shape[1], shot.shape[0]))
            self.video.write(shot)

    def close(self, scene) -> Path | None:
        from worldtrack.viz.follow import plot_follow
        for f in self.files:
            f.close()
        if self.video:
            self.video.release()
        if not self.path["xy"]:
            return None
        others: dict = {}
        for i, xy in self.path["others"]:
            others.setdefault(i, []).append(xy)
        return plot_follow(self.out / "planview.png", scene, np.array(self.path["xy"]), np.array(self.path["found"]),
                           np.array(self.path["cam"]), {i: np.array(v) for i, v in others.items()})


def run(args: argparse.Namespace) -> int:
    from worldtrack.follow import FollowConfig, FollowTracker, PIDFollower
    from worldtrack.follow.pid import pursuit_map
    from worldtrack.follow.planner import LocalPlanner
    from worldtrack.io.rgbd import RGBDSource, read_gains, read_poses
    from worldtrack.scene import load_scene

    scene = load_scene(args.scene)
    if args.camera is None and len(scene.cameras) != 1:
        raise InputError(f"--camera: the scene has {len(scene.cameras)} cameras ({', '.join(scene.cameras)}); name one")
    camera = scene.camera(args.camera or next(iter(scene.cameras)))
    if not Path(args.rgb).exists():
        raise InputError(f"--rgb {args.rgb}: no such file or folder")
    target = parse_target(args.target)
    frames_csv = Path(args.frames_csv) if args.frames_csv else _beside(args.rgb, "frames.csv")
    gains, times = read_gains(frames_csv, camera.id) if frames_csv else (None, None)
    poses_csv = Path(args.poses) if args.poses else _beside(args.rgb, "camera_poses.csv")
    poses = read_poses(poses_csv, camera.id) if poses_csv else None
    if isinstance(target, int):
        gt = Path(args.gt) if args.gt else _beside(args.rgb, "gt.csv")
        if gt is None:
            raise InputError(f"--target {target}: a person id needs ground truth (--gt gt.csv), or give X,Y")
        target = target_position(gt, target)
    config = FollowConfig.preset(args.preset)
    source = RGBDSource(camera, args.rgb, args.depth, args.disparity, args.right, args.baseline, gains, times, poses,
                        args.fps, args.frames)
    tracker = FollowTracker(config, scene)
    follower = (LocalPlanner(scene, distance=args.distance) if args.follower == "planner"
                else PIDFollower(distance=args.distance, depth_stop=args.follower != "pid",
                                 walkers=args.follower == "pid+walkers", nav=pursuit_map(scene)))
    out = _Outputs(Path(args.out), not args.no_video, source.fps)
    n = found = 0
    try:
        it = source
        if not args.quiet:
            from tqdm import tqdm
            it = tqdm(source, desc="follow", unit="frame", file=sys.stderr)
        for frame, cam in it:
            step = tracker.follow(frame, cam, start_xy=target if n == 0 else None)
            command = follower.command(step, cam, frame.t, frame=frame)
            out.write(frame, cam, step, command, follower.blocked, frame.image)
            n += 1
            found += int(step.found)
    finally:
        plot = out.close(scene)
        print(f"{n} frames, target found in {found}; outputs in {out.out}"
              + (f" (plan view {plot.name})" if plot else ""), file=sys.stderr)
        if source.matcher is not None and n:
            print(f"stereo matching (StereoSGBM): {1000 * source.stereo_seconds / n:.1f} ms per frame", file=sys.stderr)
    if n == 0:
        raise InputError(f"--rgb {args.rgb}: no frames read")
    return 0
