"""Paper 003's world: an RGB-D camera in a booth looking at a face (6-DoF head motion) or an
upper body (14 DoF).

Registered as ``face-pose`` and ``upper-body``.
"""

from __future__ import annotations

import numpy as np

from worldtrack.errors import InputError
from worldtrack.synth import scenes
from worldtrack.synth.bodies import (body_parts, HEAD, TORSO, L_UPPER_ARM, L_FOREARM, R_UPPER_ARM, R_FOREARM,
                                     PARTS_PER_PERSON)
from worldtrack.synth.environment import Environment
from worldtrack.synth.joints import JointAngles, limb_rotation
from worldtrack.synth.motion import Track
from worldtrack.synth.photometry import Light, light_direction
from worldtrack.synth.scenarios import Common, _register, _scene, _options, _lighting, _rigs, _shape
from worldtrack.synth.sensors import SensorSpec
from worldtrack.synth.sequence import Person, Scenario, head_pose


def _booth(size, depth_step_mm, cam_pos, cam_target):
    data = scenes.scene_dict("booth")
    data["cameras"][0].update(position=[float(v) for v in cam_pos], look_at=[float(v) for v in cam_target])
    scene = _scene(data, size or (320, 240))
    env = Environment(wall_height=2.6, floor_style="wood", floor_colour=(90, 120, 150), wall_colour=(170, 180, 185),
                      posters=3, seed=19)
    if depth_step_mm <= 0:
        raise InputError(f"depth_step_mm: expected a positive step in mm, got {depth_step_mm}")
    sensors = {"kinect": SensorSpec("rgbd", baseline=0.075, depth_step=depth_step_mm / 1000.0)}
    return scene, env, sensors


def _smooth_signal(rng, n, fps, amplitude, f_range=(0.08, 0.35), terms=2):
    """Sum of sinusoids with random frequencies (Hz) and phases, peak ≈ ``amplitude``."""
    t = np.arange(n) / fps
    out = np.zeros(n)
    for _ in range(terms):
        out += np.sin(2 * np.pi * rng.uniform(*f_range) * t + rng.uniform(0, 2 * np.pi))
    return amplitude * out / terms


BOOTH_XY = (2.0, 2.8)


def _booth_person(rng, env, height, n, fps):
    shape = _shape(rng, env, height, None)
    T = np.ones(n, bool)
    xy = np.tile(BOOTH_XY, (n, 1))
    tr = Track(xy, np.full(n, -np.pi / 2), np.zeros(n), T, np.zeros(n), np.zeros(n), np.zeros(n))
    ja = JointAngles.neutral(np.array([BOOTH_XY]), np.array([-np.pi / 2]))
    parts = body_parts([shape], ja)
    return shape, tr, parts


def _quat(R: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z), w ≥ 0, of a rotation matrix."""
    w = np.sqrt(max(0.0, 1 + R[0, 0] + R[1, 1] + R[2, 2])) / 2
    x = np.sqrt(max(0.0, 1 + R[0, 0] - R[1, 1] - R[2, 2])) / 2
    y = np.sqrt(max(0.0, 1 - R[0, 0] + R[1, 1] - R[2, 2])) / 2
    z = np.sqrt(max(0.0, 1 - R[0, 0] - R[1, 1] + R[2, 2])) / 2
    x = np.copysign(x, R[2, 1] - R[1, 2])
    y = np.copysign(y, R[0, 2] - R[2, 0])
    z = np.copysign(z, R[1, 0] - R[0, 1])
    q = np.array([w, x, y, z])
    return q / np.linalg.norm(q)


@_register("face-pose", "paper 003: RGB-D close-up of a face with small or large 6-DoF head motion")
def face_pose(seed: int, common: Common, *, size=None, frames=None, motion: str = "small", distance: float = 0.8,
              depth_step_mm: float = 5.0, height: float = 1.72) -> Scenario:
    """A person stands facing a Kinect-like camera ``distance`` m in front of the head and moves the
    head: ``motion="small"`` (about ±6° yaw, ±4° pitch, ±3° roll, ±1 cm) or ``"large"`` (±35°,
    ±20°, ±12°, ±5 cm), smooth random sinusoids. Depth in ``depth_step_mm`` steps (seed 003's
    simulation used 5 mm). pose.csv: the head centre (m), its head → world quaternion, and the head's
    angles relative to the torso (rz, ry, rx in degrees; ZYX). 320×240 by default."""
    if motion not in ("small", "large"):
        raise InputError(f"motion: expected small or large, got {motion!r}")
    if not 0.3 <= distance <= 3.0:
        raise InputError(f"distance: expected 0.3–3 m, got {distance}")
    rng = np.random.default_rng(seed)
    n = frames or 100
    fps = common.fps
    env0 = Environment()
    shape, tr, parts0 = _booth_person(rng, env0, height, n, fps)
    head_c = parts0.centre[HEAD]
    cam_pos = head_c + np.array([0.0, -distance, 0.0])
    scene, env, sensors = _booth(size, depth_step_mm, cam_pos, head_c)
    amp = {"small": (6.0, 4.0, 3.0, 0.01), "large": (35.0, 20.0, 12.0, 0.05)}[motion]
    head = np.column_stack([_smooth_signal(rng, n, fps, np.radians(a)) for a in amp[:3]])
    offset = np.column_stack([_smooth_signal(rng, n, fps, amp[3]) for _ in range(3)])
    person = Person(1, shape, tr, pose={"head": head, "torso_offset": offset})

    def rows(k, t, people, parts):
        out = []
        for i, p in enumerate(people):
            c, R = head_pose(parts, i)
            q = _quat(R)
            rz, ry, rx = np.degrees(p.pose["head"][k])
            out.append({"frame": k, "time": round(t, 6), "id": p.id, "tx": round(c[0], 6), "ty": round(c[1], 6),
                        "tz": round(c[2], 6), "qw": round(q[0], 8), "qx": round(q[1], 8), "qy": round(q[2], 8),
                        "qz": round(q[3], 8), "rz_deg": round(rz, 5), "ry_deg": round(ry, 5), "rx_deg": round(rx, 5)})
        return out

    light = Light(ambient=0.55, direct=0.6, direction=light_direction(-60.0, 35.0))
    return Scenario("face-pose", scene, fps, n, [person], env, _lighting(common, rng, light), _options(common),
                    _rigs(scene, common, sensors), seed, pose_rows=rows,
                    description=f"paper 003: face pose, {motion} motion")


@_register("upper-body", "paper 003: RGB-D view of an upper body with 14-DoF motion "
                          "(torso 6, shoulders 2+2, elbows 2+2)")
def upper_body(seed: int, common: Common, *, size=None, frames=None, distance: float = 1.9,
               depth_step_mm: float = 5.0, height: float = 1.72) -> Scenario:
    """A person faces a Kinect-like camera ``distance`` m away and moves torso and arms: torso
    translation (±3 cm) and ``Rz·Ry·Rx`` rotation (±9°, ±5°, ±5°), each shoulder ``Rz·Ry`` and each
    elbow ``Rz·Ry`` (see :mod:`worldtrack.synth.bodies` for the limb frames). pose.csv: the 14
    parameters (m, degrees) and the world unit axes of both upper arms and forearms (for seed 003's
    limb-axis error). 320×240 by default."""
    if not 0.8 <= distance <= 4.0:
        raise InputError(f"distance: expected 0.8–4 m, got {distance}")
    rng = np.random.default_rng(seed)
    n = frames or 100
    fps = common.fps
    env0 = Environment()
    shape, tr, parts0 = _booth_person(rng, env0, height, n, fps)
    chest = parts0.centre[TORSO] + np.array([0.0, 0.0, 0.1])
    cam_pos = chest + np.array([0.0, -distance, 0.15])
    scene, env, sensors = _booth(size, depth_step_mm, cam_pos, chest)
    sig = lambda a, f=(0.08, 0.3): _smooth_signal(rng, n, fps, a, f)
    torso = np.column_stack([sig(np.radians(9)), sig(np.radians(5)), sig(np.radians(5))])
    offset = np.column_stack([sig(0.03), sig(0.03), sig(0.01)])
    sh_rz = np.column_stack([-0.6 + sig(0.6), 0.6 + sig(0.6)])           # left: − forward; right: + forward
    sh_ry = np.column_stack([0.85 + sig(0.55), 0.85 + sig(0.55)])         # lowered from horizontal
    el_rz = np.column_stack([-(0.8 + sig(0.5)), 0.8 + sig(0.5)])          # forearm bends forward
    el_ry = np.column_stack([sig(0.25), sig(0.25)])
    shoulder = np.stack([limb_rotation(sh_rz[:, k], sh_ry[:, k]) for k in (0, 1)], axis=1)
    elbow = np.stack([limb_rotation(el_rz[:, k], el_ry[:, k]) for k in (0, 1)], axis=1)
    person = Person(1, shape, tr, pose={"torso": torso, "torso_offset": offset, "shoulder": shoulder, "elbow": elbow})

    def rows(k, t, people, parts):
        out = []
        for i, p in enumerate(people):
            base = i * PARTS_PER_PERSON
            lumbar = parts.centre[base + TORSO] - parts.axes[base + TORSO][2] * (0.11 * p.shape.height)
            row = {"frame": k, "time": round(t, 6), "id": p.id,
                   "torso_tx": round(lumbar[0], 6), "torso_ty": round(lumbar[1], 6), "torso_tz": round(lumbar[2], 6)}
            for name, val in zip(("torso_rz_deg", "torso_ry_deg", "torso_rx_deg"), np.degrees(torso[k])):
                row[name] = round(val, 5)
            for s, side in enumerate("lr"):
                row[f"{side}_shoulder_rz_deg"] = round(np.degrees(sh_rz[k, s]), 5)
                row[f"{side}_shoulder_ry_deg"] = round(np.degrees(sh_ry[k, s]), 5)
                row[f"{side}_elbow_rz_deg"] = round(np.degrees(el_rz[k, s]), 5)
                row[f"{side}_elbow_ry_deg"] = round(np.degrees(el_ry[k, s]), 5)
            for name, part in (("l_upper_arm", L_UPPER_ARM), ("l_forearm", L_FOREARM),
                               ("r_upper_arm", R_UPPER_ARM), ("r_forearm", R_FOREARM)):
                a, b = parts.centre[base + part], parts.end[base + part]
                ax = (b - a) / np.linalg.norm(b - a)
                for c, v in zip("xyz", ax):
                    row[f"{name}_axis_{c}"] = round(v, 8)
            out.append(row)
        return out

    light = Light(ambient=0.55, direct=0.6, direction=light_direction(-60.0, 40.0))
    return Scenario("upper-body", scene, fps, n, [person], env, _lighting(common, rng, light), _options(common),
                    _rigs(scene, common, sensors), seed, pose_rows=rows,
                    description="paper 003: upper-body pose, 14 DoF")
