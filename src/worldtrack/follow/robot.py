"""The following robot: its limits, defined once, and the simulated unicycle that obeys them.

:class:`RobotLimits` is what the followers (:class:`~worldtrack.follow.pid.PIDFollower`,
:class:`~worldtrack.follow.planner.LocalPlanner`) command within and what the simulated
:class:`Robot` of the closed loop (:mod:`~worldtrack.follow.loop`) drives by — one definition, so a
follower cannot plan with a robot other than the one it drives. The camera sits ``camera_forward``
m ahead of the robot's centre, ``camera_height`` m up (from the scenario), looking along the
heading, tilted ``CAMERA_TILT_DEG`` down.

>>> r = Robot(0.0, 0.0, 0.0)
>>> free = lambda xy: [5.0]                       # 5 m from every wall
>>> for _ in range(20):
...     _ = r.drive(3.0, 0.0, 0.1, free)          # asks for 3 m/s: 1.5 m/s² up to 1.6 m/s
>>> round(r.v, 2), r.limits.max_speed
(1.6, 1.6)
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from worldtrack.geometry.camera import look_at_rotation

CAMERA_TILT_DEG = 4.0


@dataclass(frozen=True)
class RobotLimits:
    """max_speed, max_reverse : m/s forward and backward; max_turn_rate : rad/s; accel : m/s²;
    turn_accel : rad/s²; radius : m, the body (the bumper); camera_forward : m, the camera ahead of
    the robot's centre."""

    max_speed: float = 1.6
    max_reverse: float = 0.5
    max_turn_rate: float = 1.5
    accel: float = 1.5
    turn_accel: float = 4.0
    radius: float = 0.3
    camera_forward: float = 0.1


@dataclass
class Robot:
    """A unicycle robot: pose (m, rad), speeds (m/s, rad/s) and its :class:`RobotLimits`."""

    x: float
    y: float
    yaw: float
    v: float = 0.0
    w: float = 0.0
    limits: RobotLimits = field(default_factory=RobotLimits)

    def drive(self, v_cmd: float, w_cmd: float, dt: float, clearance_at) -> bool:
        """Move for ``dt`` s towards the commanded speeds; False when the bumper stopped it.

        ``clearance_at(xy (1, 2)) -> (1,)`` is the distance (m) to walls and obstacles.
        """
        lim = self.limits
        v_cmd = float(np.clip(v_cmd, -lim.max_speed, lim.max_speed))
        w_cmd = float(np.clip(w_cmd, -lim.max_turn_rate, lim.max_turn_rate))
        self.v += float(np.clip(v_cmd - self.v, -lim.accel * dt, lim.accel * dt))
        self.w += float(np.clip(w_cmd - self.w, -lim.turn_accel * dt, lim.turn_accel * dt))
        self.yaw = float((self.yaw + self.w * dt + np.pi) % (2 * np.pi) - np.pi)
        new = np.array([self.x, self.y]) + self.v * dt * np.array([np.cos(self.yaw), np.sin(self.yaw)])
        if clearance_at(new[None])[0] < lim.radius:
            self.v = 0.0
            return False
        self.x, self.y = float(new[0]), float(new[1])
        return True

    @classmethod
    def from_camera(cls, camera, limits: RobotLimits | None = None) -> "Robot":
        """The robot that carries ``camera`` (its centre ``camera_forward`` behind it, same heading)."""
        limits = limits or RobotLimits()
        fwd = camera.floor_direction
        x, y = camera.centre[:2] - limits.camera_forward * fwd
        return cls(float(x), float(y), float(np.arctan2(fwd[1], fwd[0])), limits=limits)


def camera_pose(robot: Robot, camera_height: float) -> tuple[np.ndarray, np.ndarray]:
    """(R, t) world → camera of the robot's camera."""
    fwd = np.array([np.cos(robot.yaw), np.sin(robot.yaw), 0.0])
    pos = np.array([robot.x, robot.y, camera_height]) + robot.limits.camera_forward * fwd
    R = look_at_rotation(pos, pos + fwd + np.array([0.0, 0.0, -np.tan(np.radians(CAMERA_TILT_DEG))]))
    return R, -R @ pos
