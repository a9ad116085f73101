"""A synthetic sequence: scene, people and their motion, lights and cameras, rendered frame by frame.

:class:`Scenario` is what :func:`worldtrack.synth.make_scenario` returns. Iterating
:meth:`Scenario.frames` yields one :class:`SynthBundle` per frame: every camera's
:class:`~worldtrack.synth.render.SynthFrame`, the ground-truth rows of the people present, the frame's
metadata (light level, white-balance gains, robot pose) and, for the pose scenarios, the true pose.

Determinism: everything random is drawn when the scenario is built, from one
``numpy.random.Generator(seed)``; the sensor noise of frame ``k`` comes from a generator seeded by
``(seed, k)``. Rendering the same scenario twice gives identical arrays.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
from typing import Callable, Iterator

import numpy as np

from worldtrack.errors import InputError
from worldtrack.geometry.camera import Camera
from worldtrack.scene.model import Scene
from worldtrack.synth.bodies import HEAD, PARTS_PER_PERSON, BodyShape, PartArrays, body_parts, hair_colours
from worldtrack.synth.environment import Environment
from worldtrack.synth.joints import JointAngles, posed
from worldtrack.synth.motion import Track
from worldtrack.synth.photometry import LightingSchedule, WhiteBalance, grey_world_mean
from worldtrack.synth.render import Renderer, RenderOptions, SynthFrame
from worldtrack.synth.sensors import SensorSpec

GT_BASE_COLUMNS = ("frame", "time", "id", "x", "y", "z_head", "height", "width", "speed")


@dataclass
class Person:
    """A person of the sequence: id (from 1), build and clothes, motion.

    ``pose`` optionally overrides joint angles per frame (pose scenarios): a mapping from a
    :class:`~worldtrack.synth.joints.JointAngles` field name to an array with one row per frame.
    """

    id: int
    shape: BodyShape
    track: Track
    pose: dict[str, np.ndarray] = field(default_factory=dict)


@dataclass
class CameraRig:
    """How one camera behaves: its sensor, white balance, and (for a robot) its pose per frame.

    ``poses`` is None for a fixed camera, else a list of (R, t) world → camera, one per frame.
    """

    sensor: SensorSpec = field(default_factory=SensorSpec)
    white_balance: WhiteBalance = field(default_factory=WhiteBalance)
    poses: list[tuple[np.ndarray, np.ndarray]] | None = None


@dataclass
class SynthBundle:
    """Everything about one frame.

    Attributes
    ----------
    frame : int (from 0); time : float, seconds (= frame / fps)
    views : dict camera id → SynthFrame
    gt : list of dict — gt.csv rows of the people present (keys :meth:`Scenario.gt_columns`)
    meta : dict — the frames.csv row
    pose : list of dict — pose.csv rows (pose scenarios), else empty
    """

    frame: int
    time: float
    views: dict[str, SynthFrame]
    gt: list[dict]
    meta: dict
    pose: list[dict] = field(default_factory=list)


class Scenario:
    """A ready-to-render synthetic sequence (see the module docstring).

    Attributes
    ----------
    name : str; scene : Scene (cameras at their first-frame pose); fps : float; n_frames : int
    people : list of Person; environment : Environment; lighting : LightingSchedule
    options : RenderOptions; rigs : dict camera id → CameraRig; seed : int
    params : dict — the parameters the scenario was built with (for README.txt)
    pose_rows : callable(frame, people, parts) → list of dict, or None
    """

    def __init__(self, name: str, scene: Scene, fps: float, n_frames: int, people: list[Person],
                 environment: Environment, lighting: LightingSchedule, options: RenderOptions,
                 rigs: dict[str, CameraRig], seed: int, params: dict | None = None,
                 pose_rows: Callable | None = None, description: str = ""):
        self.name = name
        self.scene = scene
        self.fps = float(fps)
        self.n_frames = int(n_frames)
        self.people = people
        self.environment = environment
        self.lighting = lighting
        self.options = options
        self.rigs = {cid: rigs.get(cid, CameraRig()) for cid in scene.cameras}
        for cid, rig in self.rigs.items():
            if rig.sensor.has_depth and scene.cameras[cid].has_distortion:
                raise InputError(f"camera {cid!r}: a {rig.sensor.kind} sensor is modelled as a rectified "
                                 "pinhole camera; expected no lens distortion")
        self.seed = int(seed)
        self.params = dict(params or {})
        self.pose_rows = pose_rows
        self.description = description
        self._renderer = Renderer(scene, environment, options, {c: r.sensor for c, r in self.rigs.items()})

    # ------------------------------------------------------------------ structure
    @property
    def camera_ids(self) -> list[str]:
        return list(self.scene.cameras)

    @property
    def moving_cameras(self) -> list[str]:
        return [c for c, r in self.rigs.items() if r.poses is not None]

    def gt_columns(self) -> list[str]:
        """gt.csv columns: the base ones, then ``vis_<cam>, head_<cam>, feet_<cam>`` per camera."""
        cols = list(GT_BASE_COLUMNS)
        for c in self.camera_ids:
            cols += [f"vis_{c}", f"head_{c}", f"feet_{c}"]
        return cols

    def camera_at(self, camera_id: str, frame: int) -> Camera:
        """The camera at ``frame`` (its fixed pose, or the robot's pose then)."""
        cam = self.scene.cameras[camera_id]
        poses = self.rigs[camera_id].poses
        if poses is None:
            return cam
        R, t = poses[min(max(frame, 0), len(poses) - 1)]
        return cam.moved(R, t)

    def time(self, frame: int) -> float:
        return frame / self.fps

    def present(self, frame: int) -> list[Person]:
        return [p for p in self.people if p.track.present[frame]]

    def pose_people(self, frame: int) -> tuple[list[Person], PartArrays]:
        """The people present at ``frame`` and their posed parts."""
        people = self.present(frame)
        if not people:
            return people, body_parts([], JointAngles.neutral(np.zeros((0, 2)), np.zeros(0)))
        tr = [p.track for p in people]
        ja = posed(np.array([t.xy[frame] for t in tr]), np.array([t.yaw[frame] for t in tr]),
                   np.array([t.phase[frame] for t in tr]), np.array([t.amplitude[frame] for t in tr]),
                   np.array([t.sit[frame] for t in tr]))
        for i, p in enumerate(people):
            for name, values in p.pose.items():
                getattr(ja, name)[i] = values[frame]
        return people, body_parts([p.shape for p in people], ja)

    # ------------------------------------------------------------------ rendering
    def frames(self, progress: bool = False) -> Iterator[SynthBundle]:
        """Render the sequence from frame 0, one :class:`SynthBundle` per frame."""
        wbs = {c: self._initial_white_balance(c) for c in self.rigs}
        it = range(self.n_frames)
        if progress:
            from tqdm import tqdm
            it = tqdm(it, desc=f"synth {self.name}", unit="frame")
        for k in it:
            yield self._render_frame(k, wbs)

    def render(self) -> list[SynthBundle]:
        """All frames as a list (small sequences only)."""
        return list(self.frames())

    def _render_frame(self, k: int, wbs: dict[str, WhiteBalance], with_noise: bool = True) -> SynthBundle:
        t = self.time(k)
        people, parts = self.pose_people(k)
        ids = np.array([p.id for p in people], dtype=np.int64)
        shapes = [p.shape for p in people]
        hair = hair_colours(shapes) if shapes else np.zeros((0, 3), np.float32)
        style = np.array([s.hair_style for s in shapes], dtype=np.int64)
        ground = np.array([[p.track.xy[k, 0], p.track.xy[k, 1], 0.0] for p in people]).reshape(-1, 3)
        rng = np.random.default_rng([self.seed, k, 7])
        views: dict[str, SynthFrame] = {}
        vis = {}
        for cid in self.camera_ids:
            cam = self.camera_at(cid, k)
            moving = self.rigs[cid].poses is not None
            light, _ = self.lighting.at(t, _camera_yaw(cam) if moving else None)
            views[cid], vis[cid] = self._renderer.render(cam, parts, ids, hair, style, light, wbs[cid], k, t, rng,
                                                         ground, moving=moving, with_noise=with_noise)
        # Level, exposure and segment do not depend on the camera (only a moving camera's light direction does).
        first_light, segment = self.lighting.at(t)
        meta: dict = {"frame": k, "time": round(t, 6), "light_level": round(float(first_light.level), 6)}
        for cid in self.camera_ids:
            meta[f"wb_r_{cid}"], meta[f"wb_b_{cid}"] = views[cid].wb_gains
        meta["exposure"] = round(float(first_light.exposure), 6)
        meta["segment"] = segment
        for cid in self.moving_cameras:
            cam = views[cid].camera
            c = cam.centre
            meta[f"{cid}_x"], meta[f"{cid}_y"], meta[f"{cid}_z"] = (round(float(v), 6) for v in c)
            meta[f"{cid}_yaw_deg"] = round(float(np.degrees(_camera_yaw(cam))), 4)
        gt = []
        fraction = {cid: v.fraction for cid, v in vis.items()}
        for i, p in enumerate(people):
            row = {"frame": k, "time": round(t, 6), "id": p.id,
                   "x": round(float(p.track.xy[k, 0]), 6), "y": round(float(p.track.xy[k, 1]), 6),
                   "z_head": round(float(parts.head_top[i, 2]), 6), "height": round(p.shape.height, 6),
                   "width": round(p.shape.shoulder_width, 6), "speed": round(float(p.track.speed[k]), 6)}
            for cid in self.camera_ids:
                v = vis[cid]
                row[f"vis_{cid}"] = round(float(fraction[cid][i]), 4)
                row[f"head_{cid}"] = int(v.head_visible[i])
                row[f"feet_{cid}"] = int(v.feet_visible[i])
            gt.append(row)
        pose = self.pose_rows(k, t, people, parts) if self.pose_rows else []
        return SynthBundle(k, t, views, gt, meta, pose)

    def _empty_raw_mean(self, camera_id: str) -> np.ndarray:
        cam = self.camera_at(camera_id, 0)
        moving = self.rigs[camera_id].poses is not None
        light, _ = self.lighting.at(0.0, _camera_yaw(cam) if moving else None)
        layer = self._renderer.static_layer(cam, moving)
        lit, _ = self._renderer.lit_static(cam, layer, light)
        raw = lit * np.float32(light.level * light.exposure) * np.asarray(light.tint, np.float32) \
            + np.float32(light.exposure) * layer.emissive
        return grey_world_mean(raw)

    def _initial_white_balance(self, camera_id: str) -> WhiteBalance:
        """The camera's white balance before frame 0: settled on the empty scene (auto mode)."""
        wb = copy.deepcopy(self.rigs[camera_id].white_balance)
        if wb.mode == "auto":
            wb.update(-1, self._empty_raw_mean(camera_id))
        return wb

    def background(self, camera_id: str) -> np.ndarray:
        """The empty scene as ``camera_id`` sees it at frame 0: noise-free, under frame 0's lighting,
        with the white balance the camera had settled on before people came (uint8 BGR) — the
        background plate a background subtractor starts from."""
        cam = self.camera_at(camera_id, 0)
        moving = self.rigs[camera_id].poses is not None
        light, _ = self.lighting.at(0.0, _camera_yaw(cam) if moving else None)
        wb = self._initial_white_balance(camera_id)
        return self._renderer.background(cam, light, (wb.r, wb.b), moving)

    def __repr__(self) -> str:
        return (f"Scenario({self.name!r}, cameras={self.camera_ids}, people={len(self.people)}, "
                f"frames={self.n_frames}, fps={self.fps:g})")


def _camera_yaw(cam: Camera) -> float:
    """Heading (rad) of the camera's viewing direction on the floor."""
    d = cam.floor_direction
    return float(np.arctan2(d[1], d[0]))


def head_pose(parts: PartArrays, i: int) -> tuple[np.ndarray, np.ndarray]:
    """Centre (3,) and head → world rotation (3, 3) of person ``i``'s head."""
    k = i * PARTS_PER_PERSON + HEAD
    return parts.centre[k].copy(), parts.axes[k].T.copy()
