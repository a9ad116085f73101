"""The follower as a local planner (worldtrack; the paper's PID is :mod:`~worldtrack.follow.pid`).

A PID steers at the target's bearing: into a kiosk the target walked round, into a person who
stands in the way, and it waits behind a crosser who is already leaving. This follower knows the
room (:class:`~worldtrack.follow.navigation.NavigationGrid`), the people the tracker follows with
their velocities, and the near points of its own depth image (:mod:`~worldtrack.follow.safety`),
and picks (v, ω) by a dynamic-window search:

1. the robot's speed and turn rate from its camera's last two poses (odometry);
2. candidate commands over the robot's whole range (``speeds`` × ``turns``), each rolled out for
   ``horizon`` s with the robot's acceleration limits (a unicycle, as the robot drives);
3. the target predicted along its Kalman velocity, the others along theirs;
4. each rollout scored by
   * *following*: the camera's distance to the predicted target minus the set distance, squared,
     over the rollout and at its end, where the distance is the way round the obstacles
     (geodesic) when the end does not see the target — so after a hold the robot drives faster
     than the target until the error is gone, and when the target is lost behind an obstacle it
     drives round to where it went instead of turning in place (halfway between where it was last
     seen and where it is predicted: it may have stopped or walked on);
   * *sight*: another person, at the rollout's end, in the line from the camera to the target
     (a cut-in that stops there hides it: the robot moves to see past them);
   * *view*: the target's bearing beyond ``view_half_angle`` from the camera's axis;
   * *clearance*: to walls and obstacles (the distance field), to every person at the rollout's
     time (their predicted positions: a crosser walking out of the path no longer blocks it),
     and to depth points no tracked person explains (somebody the detector missed);
   rollouts that come closer than ``obstacle_clearance``, ``person_clearance`` or
   ``point_clearance`` are not admissible (unless nothing is: then the one that keeps the most);
5. a safety layer on the chosen command: the speed that stops ``safety_radius`` short of *any*
   near depth point along its path, braking at ``brake`` (no detector needed).

>>> import numpy as np
>>> from types import SimpleNamespace
>>> from worldtrack.synth import make_scenario
>>> sc = make_scenario("follow-target", size=(160, 120), frames=2, seed=0, others=0)
>>> cam = sc.camera_at("robot", 0)
>>> fwd = cam.floor_direction
>>> target = cam.centre[:2] + 3.0 * fwd                        # 3 m straight ahead, standing
>>> step = SimpleNamespace(t=0.0, found=True, xy=target, velocity=np.zeros(2), measured=target,
...                        others_xy=np.zeros((0, 2)), others_velocity=np.zeros((0, 2)),
...                        candidates=SimpleNamespace(xy=target[None]))
>>> v, w = LocalPlanner(sc.scene).command(step, cam, 0.0)
>>> bool(v > 0.5), bool(abs(w) < 0.3)                          # too far: straight on
(True, True)
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from worldtrack.follow.robot import RobotLimits
from worldtrack.follow.navigation import NavigationGrid
from worldtrack.follow.safety import free_path, near_points, unexplained
from worldtrack.geometry.camera import Camera

#: Fastest a walker is assumed to go (m/s): larger Kalman velocities are noise.
MAX_WALK = 2.0
#: A depth point this close (m) to a wall or obstacle of the map is its surface, not an unknown obstacle.
MAP_SURFACE = 0.15
#: Nearer than this (m) the camera's view misses the floor-level part of a body: remembered points stay.
NEAR_BLIND = 0.6


class Rollouts:
    """Candidate commands (C, 2) and their rollouts: centre positions (C, S + 1, 2) from the robot's
    position, headings (C, S + 1) rad, times (S + 1,) s from now."""

    def __init__(self, commands: np.ndarray, xy: np.ndarray, yaw: np.ndarray, times: np.ndarray):
        self.commands, self.xy, self.yaw, self.times = commands, xy, yaw, times


def roll_out(pose, velocity, commands: np.ndarray, horizon: float, step: float, accel: float,
             turn_accel: float) -> Rollouts:
    """Unicycle rollouts: from ``pose`` (x, y, yaw) at ``velocity`` (v m/s, ω rad/s) towards each
    command (C, 2), speed changes limited to ``accel`` m/s² and ``turn_accel`` rad/s², as the robot
    drives (speeds first, then the heading, then the position)."""
    c = len(commands)
    n = max(1, int(round(horizon / step)))
    xy = np.zeros((c, n + 1, 2))
    yaw = np.zeros((c, n + 1))
    xy[:, 0], yaw[:, 0] = pose[:2], pose[2]
    v = np.full(c, float(velocity[0]))
    w = np.full(c, float(velocity[1]))
    for s in range(1, n + 1):
        v = v + np.clip(commands[:, 0] - v, -accel * step, accel * step)
        w = w + np.clip(commands[:, 1] - w, -turn_accel * step, turn_accel * step)
        yaw[:, s] = yaw[:, s - 1] + w * step
        xy[:, s] = xy[:, s - 1] + (v * step)[:, None] * np.column_stack([np.cos(yaw[:, s]), np.sin(yaw[:, s])])
    return Rollouts(commands, xy, yaw, np.arange(n + 1) * step)


def _capped(velocity: np.ndarray) -> np.ndarray:
    v = np.asarray(velocity, float).reshape(-1, 2)
    speed = np.hypot(v[:, 0], v[:, 1])
    return v * np.minimum(1.0, MAX_WALK / np.maximum(speed, 1e-9))[:, None]


def _min_distance(xy: np.ndarray, points: np.ndarray, slack=0.0) -> np.ndarray:
    """(C,) nearest approach of rollouts (C, S, 2) to static points (M, 2), less each point's ``slack``
    (M,) m; inf without points."""
    if len(points) == 0:
        return np.full(len(xy), np.inf)
    d = np.hypot(xy[:, :, None, 0] - points[None, None, :, 0], xy[:, :, None, 1] - points[None, None, :, 1])
    return (d - np.broadcast_to(slack, len(points))[None, None]).min(axis=(1, 2))


def _blocks_view(cam: np.ndarray, target: np.ndarray, people: np.ndarray, body: float = 0.3) -> np.ndarray:
    """(C,) 1.0 where one of ``people`` (K, 2) stands within ``body`` m of the sight line from a camera
    position (C, 2) to ``target`` (2,), between the two, else 0.0."""
    line = target[None] - cam                                                  # (C, 2)
    length2 = np.maximum((line ** 2).sum(axis=1), 1e-9)
    rel = people[None] - cam[:, None]                                          # (C, K, 2)
    along = (rel * line[:, None]).sum(axis=2) / length2[:, None]
    off = rel - along[..., None] * line[:, None]
    between = (along > 0.0) & (along < 1.0 - body / np.sqrt(length2)[:, None])
    return ((np.hypot(off[..., 0], off[..., 1]) < body) & between).any(axis=1).astype(float)


@dataclass
class LocalPlanner:
    """Dynamic-window follower; see the module docstring. Lengths in m, times in s, angles in rad.

    scene : the Scene (walls and obstacles); distance : set following distance, camera to target;
    robot : its limits and the camera ahead of its centre (:class:`~worldtrack.follow.robot.RobotLimits`,
    the simulated robot's);
    horizon, step : rollout length and step; speeds, turns : number of commands sampled;
    obstacle_clearance, person_clearance, point_clearance : closest admissible approach of the
    robot's centre to a wall, a person's centre, an unexplained depth point;
    safety_radius, brake : the safety layer; view_half_angle : the target's bearing allowed
    without cost; view_half_fov : half the camera's horizontal field of view, a little less (a
    remembered point inside it that is not seen again is gone); memory, spread : unexplained
    points are remembered this long (s), their clearance growing by this (m/s: a person's walk);
    lost_timeout, search_distance : the target unseen this long (s), the robot drives to this
    distance (m) of the point halfway between where it was last seen and where it is predicted to
    be (it may have stopped, or walked on), to look for it there;
    weights : (view, hidden, obstacles, people, points, smooth) against the
    following error in m².
    """

    scene: object
    distance: float = 1.8
    robot: RobotLimits = RobotLimits()
    horizon: float = 1.5
    step: float = 0.1
    speeds: int = 12
    turns: int = 21
    obstacle_clearance: float = 0.4
    person_clearance: float = 0.65
    point_clearance: float = 0.4
    safety_radius: float = 0.35
    brake: float = 1.2
    view_half_angle: float = 0.25
    view_half_fov: float = 0.5
    memory: float = 1.0
    lost_timeout: float = 1.0
    search_distance: float = 0.8
    spread: float = 0.8
    weights: tuple = (20.0, 2.0, 4.0, 3.0, 3.0, 0.05)
    _state: dict = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        self.nav = NavigationGrid(self.scene, radius=self.robot.radius)
        v = np.linspace(-self.robot.max_reverse, self.robot.max_speed, self.speeds)
        w = np.linspace(-self.robot.max_turn_rate, self.robot.max_turn_rate, self.turns)
        self._commands = np.stack(np.meshgrid(v, w, indexing="ij"), axis=-1).reshape(-1, 2)

    def reset(self) -> None:
        self._state.clear()

    @property
    def blocked(self) -> bool:
        """Whether the last command was slowed by somebody or something in the robot's way."""
        return bool(self._state.get("blocked", False))

    def command(self, step, camera: Camera, t: float, frame=None) -> tuple[float, float]:
        """(v m/s, ω rad/s) for this frame's :class:`~worldtrack.follow.tracker.FollowStep`, the
        camera's pose and (optionally) the frame, whose depth feeds the safety layer."""
        fwd = camera.floor_direction
        pose = np.array([*(camera.centre[:2] - self.robot.camera_forward * fwd), np.arctan2(fwd[1], fwd[0])])
        velocity = self._odometry(pose, t)
        roll = roll_out(pose, velocity, self._commands, self.horizon, self.step, self.robot.accel,
                        self.robot.turn_accel)
        points = near_points(getattr(frame, "depth", None), camera)
        cost, admissible, margin, free_cost = self._score(roll, step, points, camera)
        if admissible.any():
            k = int(np.flatnonzero(admissible)[np.argmin(cost[admissible])])
        else:                                      # nothing is safe: keep as far from everything as we can
            k = int(np.argmax(margin))
        v, w = (float(x) for x in self._commands[k])
        free = int(np.argmin(free_cost))
        limit = self._safety_limit(roll.xy[k], points, v)
        self._state["blocked"] = bool(limit < v or (self._commands[free, 0] - v > 0.2 and free != k)
                                      or not admissible.any())
        v = min(v, limit)
        self._state["command"] = (v, w)
        return v, w

    # ------------------------------------------------------------------ internals
    def _odometry(self, pose: np.ndarray, t: float) -> np.ndarray:
        """(v, ω) from the previous pose (the robot's last speeds); the last command at the start."""
        s = self._state
        prev = s.get("pose")
        s["pose"] = (pose, t)
        if prev is None or t <= prev[1]:
            return np.asarray(s.get("command", (0.0, 0.0)), float)
        (p0, t0), dt = prev, t - prev[1]
        heading = np.array([np.cos(pose[2]), np.sin(pose[2])])
        turn = (pose[2] - p0[2] + np.pi) % (2 * np.pi) - np.pi
        return np.array([float((pose[:2] - p0[:2]) @ heading) / dt, turn / dt])

    def _score(self, roll: Rollouts, step, points: np.ndarray, camera: Camera):
        """Per command (C,): total cost, admissible, safety margin (m, larger is safer) and the cost
        without people and unexplained points (to tell when they held the robot back)."""
        wv, wh, wo, wp, wq, ws = self.weights
        xy, ts = roll.xy, roll.times
        cam = xy + self.robot.camera_forward * np.stack([np.cos(roll.yaw), np.sin(roll.yaw)], axis=-1)
        if step.found:
            self._state["seen"], self._state["last_xy"] = float(step.t), np.asarray(step.measured, float)
        lost = float(step.t) - self._state.get("seen", float(step.t)) > self.lost_timeout
        aim, velocity = np.asarray(step.xy, float), _capped(step.velocity)[0]
        if lost and np.all(np.isfinite(self._state.get("last_xy", np.nan))):
            # Lost: the target walked on (the prediction) or stopped where last seen; look between the two.
            aim, velocity = 0.5 * (aim + self._state["last_xy"]), 0.5 * velocity
        target = aim + ts[:, None] * velocity
        # Lost: go and look where the prediction says it went (round obstacles), not from afar.
        follow, hidden, view = self._follow_cost(cam, roll.yaw, target, self.search_distance if lost else self.distance)
        people, pvel = self._people(step)
        others = people[1:] if step.found else people
        if len(others):
            # A person standing between the camera and the target hides it: see past them, as the
            # tracker needs (a cut-in that stops in the line of sight).
            hidden = np.maximum(hidden, _blocks_view(cam[:, -1], target[-1], others + ts[-1] * pvel[-len(others):]))
        # Walls and obstacles.
        clear = self.nav.clearance(xy.reshape(-1, 2)).reshape(xy.shape[:2]).min(axis=1)
        now = self.nav.clearance(xy[:1, 0])[0]
        ok_static = (clear >= self.obstacle_clearance) | (clear >= now - 1e-3)
        # People, where they will be; the target too (not to be run into).
        if len(people):
            future = people[:, None] + ts[None, :, None] * pvel[:, None]          # (K, S, 2)
            d = np.hypot(*(xy[:, None] - future[None]).transpose(3, 0, 1, 2)).min(axis=2)   # (C, K)
            d_now = np.hypot(*(xy[0, 0] - people).T)
            need = np.where(np.arange(len(people)) == 0, self.person_clearance + 0.2, self.person_clearance) \
                if step.found else np.full(len(people), self.person_clearance)
            ok_people = ((d >= need) | (d >= d_now - 1e-3)).all(axis=1)
            near_people = (np.maximum(0.0, need + 0.5 - d) ** 2).sum(axis=1)
            person_margin = (d - need).min(axis=1)
        else:
            ok_people, near_people, person_margin = np.ones(len(xy), bool), np.zeros(len(xy)), np.full(len(xy), np.inf)
        # Depth points nobody tracked explains and the map does not (a person the detector missed),
        # remembered for ``memory`` s while out of view, with a margin growing by ``spread`` m/s.
        q, age = self._unknown(step, points, roll, camera)
        dq = _min_distance(xy, q, self.spread * age)
        dq_now = _min_distance(xy[:1, :1], q, self.spread * age)[0]
        ok_points = (dq >= self.point_clearance) | (dq >= dq_now - 1e-3)
        smooth = (roll.commands[:, 1] - self._state.get("command", (0.0, 0.0))[1]) ** 2
        base = follow + wv * view + wh * hidden + wo * np.maximum(0.0, 0.8 - clear) ** 2 + ws * smooth
        cost = base + wp * near_people + wq * np.maximum(0.0, self.point_clearance + 0.3 - dq) ** 2
        admissible = ok_static & ok_people & ok_points
        margin = np.minimum.reduce([clear - self.obstacle_clearance, person_margin, dq - self.point_clearance])
        return cost, admissible, margin, np.where(ok_static, base, np.inf)

    def _follow_cost(self, cam: np.ndarray, yaw: np.ndarray, target: np.ndarray, distance: float):
        """(C,) following error² (rollout mean + end), end not seeing the target (0/1), view cost."""
        rel = target[None] - cam                                                  # (C, S, 2)
        dist = np.hypot(rel[..., 0], rel[..., 1])
        end = dist[:, -1].copy()
        sees = self.nav.line_of_sight(cam[:, -1], target[-1])
        if not sees.all():
            # The way round the obstacles, from the end of each rollout that does not see the target.
            geo = self.nav.geodesic(target[-1]).sample(cam[~sees, -1], outside=1e3)
            end[~sees] = np.maximum(end[~sees], geo)
        e = dist - distance
        follow = (e ** 2).mean(axis=1) + (end - distance) ** 2
        bearing = (np.arctan2(rel[..., 1], rel[..., 0]) - yaw + np.pi) % (2 * np.pi) - np.pi
        # Facing the target matters where it can be seen: behind an obstacle, the way round comes first.
        view = (np.maximum(0.0, np.abs(bearing) - self.view_half_angle) ** 2).mean(axis=1) * sees
        return follow, (~sees).astype(float), view

    def _unknown(self, step, points: np.ndarray, roll: Rollouts, camera: Camera) -> tuple[np.ndarray, np.ndarray]:
        """(M, 2) unexplained depth points off the map's obstacles, this frame's and those remembered from
        the last ``memory`` s that are now out of view, and (M,) their ages (s)."""
        q = unexplained(points, np.asarray(step.candidates.xy, float).reshape(-1, 2))
        q = q[self.nav.clearance(q) > MAP_SURFACE] if len(q) else q
        t = float(step.t) if hasattr(step, "t") else 0.0
        kept = [(t0, p) for t0, p in self._state.get("unknown", []) if 0 < t - t0 <= self.memory]
        self._state["unknown"] = kept + [(t, q)]
        old = [(p, np.full(len(p), t - t0)) for t0, p in kept if len(p)]
        if old:
            p, a = np.vstack([o[0] for o in old]), np.concatenate([o[1] for o in old])
            rel = p - camera.centre[:2]
            fwd = camera.floor_direction
            bearing = np.abs(np.arctan2(rel @ np.array([-fwd[1], fwd[0]]), rel @ fwd))
            gone = (bearing < self.view_half_fov) & (np.hypot(*rel.T) > NEAR_BLIND)  # in view now, not seen again
            q = np.vstack([q, p[~gone]])
            return q, np.concatenate([np.zeros(len(q) - (~gone).sum()), a[~gone]])
        return q, np.zeros(len(q))

    def _people(self, step) -> tuple[np.ndarray, np.ndarray]:
        """(K, 2) positions and velocities of the people to keep clear of; the target first when found."""
        xy = [np.asarray(step.others_xy, float).reshape(-1, 2)]
        vel = [_capped(getattr(step, "others_velocity", np.zeros((len(xy[0]), 2))))]
        if step.found:
            xy.insert(0, np.asarray(step.xy, float)[None])
            vel.insert(0, _capped(step.velocity))
        return np.vstack(xy), np.vstack(vel)

    def _safety_limit(self, path: np.ndarray, points: np.ndarray, v: float) -> float:
        """Largest forward speed (m/s) that stops ``safety_radius`` short of any near depth point along
        the chosen rollout, braking at ``brake`` after one step's delay."""
        if v <= 0 or len(points) == 0:
            return np.inf
        gap = free_path(path, points, self.safety_radius)
        if not np.isfinite(gap):
            return np.inf
        return float(max(0.0, np.sqrt(2 * self.brake * max(gap, 0.0)) - self.brake * self.step))
