"""``worldtrack pose track``: track the 6-DoF pose of a face or a rigid object (paper 003).

    worldtrack pose track --model face|upper-body|MODEL.obj --rgb DIR [--depth DIR] \\
        --camera K.yaml --init POSE --out DIR

Writes ``DIR/pose.csv`` (one row per frame, flushed as it goes: the pose of the model in the
camera frame — translation in metres, quaternion, ZYX angles in degrees; for upper-body the 14
parameters — the synthetic ground truth's columns, plus the per-frame cost), ``DIR/annotated.mp4``
(model outline and axes) and ``DIR/cost.png``. A face uses the built-in face model and its
eigen-template (RGB); an OBJ mesh and the upper body (default proportions) learn their appearance
from the first frame at ``--init`` and use colour and, with ``--depth``, depth.
"""

from __future__ import annotations

import argparse
import csv
import math
from pathlib import Path

import cv2
import numpy as np
import yaml

from worldtrack.errors import InputError
from worldtrack.pose.models import PointModel, load_obj
from worldtrack.pose.render import Intrinsics, learn_appearance
from worldtrack.pose.tracker import RigidTracker, TrackerConfig, to_grey

IMAGE_EXT = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")
DEPTH_EXT = (".png", ".tif", ".tiff", ".npz", ".npy")
COLUMNS = ["frame", "time", "id", "tx", "ty", "tz", "qw", "qx", "qy", "qz", "rz_deg", "ry_deg", "rx_deg",
           "cost", "n_template"]


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("pose", help="track the pose of a face, an upper body or a rigid object (paper 003)",
                       description="Pose tracking by particle filter + Levenberg-Marquardt (paper 003).")
    verbs = p.add_subparsers(dest="pose_command", metavar="<verb>")
    t = verbs.add_parser("track", help="track a model through a folder of frames",
                         description=__doc__.split("\n\n")[0] + " " + __doc__.split("\n\n")[2].replace("\n", " "))
    t.add_argument("--model", required=True, help="face, upper-body, or a Wavefront OBJ mesh in metres")
    t.add_argument("--rgb", required=True, metavar="DIR", help="folder of colour frames (sorted by name)")
    t.add_argument("--depth", metavar="DIR", help="folder of depth frames (16-bit PNG or .npz/.npy), one per colour frame")
    t.add_argument("--depth-scale", type=float, default=0.001, help="depth units in metres (default 0.001: mm)")
    t.add_argument("--camera", required=True, metavar="K.yaml",
                   help="intrinsics: YAML/JSON with K (3x3) or fx, fy, cx, cy (or ViSP's px, py, u0, v0)")
    t.add_argument("--init", required=True, metavar="POSE",
                   help="pose at the first frame: a file holding a 4x4 object-to-camera matrix (metres), or "
                        "'x,y,z,rx,ry,rz' (metres; rotation vector in degrees); for upper-body 14 numbers: "
                        "torso tx,ty,tz (m), torso rz,ry,rx, then left shoulder, left elbow, right shoulder, "
                        "right elbow rz,ry (degrees)")
    t.add_argument("--out", default="pose_out", metavar="DIR", help="output folder (default pose_out)")
    t.add_argument("--stages", type=int, default=1, help="coarse-to-fine particle-filter stages (PFx, default 1)")
    t.add_argument("--lm-iterations", type=int, default=None,
                   help="LM iterations per frame (LMx, default 10; 15 for upper-body)")
    t.add_argument("--candidates", type=int, default=None,
                   help="candidates per stage (default 1000; 1500 for upper-body)")
    t.add_argument("--face-identity", type=int, default=0, help="built-in face model to use with --model face")
    t.add_argument("--lam", type=float, default=0.9, help="share of the depth term (λ, default 0.9)")
    t.add_argument("--fps", type=float, default=30.0, help="frame rate for time stamps (default 30)")
    t.add_argument("--seed", type=int, default=0, help="random seed of the particle filter")
    t.add_argument("--no-video", action="store_true", help="do not write annotated.mp4")
    t.add_argument("--quiet", action="store_true", help="no progress bar")
    t.set_defaults(func=run)
    p.set_defaults(func=lambda a: (p.print_help(), 2)[1])


def read_camera(path: str) -> dict:
    """Intrinsics from YAML/JSON: ``{fx, fy, cx, cy, width?, height?}`` (pixels)."""
    try:
        data = yaml.safe_load(Path(path).read_text())
    except (OSError, yaml.YAMLError, UnicodeDecodeError) as e:
        raise InputError(f"--camera {path}: cannot read ({getattr(e, 'strerror', None) or e})") from None
    if not isinstance(data, dict):
        raise InputError(f"--camera {path}: expected a mapping with K or fx, fy, cx, cy")
    try:
        if "K" in data or "camera_matrix" in data:
            K = np.asarray(data.get("K", data.get("camera_matrix")), float).reshape(3, 3)
            cam = {"fx": K[0, 0], "fy": K[1, 1], "cx": K[0, 2], "cy": K[1, 2]}
        elif "px" in data:
            cam = {"fx": data["px"], "fy": data["py"], "cx": data["u0"], "cy": data["v0"]}
        else:
            cam = {k: data[k] for k in ("fx", "fy", "cx", "cy")}
        cam = {k: float(v) for k, v in cam.items()}
    except (KeyError, ValueError, TypeError) as e:
        raise InputError(f"--camera {path}: expected K (3x3) or fx, fy, cx, cy in pixels ({e})") from None
    if not (cam["fx"] > 0 and cam["fy"] > 0):
        raise InputError(f"--camera {path}: focal lengths must be positive, got fx={cam['fx']}, fy={cam['fy']}")
    for a, b in (("width", "w"), ("height", "h")):
        if a in data or b in data:
            cam[a] = int(data.get(a, data.get(b)))
    return cam


def read_pose(text: str) -> tuple[np.ndarray, np.ndarray]:
    """(R, t) from a file with a 4×4 (or 3×4) matrix, or from ``x,y,z,rx,ry,rz`` (m, degrees)."""
    p = Path(text)
    if p.is_file():
        raw = p.read_text()
        try:
            data = yaml.safe_load(raw)
            nums = np.asarray(data, float).ravel() if not isinstance(data, (dict, str)) else None
        except (yaml.YAMLError, ValueError, TypeError):
            nums = None
        if nums is None:
            try:
                nums = np.array([float(x) for x in raw.replace(",", " ").replace("[", " ").replace("]", " ").split()])
            except ValueError:
                raise InputError(f"--init {text}: expected a 4x4 pose matrix (numbers)") from None
        if nums.size not in (12, 16):
            raise InputError(f"--init {text}: expected a 4x4 or 3x4 matrix, got {nums.size} numbers")
        M = nums[:12].reshape(3, 4)
        U, _, Vt = np.linalg.svd(M[:, :3])
        return U @ np.diag([1, 1, np.linalg.det(U @ Vt)]) @ Vt, M[:, 3].copy()
    try:
        v = [float(x) for x in text.split(",")]
    except ValueError:
        v = []
    if len(v) != 6 or not all(math.isfinite(x) for x in v):
        raise InputError(f"--init {text!r}: expected a pose file or x,y,z,rx,ry,rz (metres, degrees)")
    return cv2.Rodrigues(np.radians(np.array(v[3:])))[0], np.array(v[:3])


def _listing(folder: str, ext: tuple, flag: str) -> list[Path]:
    d = Path(folder)
    if not d.is_dir():
        raise InputError(f"{flag} {folder}: no such folder")
    files = sorted(f for f in d.iterdir() if f.suffix.lower() in ext)
    if not files:
        raise InputError(f"{flag} {folder}: no frames ({', '.join(ext)}) in the folder")
    return files


def read_depth(path: Path, scale: float) -> np.ndarray:
    """Depth in metres (0 = no measurement) from a 16-bit PNG/TIFF, ``.npz`` (array ``data``) or ``.npy``."""
    try:
        if path.suffix == ".npz":
            with np.load(path, allow_pickle=False) as z:
                raw = z["data"] if "data" in z.files else z[z.files[0]]
        elif path.suffix == ".npy":
            raw = np.load(path, allow_pickle=False)
        else:
            raw = cv2.imread(str(path), cv2.IMREAD_ANYDEPTH)
    except (OSError, ValueError, KeyError, IndexError) as e:
        raise InputError(f"{path}: cannot read depth ({e})") from None
    if raw is None or raw.ndim != 2:
        raise InputError(f"{path}: cannot read depth (expected a single-channel image or array)")
    return np.nan_to_num(raw.astype(np.float32) * np.float32(scale))


def _model(args) -> tuple[PointModel, str]:
    """The model (geometry; albedo for the face) and its cost."""
    if args.model == "face":
        from worldtrack.synth.faces import face_model, make_face
        return face_model(make_face(args.face_identity)), "eigen"
    return load_obj(args.model), "colour-depth"


def _learn(args, model: PointModel, first: np.ndarray, intr: Intrinsics, R0, t0) -> PointModel:
    """An OBJ model's appearance, read from the first frame at the initial pose."""
    albedo = learn_appearance(model.points, model.normals, to_grey(first), intr, R0, t0)
    if not np.isfinite(albedo).any():
        raise InputError(f"--init: the model {args.model} is not in view of the first frame at this pose")
    return model.with_albedo(albedo)


def run(args: argparse.Namespace) -> int:
    colour = _listing(args.rgb, IMAGE_EXT, "--rgb")
    depths = _listing(args.depth, DEPTH_EXT, "--depth") if args.depth else None
    if depths is not None and len(depths) != len(colour):
        raise InputError(f"--depth {args.depth}: {len(depths)} depth frames for {len(colour)} colour frames")
    cam = read_camera(args.camera)
    first = cv2.imread(str(colour[0]), cv2.IMREAD_COLOR)
    if first is None:
        raise InputError(f"{colour[0]}: cannot read the image")
    h, w = first.shape[:2]
    if ("width" in cam and cam["width"] != w) or ("height" in cam and cam["height"] != h):
        raise InputError(f"--camera {args.camera}: made for {cam.get('width')}x{cam.get('height')} images, "
                         f"but {colour[0].name} is {w}x{h}")
    intr = Intrinsics(cam["fx"], cam["fy"], cam["cx"], cam["cy"], w, h)
    if depths is not None:
        d0 = read_depth(depths[0], args.depth_scale)
        if d0.shape != (h, w):
            raise InputError(f"{depths[0]}: depth is {d0.shape[1]}x{d0.shape[0]} but the colour frame "
                             f"{colour[0].name} is {w}x{h}")
    if args.model == "upper-body":
        return _run_body(args, colour, depths, first, intr)
    R0, t0 = read_pose(args.init)
    model, cost = _model(args)
    z = (model.points @ R0.T + t0)[:, 2]
    if z.min() <= 0.01:
        raise InputError(f"--init: the pose puts the model behind the camera (nearest point at z = {z.min():.3f} m)")
    if cost == "colour-depth":
        model = _learn(args, model, first, intr, R0, t0)
    config = TrackerConfig(stages=args.stages, lm_iterations=10 if args.lm_iterations is None else args.lm_iterations,
                           n_candidates=1000 if args.candidates is None else args.candidates, lam=args.lam, seed=args.seed)
    tracker = RigidTracker(model, intr, R0, t0, config, cost=cost)
    if cost == "colour-depth" and depths is not None:
        tracker.learn_depth_offset(d0)          # the sensor's depth bias at the object, at the known first pose
    return _track_rigid(args, colour, depths, tracker, intr, model, (R0, t0), (w, h))


BODY_COLUMNS = (["frame", "time", "id", "torso_tx", "torso_ty", "torso_tz", "torso_rz_deg", "torso_ry_deg",
                 "torso_rx_deg"] + [f"{s}_{j}_{a}_deg" for s in "lr" for j in ("shoulder", "elbow") for a in ("rz", "ry")]
                + ["cost", "n_template"])


def read_body_pose(text: str) -> np.ndarray:
    """14 parameters from ``tx,ty,tz`` (m) and 11 angles (degrees), given inline or in a file."""
    raw = Path(text).read_text() if Path(text).is_file() else text
    try:
        v = np.array([float(x) for x in raw.replace(",", " ").split()])
    except ValueError:
        v = np.zeros(0)
    if v.size != 14 or not np.isfinite(v).all():
        raise InputError(f"--init {text!r}: for upper-body expected 14 numbers: tx,ty,tz (m), torso rz,ry,rx, "
                         "left shoulder rz,ry, left elbow rz,ry, right shoulder rz,ry, right elbow rz,ry (degrees)")
    return np.r_[v[:3], np.radians(v[3:])]


def _run_body(args, colour, depths, first, intr: Intrinsics) -> int:
    """``--model upper-body``: the 14-DoF tracker, a default body shape, appearance from frame 0."""
    from worldtrack.pose.body import body_geometry, body_transforms, model_points_camera, with_part_albedo
    from worldtrack.pose.body_tracker import BodyConfig, BodyTracker
    from worldtrack.viz.pose_overlay import draw_pose

    if depths is None:
        raise InputError("--model upper-body needs --depth (the body is tracked with colour and depth)")
    p0 = read_body_pose(args.init)
    shape = body_geometry(0.003)
    xyz = model_points_camera(p0, shape)
    if xyz[:, 2].min() <= 0.01:
        raise InputError(f"--init: the pose puts the model behind the camera (nearest point at z = {xyz[:, 2].min():.3f} m)")
    T = body_transforms(p0[None], shape)[0]
    normals = np.concatenate([m.normals @ T[k, :, :3].T for k, m in enumerate(shape.parts)])
    model = with_part_albedo(shape, learn_appearance(xyz, normals, to_grey(first), intr, np.eye(3), np.zeros(3)))
    config = BodyConfig(stages=args.stages, lm_iterations=15 if args.lm_iterations is None else args.lm_iterations,
                        n_candidates=1500 if args.candidates is None else args.candidates, lam=args.lam, seed=args.seed)
    tracker = BodyTracker(model, intr, p0, config)

    def step(image, depth):
        est = tracker.step(image, depth)
        return est.params, est.cost, est.n_template

    def row(k, p, c, n):
        vals = [k, round(k / args.fps, 6), 1, *np.round(p[:3], 6), *np.round(np.degrees(p[3:]), 5)]
        return vals + ["" if not math.isfinite(c) else round(c, 6), n]

    def draw(image, p, label):
        out = draw_pose(image, model_points_camera(p, model), np.eye(3), np.zeros(3), intr, 0.0)
        T0 = body_transforms(p[None], model)[0, 0]
        return draw_pose(out, np.zeros((0, 3)), T0[:, :3], T0[:, 3], intr, 0.15, label=label)

    return _loop(args, colour, depths, (intr.width, intr.height), BODY_COLUMNS, p0, step, row, draw)


def _row(k: int, fps: float, R: np.ndarray, t: np.ndarray, cost: float, n: int) -> list:
    from scipy.spatial.transform import Rotation

    x, y, zq, wq = Rotation.from_matrix(R).as_quat()
    if wq < 0:
        x, y, zq, wq = -x, -y, -zq, -wq
    rz, ry, rx = Rotation.from_matrix(R).as_euler("ZYX", degrees=True)
    vals = [k, round(k / fps, 6), 1, *np.round(t, 6), *np.round([wq, x, y, zq], 8), *np.round([rz, ry, rx], 5)]
    return vals + ["" if not math.isfinite(cost) else round(cost, 6), n]


def _loop(args, colour: list[Path], depths, size: tuple, columns: list[str], pose0, step, row, draw) -> int:
    """Read the frames, call ``step(image, depth) → (pose, cost, n)`` from frame 1 on, write
    ``row(k, pose, cost, n)`` to pose.csv (flushed per frame) and ``draw(image, pose, label)`` to
    the video; the outputs written so far stay valid when a frame is bad or on Ctrl-C."""
    from tqdm import tqdm

    from worldtrack.io.video import VideoWriter

    out = Path(args.out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise InputError(f"--out {out}: cannot create the folder ({e.strerror})") from None
    video = None if args.no_video else VideoWriter(out / "annotated.mp4", args.fps)
    costs = []
    with open(out / "pose.csv", "w", newline="") as f:
        writer = csv.writer(f, lineterminator="\n")
        writer.writerow(columns)
        try:
            for k, path in enumerate(tqdm(colour, desc="pose", unit="frame", disable=args.quiet)):
                image = cv2.imread(str(path), cv2.IMREAD_COLOR)
                if image is None:
                    raise InputError(f"{path}: cannot read the image")
                if image.shape[:2] != (size[1], size[0]):
                    raise InputError(f"{path}: {image.shape[1]}x{image.shape[0]}, expected {size[0]}x{size[1]} "
                                     "like the first frame")
                depth = read_depth(depths[k], args.depth_scale) if depths is not None else None
                if depth is not None and depth.shape != image.shape[:2]:
                    raise InputError(f"{depths[k]}: depth is {depth.shape[1]}x{depth.shape[0]} but the colour "
                                     f"frame {path.name} is {image.shape[1]}x{image.shape[0]}")
                pose, c, n = (pose0, float("nan"), 0) if k == 0 else step(image, depth)
                costs.append(c)
                writer.writerow(row(k, pose, c, n))
                f.flush()
                if video is not None:
                    video.write(draw(image, pose, f"frame {k}  cost {c:.3f}"))
        finally:
            if video is not None:
                video.close()
            _cost_plot(out / "cost.png", costs, args.fps)
    print(f"wrote {out / 'pose.csv'} ({len(costs)} frames)" + ("" if video is None else f", {out / 'annotated.mp4'}"))
    return 0


def _track_rigid(args, colour, depths, tracker: RigidTracker, intr: Intrinsics, model: PointModel, pose0, size) -> int:
    from worldtrack.viz.pose_overlay import draw_pose

    def step(image, depth):
        est = tracker.step(image, depth)
        return (est.R, est.t), est.cost, est.n_template

    return _loop(args, colour, depths, size, COLUMNS, pose0, step,
                 lambda k, pose, c, n: _row(k, args.fps, *pose, c, n),
                 lambda image, pose, label: draw_pose(image, model.points, *pose, intr, model.radius * 0.8, label=label))


def _cost_plot(path: Path, costs: list[float], fps: float) -> None:
    if len(costs) < 2:
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 2.5))
    ax.plot(np.arange(len(costs)) / fps, costs)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("mean ρ over the template")
    ax.set_title("per-frame cost")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)

