"""Writing a synthetic sequence to a folder: videos or PNGs, depth, ground truth, metadata.

Layout of ``out_dir`` (see :func:`write_sequence`; the folder's README.txt repeats it)::

    scene.yaml                  the scene (cameras at frame 0), readable by worldtrack.scene.load_scene
    <cam>.mp4 | <cam>/NNNNNN.png colour video (MP4, fourcc mp4v) or lossless PNG frames
    <cam>_background.png        the empty scene, noise-free, at frame 0's light and white balance
    <cam>_depth/NNNNNN.png      measured depth, 16-bit, millimetres, 0 = no measurement (stereo, RGB-D)
    <cam>_disparity/NNNNNN.png  measured disparity, 16-bit, 1/16 pixel, 0 = none (stereo)
    <cam>_instance/NNNNNN.png   person ids, 16-bit, 0 = background (with instances=True)
    gt.csv                      one row per person present per frame
    frames.csv                  per-frame light level, white-balance gains, lighting segment, robot pose
    camera_poses.csv            per-frame pose of moving cameras (rvec, t: world → camera)
    pose.csv                    true pose parameters (face-pose, upper-body)
    README.txt
"""

from __future__ import annotations

import csv
from pathlib import Path

import cv2
import numpy as np

from worldtrack.errors import InputError
from worldtrack.geometry.rotation import rotation_to_rodrigues
from worldtrack.scene.load import dump_scene
from worldtrack.synth.sensors import depth_to_png_mm, disparity_to_png
from worldtrack.synth.sequence import Scenario

_PNG = [cv2.IMWRITE_PNG_COMPRESSION, 3]


def _fmt(v) -> str:
    if isinstance(v, (bool, np.bool_)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        return repr(float(v)) if np.isfinite(v) else ""
    return str(v)


class _Csv:
    def __init__(self, path: Path, columns: list[str]):
        self.f = open(path, "w", newline="")
        self.w = csv.writer(self.f, lineterminator="\n")
        self.columns = columns
        self.w.writerow(columns)

    def rows(self, rows: list[dict]) -> None:
        for r in rows:
            self.w.writerow([_fmt(r.get(c, "")) for c in self.columns])

    def close(self) -> None:
        self.f.close()


def write_sequence(scenario: Scenario, out_dir: str | Path, png: bool = False, progress: bool = True,
                   instances: bool = False) -> Path:
    """Render ``scenario`` and write it to ``out_dir`` (created; existing files are overwritten).

    Parameters
    ----------
    png : bool — lossless PNG frames instead of MP4 video
    progress : bool — show a progress bar on stderr
    instances : bool — also write the instance-id images

    Returns
    -------
    Path of the folder. Same scenario and seed → identical files (PNG and CSV byte for byte; MP4 is
    deterministic with this OpenCV build too, but that depends on the codec library).
    """
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise InputError(f"--out: cannot create folder {out} ({e.strerror})") from None
    dump_scene(scenario.scene, out / "scene.yaml")
    cams = scenario.camera_ids
    rigs = scenario.rigs
    writers: dict[str, cv2.VideoWriter] = {}
    for cid in cams:
        cam = scenario.scene.cameras[cid]
        cv2.imwrite(str(out / f"{cid}_background.png"), scenario.background(cid), _PNG)
        if png:
            (out / cid).mkdir(exist_ok=True)
        else:
            vw = cv2.VideoWriter(str(out / f"{cid}.mp4"), cv2.VideoWriter_fourcc(*"mp4v"), scenario.fps,
                                 (cam.width, cam.height))
            if not vw.isOpened():
                raise InputError(f"cannot open an MP4 writer for {out / (cid + '.mp4')} (try --png)")
            writers[cid] = vw
        if rigs[cid].sensor.has_depth:
            (out / f"{cid}_depth").mkdir(exist_ok=True)
        if rigs[cid].sensor.kind == "stereo":
            (out / f"{cid}_disparity").mkdir(exist_ok=True)
        if instances:
            (out / f"{cid}_instance").mkdir(exist_ok=True)
    gt = _Csv(out / "gt.csv", scenario.gt_columns())
    frames_csv = None
    poses_csv = None
    if scenario.moving_cameras:
        poses_csv = _Csv(out / "camera_poses.csv", ["frame", "time", "camera", "rvec_x", "rvec_y", "rvec_z",
                                                     "t_x", "t_y", "t_z", "centre_x", "centre_y", "centre_z"])
    pose_csv = None
    try:
        for b in scenario.frames(progress=progress):
            name = f"{b.frame:06d}.png"
            for cid in cams:
                v = b.views[cid]
                if png:
                    cv2.imwrite(str(out / cid / name), v.image, _PNG)
                else:
                    writers[cid].write(v.image)
                if v.sensor_depth is not None:
                    cv2.imwrite(str(out / f"{cid}_depth" / name), depth_to_png_mm(v.sensor_depth), _PNG)
                if v.disparity is not None:
                    cv2.imwrite(str(out / f"{cid}_disparity" / name), disparity_to_png(v.disparity), _PNG)
                if instances:
                    cv2.imwrite(str(out / f"{cid}_instance" / name), v.instance.astype(np.uint16), _PNG)
            gt.rows(b.gt)
            if frames_csv is None:
                frames_csv = _Csv(out / "frames.csv", list(b.meta))
            frames_csv.rows([b.meta])
            if poses_csv is not None:
                for cid in scenario.moving_cameras:
                    cam = b.views[cid].camera
                    r = rotation_to_rodrigues(cam.R)
                    c = cam.centre
                    poses_csv.rows([{"frame": b.frame, "time": round(b.time, 6), "camera": cid,
                                     **{f"rvec_{a}": round(float(x), 9) for a, x in zip("xyz", r)},
                                     **{f"t_{a}": round(float(x), 9) for a, x in zip("xyz", cam.t)},
                                     **{f"centre_{a}": round(float(x), 9) for a, x in zip("xyz", c)}}])
            if b.pose:
                if pose_csv is None:
                    pose_csv = _Csv(out / "pose.csv", list(b.pose[0]))
                pose_csv.rows(b.pose)
    finally:
        for vw in writers.values():
            vw.release()
        for c in (gt, frames_csv, poses_csv, pose_csv):
            if c is not None:
                c.close()
    (out / "README.txt").write_text(readme_text(scenario, png, instances))
    return out


def readme_text(scenario: Scenario, png: bool, instances: bool) -> str:
    """The README.txt of an output folder."""
    cams = scenario.camera_ids
    lines = [
        f"worldtrack synthetic sequence: {scenario.name}",
        f"{scenario.description}",
        "",
        f"frames: {scenario.n_frames} at {scenario.fps:g} fps (time = frame / fps, frames from 0)",
        f"cameras: {', '.join(cams)}"
        + (f" (moving: {', '.join(scenario.moving_cameras)})" if scenario.moving_cameras else ""),
        "parameters: " + ", ".join(f"{k}={v}" for k, v in scenario.params.items()),
        "",
        "Units: metres, seconds; world Z up, floor Z = 0; images BGR, pixel centres at integers.",
        "",
        "Files",
        "-----",
        "scene.yaml            the scene: cameras (their frame-0 pose), walkable floor, obstacles, entry regions.",
    ]
    for cid in cams:
        sensor = scenario.rigs[cid].sensor
        if png:
            lines.append(f"{cid}/NNNNNN.png     colour frames, lossless PNG (BGR).")
        else:
            lines.append(f"{cid}.mp4              colour video, MP4 (fourcc mp4v, lossy compression).")
        lines.append(f"{cid}_background.png  the empty scene, noise-free, frame 0's lighting and white balance.")
        if sensor.has_depth:
            extra = (f"RGB-D: quantised to {sensor.depth_step * 1000:g} mm, invalid below {sensor.depth_min:g} m"
                     if sensor.kind == "rgbd" else f"stereo, baseline {sensor.baseline:g} m: depth = fx*B/disparity")
            lines.append(f"{cid}_depth/NNNNNN.png   measured depth, 16-bit PNG, millimetres, "
                         f"0 = no measurement ({extra}).")
        if sensor.kind == "stereo":
            lines.append(f"{cid}_disparity/NNNNNN.png  measured disparity, 16-bit PNG in 1/16 pixel (value/16 = px), "
                         "0 = no measurement (occluded in the right view, too little texture, speckle).")
        if instances:
            lines.append(f"{cid}_instance/NNNNNN.png  person id per pixel, 16-bit PNG, 0 = background.")
    lines += [
        "gt.csv                one row per person present per frame:",
        "  frame, time (s), id (from 1);",
        "  x, y (m): the ground point = the pelvis centre projected on the floor (midway between the",
        "    ankles when standing; the point a tracker should report);",
        "  z_head (m): current top of the head; height (m): standing body height; width (m): shoulder",
        "    width; speed (m/s): ground speed, exactly 0 while standing still;",
        "  vis_<cam>: visible pixels of the person / pixels the person covers when rendered alone",
        "    (no obstacles, no other people) on the image plane extended to 3x the image size",
        "    (so obstacles, other people and the image border all reduce it);",
        "  head_<cam>, feet_<cam>: 1 if the top of the head / the ground point is inside the image and",
        "    not hidden by an obstacle or another person.",
        "frames.csv            per frame: light_level (relative), wb_r_<cam>, wb_b_<cam> (white-balance gains,",
        "                      0-1023, 512 = x1), segment (lighting segment), and moving cameras' centre/heading.",
    ]
    if scenario.moving_cameras:
        lines.append("camera_poses.csv      per frame and moving camera: rvec, t (world -> camera, OpenCV), "
                     "centre (m).")
    if scenario.pose_rows is not None:
        lines.append("pose.csv              true pose per frame (columns named with units; angles in degrees).")
    return "\n".join(lines) + "\n"
