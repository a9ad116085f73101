"""The closed loop in the synthetic world: the robot's camera moves by the commands it gets.

Each frame of a ``follow-target`` scenario is rendered from where the simulated robot stands *now*:
the robot's pose becomes the camera pose of that frame before the frame is drawn (the scenario
renders lazily, frame by frame), the tracker sees the frame, the follower — by default the paper's
PID (:mod:`~worldtrack.follow.pid`) with worldtrack's depth safety layer, or the local planner
(:mod:`~worldtrack.follow.planner`) — turns what it saw (and the frame's depth) into (v, ω), and
the robot drives by them for one frame time — a unicycle with limited speed, turn rate
and acceleration that stops rather than drive into a wall or an obstacle (a bumper, counted).

The robot and its camera are :mod:`~worldtrack.follow.robot`'s: the camera ``camera_height`` m up
(as in the scenario), 0.1 m ahead of the robot's centre, looking along its heading, tilted 4° down.

>>> from worldtrack.synth import make_scenario
>>> sc = make_scenario("follow-target", size=(160, 120), frames=20, seed=3, others=0)
>>> result = run_closed_loop(sc)
>>> bool(abs(result.distance[-1] - 1.8) < 0.4), result.collisions
(True, 0)
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from worldtrack.follow.pid import PIDFollower
from worldtrack.follow.planner import LocalPlanner
from worldtrack.follow.robot import Robot, RobotLimits, camera_pose
from worldtrack.follow.observation import frame_from_synth
from worldtrack.follow.scan import simulate_scan
from worldtrack.follow.tracker import FollowStep, FollowTracker

@dataclass
class LoopResult:
    """What happened in a closed-loop run (T frames).

    times (T,) s; robot_xy (T, 2) m; camera_xy (T, 2) m; target_xy (T, 2) the true target, m;
    distance (T,) camera to true target, m; commands (T, 2) (v m/s, ω rad/s);
    nearest_person (T,) distance from the robot's centre to the nearest person, m;
    clearance (T,) robot centre to the nearest wall or obstacle, m; found (T,) bool;
    bumps : frames the bumper stopped the robot; contacts : frames with a person within
    ``robot.limits.radius + 0.2`` m of the robot's centre; collisions : of those, frames where the robot
    drove into somebody — its speed towards them above 0.05 m/s and at least theirs towards it (the
    robot's doing: "unseen" or "seen, not stopped"); walked_into : contact frames where a person
    closed in faster than the robot (standing or not): the scripted people do not see the robot, and
    that is their doing, counted apart; collision_causes : one :class:`Collision` per person in
    contact per frame (cause "walked into the robot", "unseen", "seen, not stopped" or "side by side":
    nobody closing in); steps : the FollowSteps (if kept)
    """

    times: np.ndarray
    robot_xy: np.ndarray
    camera_xy: np.ndarray
    target_xy: np.ndarray
    distance: np.ndarray
    commands: np.ndarray
    nearest_person: np.ndarray
    clearance: np.ndarray
    found: np.ndarray
    bumps: int
    contacts: int
    collisions: int
    collision_causes: list = field(default_factory=list)
    steps: list = field(default_factory=list)
    walked_into: int = 0


@dataclass
class Collision:
    """One person in contact with the robot in one frame, and why (``cause``):

    * ``"walked into the robot"`` — the person closed in faster than the robot drove at them
      (including a robot standing still);
    * ``"side by side"`` — neither closes in faster than 0.05 m/s;
    * ``"unseen"`` — the person was not visible to the robot's camera in the last ``SEEN_S`` s
      (beside or behind it, or hidden): a forward camera cannot stop for them;
    * ``"seen, not stopped"`` — the robot saw them and still drove into them: the follower's fault.

    frame; person id; distance (m, robot centre to person); robot_speed, person_speed (m/s towards
    each other); visible : the person's largest visible share in the last ``SEEN_S`` s; tracked :
    the follower had a candidate or track within 0.5 m of them; blocked : the path check held the
    robot back.
    """

    frame: int
    person: int
    distance: float
    robot_speed: float
    person_speed: float
    visible: float
    tracked: bool
    blocked: bool
    cause: str

    @property
    def robot_fault(self) -> bool:
        """The robot drove into them (cause "unseen" or "seen, not stopped")."""
        return self.cause in ("unseen", "seen, not stopped")


SEEN_S = 1.0


def _collision(k: int, pid: int, rel: np.ndarray, robot, person_velocity: np.ndarray, visible: float, step,
               blocked: bool) -> Collision:
    """Classify one collision (see :class:`Collision`); ``rel`` person − robot (m)."""
    dist = float(np.hypot(*rel))
    towards = rel / max(dist, 1e-9)
    robot_speed = robot.v * float(towards @ np.array([np.cos(robot.yaw), np.sin(robot.yaw)]))
    person_speed = -float(person_velocity @ towards)
    known = [a for a in (step.candidates.xy, step.others_xy, np.asarray(step.xy)[None]) if len(a)]
    person_xy = np.array([robot.x, robot.y]) + rel
    tracked = bool(np.hypot(*(np.vstack(known) - person_xy).T).min() < 0.5) if known else False
    if person_speed > robot_speed and person_speed > 0.05:
        cause = "walked into the robot"
    elif robot_speed <= 0.05:
        cause = "side by side"
    elif visible < 0.2:
        cause = "unseen"
    else:
        cause = "seen, not stopped"
    return Collision(k, pid, dist, robot_speed, person_speed, visible, tracked, blocked, cause)


def run_closed_loop(scenario, tracker: FollowTracker | None = None, follower: LocalPlanner | PIDFollower | None = None,
                    camera_id: str = "robot", camera_height: float | None = None, keep_steps: bool = False,
                    on_frame=None, side_scan: bool = False, limits: RobotLimits | None = None) -> LoopResult:
    """Render ``scenario`` frame by frame from the robot that follows its person 1 (see the module docstring).

    ``on_frame(bundle, step, (v, ω))`` is called after every frame (e.g. to write a video).
    ``side_scan``: the robot also carries a 270° planar range scanner (:func:`~worldtrack.follow.scan.simulate_scan`,
    4 m, 1°, σ 2 cm), whose points go to the follower (``command(..., scan=)``; the PID only).
    ``limits``: the robot's (:class:`~worldtrack.follow.robot.RobotLimits`; the default robot).
    """
    tracker = tracker or FollowTracker(scene=scenario.scene)
    follower = follower or PIDFollower(distance=float(scenario.params.get("distance", 1.8)), depth_stop=True)
    poses = scenario.rigs[camera_id].poses
    if poses is None:
        raise ValueError(f"camera {camera_id!r} of scenario {scenario.name!r} does not move")
    first = scenario.camera_at(camera_id, 0)
    height = float(first.centre[2]) if camera_height is None else camera_height
    robot = Robot.from_camera(first, limits)
    df = scenario.scene.distance_field(0.05)
    clearance_at = lambda xy: df.sample(xy, outside=-1.0)  # noqa: E731
    n = scenario.n_frames
    rec = {k: np.zeros((n, 2)) for k in ("robot", "camera", "target", "cmd")}
    near, clear, found = np.full(n, np.inf), np.zeros(n), np.zeros(n, bool)
    bumps = contacts = collisions = walked_into = 0
    causes: list[Collision] = []
    previous: dict = {}
    visible: dict = {}
    steps: list[FollowStep] = []
    frames = scenario.frames()
    radius = {p.id: 0.5 * float(p.shape.shoulder_width) for p in scenario.people}
    scan_rng = np.random.default_rng([int(scenario.seed), 1])
    extra = {}
    for k in range(n):
        poses[k] = camera_pose(robot, height)     # frame k is drawn from where the robot is now
        bundle = next(frames)
        cam = bundle.views[camera_id].camera
        people = {r["id"]: np.array([r["x"], r["y"]]) for r in bundle.gt}
        for r in bundle.gt:
            visible.setdefault(r["id"], []).append(float(r.get(f"vis_{camera_id}", 1.0)))
        start = people.get(1) if k == 0 else None
        frame = frame_from_synth(bundle, camera_id)
        step = tracker.follow(frame, cam, start_xy=start)
        if side_scan:
            ids = list(people)
            extra["scan"] = simulate_scan((robot.x, robot.y), robot.yaw, np.array([people[i] for i in ids]).reshape(-1, 2),
                                          np.array([radius.get(i, 0.2) for i in ids]), clearance_at, rng=scan_rng)
        v, w = follower.command(step, cam, bundle.time, frame=frame, **extra)
        rec["robot"][k] = (robot.x, robot.y)
        rec["camera"][k] = cam.centre[:2]
        rec["target"][k] = people.get(1, np.full(2, np.nan))
        rec["cmd"][k] = (v, w)
        found[k] = step.found
        heading = np.array([np.cos(robot.yaw), np.sin(robot.yaw)])
        if people:
            rel = np.array(list(people.values())) - rec["robot"][k]
            dist = np.hypot(rel[:, 0], rel[:, 1])
            near[k] = dist.min()
            touching = dist < robot.limits.radius + 0.2
            contacts += int(touching.any())
            frame_causes = []
            for j in np.flatnonzero(touching):
                pid = list(people)[j]
                vel = (people[pid] - previous.get(pid, people[pid])) * scenario.fps
                seen = max(visible[pid][-int(SEEN_S * scenario.fps) - 1:])
                frame_causes.append(_collision(k, pid, rel[j], robot, vel, seen, step,
                                               bool(getattr(follower, "blocked", False))))
            causes += frame_causes
            collisions += int(any(c.robot_fault for c in frame_causes))
            walked_into += int(any(c.cause == "walked into the robot" for c in frame_causes))
        previous = people
        clear[k] = clearance_at(rec["robot"][k][None])[0]
        if keep_steps:
            steps.append(step)
        if on_frame is not None:
            on_frame(bundle, step, (v, w))
        dt = 1.0 / scenario.fps
        bumps += int(not robot.drive(v, w, dt, clearance_at))
    distance = np.hypot(*(rec["target"] - rec["camera"]).T)
    return LoopResult(np.arange(n) / scenario.fps, rec["robot"], rec["camera"], rec["target"], distance, rec["cmd"],
                      near, clear, found, bumps, contacts, collisions, causes, steps, walked_into)
