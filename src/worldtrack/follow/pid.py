"""The follower (seed 001 §3.2): PID control on the distance and bearing to the target → (v, ω).

The robot's pose is its camera's: the camera centre on the floor and its viewing direction. With
``e_d = d − distance`` (m) and ``e_β = β`` (rad, left positive)::

    v = v_ff + Kp_d·e_d + Ki_d·∫e_d dt + Kd_d·de_d/dt
    ω = ω_ff + Kp_β·e_β + Ki_β·∫e_β dt + Kd_β·de_β/dt

with the real time step. ``v_ff`` (the target's speed along the line of sight) and ``ω_ff`` (its
angular rate about the robot), both from the Kalman filter's velocity, are worldtrack's
feed-forward terms (``feed_forward=False`` is the paper's plain PID): without them a PID lags a
walking target by ``v/Kp``. Derivatives are of the errors computed from the filtered state, so a
noisy detection does not kick the output. Limits (``robot``, :class:`~worldtrack.follow.robot.RobotLimits`):
``−max_reverse ≤ v ≤ max_speed`` (the robot backs off when the target walks at it), ``|ω| ≤ max_turn_rate``; the integrals are clamped (anti-windup)
and reset when the target is lost.

Safety: everybody the follower knows of (the target, every candidate, every other person's track,
including those coasting out of view) who stands in the robot's path — ahead, within ``corridor``
metres to either side — limits the forward speed to what lets it stop ``stop_distance`` metres
short of them braking at ``brake`` m/s² after one frame's delay, ``v ≤ √(2·brake·gap) − brake·dt``;
nobody within ``stop_distance`` ahead at all (path or not) lets it move forward. So the robot slows
as it nears anybody in its way instead of stopping late. The target hidden behind somebody nearer
(the tracker's ``hidden``: depth puts them in front of its prediction) is followed by its prediction
for up to ``hidden_coast`` seconds. Otherwise, not seen for ``lost_timeout`` seconds, the target is
lost: the robot goes to where it was last seen (``pursue`` seconds at most: it turns to face the
place first, then drives, under the same speed limits; with the room's map, ``nav``, along the
shortest way round its obstacles) — a target that turned a corner out of view is seen again from
there —, and then only turns (at most ``search_turn_rate``) towards where the
target should be, to look for it. With ``map_approach`` (default), a followed target whose straight way
is blocked by the map (a bench between them: the PID would turn to it and the depth stop hold the robot
in front of the bench) is approached the way the pursuit goes, round the obstacle, at up to the robot's
top speed, stopping ``distance`` m short of it.

>>> import numpy as np
>>> from types import SimpleNamespace
>>> from worldtrack.geometry.camera import Camera
>>> cam = Camera.look_at("robot", 160, 120, position=(0, 0, 1.1), target=(1, 0, 1.1), hfov_deg=66)
>>> step = SimpleNamespace(found=True, xy=np.array([3.0, 0.5]), velocity=np.zeros(2), t=0.0,
...                        candidates=SimpleNamespace(xy=np.array([[3.0, 0.5]])), others_xy=np.zeros((0, 2)))
>>> v, w = PIDFollower().command(step, cam, 0.0)
>>> bool(v > 0 and w > 0)                  # too far and to the left: forward, turning left
True
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from worldtrack.follow.movers import moving_speed_limit
from worldtrack.follow.navigation import NavigationGrid
from worldtrack.follow.robot import RobotLimits
from worldtrack.follow.safety import free_path, near_points
from worldtrack.follow.scan import ScanMovers, segments
from worldtrack.geometry.camera import Camera


#: The pursuit's carrot on the way round obstacles: this far (m) ahead, in steps of 0.1 m over 16 headings.
LOOKAHEAD = 0.6
RING = np.column_stack([np.cos(np.arange(16) * np.pi / 8), np.sin(np.arange(16) * np.pi / 8)])
#: The pursuit's way keeps this much (m) more than the robot's radius from obstacles (the carrot cuts corners).
NAV_MARGIN = 0.2
#: ``map_approach``: the straight way is blocked when the robot's radius plus this (m) does not pass.
MAP_APPROACH_MARGIN = 0.05
#: ``map_approach``: the way round is planned again once the target has moved this far (m) from its goal.
REPLAN = 0.3
#: ``reverse_guard``: the map is read this far (m) behind the robot, every 0.02 m, and the body kept this much
#: (m) more than its radius from what it shows there.
REVERSE_LOOK, REVERSE_MARGIN = 0.5, 0.02
#: ``search_map``: how far (m) the camera is taken to see along each of ``RING``'s 16 headings, every 0.1 m.
SEE_FAR = 8.0
#: Half the robot camera's horizontal field of view (rad): a heading farther off the robot's is out of view.
HALF_VIEW = np.radians(33.0)


def pursuit_map(scene, robot: RobotLimits = RobotLimits()) -> NavigationGrid:
    """The room's :class:`NavigationGrid` for :attr:`PIDFollower.nav`: drivable ``NAV_MARGIN`` clear of the
    robot's radius."""
    return NavigationGrid(scene, radius=robot.radius + NAV_MARGIN)


@dataclass
class PIDFollower:
    """PID on distance (m) and bearing (rad) to the target; see the module docstring.

    distance_gains, bearing_gains : (Kp, Ki, Kd) in 1/s, 1/s², 1 (distance) and 1/s, 1/s², 1 (bearing)
    depth_stop : also stop short of near depth points nobody detected (worldtrack's safety layer; False:
    the paper's PID)
    search_look : seconds the lost target's predicted place is looked at before the robot turns on round
    to look about (None: it only faces the prediction, the paper's and 35e's behaviour)
    pursue : seconds after the loss during which the robot drives to where the target was last seen
    (None: it stands, 35g and before)
    nav : the room (:func:`pursuit_map`): the pursuit drives towards a
    point ``LOOKAHEAD`` m down the shortest way round its obstacles (None: straight at the place)
    hidden_coast : seconds since last seen that a target hidden behind somebody nearer is followed by
    its prediction (0: lost after ``lost_timeout`` like any other)
    walkers : the other people's tracks (and the range scan's movers) limit the speed by where they walk
    (:func:`~worldtrack.follow.movers.moving_speed_limit`: someone walking out of the path, or ahead in
    the robot's direction, does not hold it); False: everybody is treated as standing (35e and before)
    map_approach : with ``nav``, a followed target whose straight way is blocked on the map (the robot's
    body, ``robot.radius`` + ``MAP_APPROACH_MARGIN`` m, does not pass from here to ``distance`` short of
    it) is driven to along the shortest way round (:meth:`_drive_to`) at up to ``robot.max_speed``,
    stopping ``distance`` short (True, the default since s11, with the tracker's ``reid_any_track_after``
    3 s; False: the PID steers straight at it, s10 and before)
    search_map : with ``nav`` (opt-in, False by default), the lost target's prediction is looked at only when
    it stands on the map and in line of sight (else the look about starts at once), and the look about turns
    towards the most open heading out of view (:meth:`_open_side`), not the way the target was going round
    reverse_guard : with ``nav``, backing off (the target too near) is limited to the speed that stops before
    the robot's body comes within ``REVERSE_MARGIN`` of a wall or an obstacle behind it on the map
    (:meth:`_reverse_limit`; the camera and the 270° scan do not see behind it). True (default; s11: every
    bumper stop of pid+scan on record, never-used 97's 20 / 40, was the PID backing into the bench)
    """

    distance: float = 1.8
    distance_gains: tuple = (1.2, 0.1, 0.1)
    bearing_gains: tuple = (2.5, 0.1, 0.1)
    robot: RobotLimits = RobotLimits()
    feed_forward: bool = True
    stop_distance: float = 0.7
    corridor: float = 0.6
    brake: float = 1.2
    lost_timeout: float = 1.0
    search_turn_rate: float = 0.5
    integral_limit: float = 0.5
    depth_stop: bool = False
    walkers: bool = False
    search_look: float | None = 2.0
    pursue: float | None = 10.0
    pursue_speed: float = 1.0
    arrive: float = 0.4
    hidden_coast: float = 3.0
    nav: NavigationGrid | None = None
    map_approach: bool = True
    reverse_guard: bool = True
    search_map: bool = False
    _state: dict = field(default_factory=dict, repr=False)

    def reset(self) -> None:
        self._state.clear()

    def command(self, step, camera: Camera, t: float, frame=None, scan=None) -> tuple[float, float]:
        """(v m/s, ω rad/s) for this frame's :class:`~worldtrack.follow.tracker.FollowStep`; ``frame``'s
        depth is read only with ``depth_stop`` (the paper's follower reads only the tracker's output);
        ``scan`` (M, 2): a range scanner's hit points round the robot (world, m, in ray order; see
        :mod:`~worldtrack.follow.scan`), read with ``depth_stop`` (its points) and ``walkers`` (its movers)."""
        s = self._state
        if step.found:
            s["seen"] = s["followed"] = t
        elif getattr(step, "hidden", False) and t - s.get("seen", -np.inf) <= self.hidden_coast:
            s["followed"] = t                   # behind somebody nearer: keep to its prediction
        pos = camera.centre[:2]
        fwd = camera.floor_direction
        left = np.array([-fwd[1], fwd[0]])
        rel = np.asarray(step.xy, float) - pos
        d = float(np.hypot(*rel))
        bearing = float(np.arctan2(rel @ left, rel @ fwd))
        if t - s.get("followed", -np.inf) > self.lost_timeout:
            self._lost_reset(t)
            goal = self._pursuit_goal(step, pos, t)
            if goal is not None:
                return self._drive_to(goal, step, camera, t, frame, scan)
            return self._search(t, bearing, camera, step)
        if self.map_approach and self.nav is not None and self._blocked_by_map(pos, rel, d):
            for k in ("t", "d_i", "d_e", "b_i", "b_e"):        # the PID starts afresh where the way is clear
                s.pop(k, None)
            return self._drive_to(np.asarray(step.xy, float), step, camera, t, frame, scan, stop_short=self.distance,
                                  speed=self.robot.max_speed, with_target=True)
        e_d = d - self.distance
        dt = t - s["t"] if "t" in s else 0.0
        v_ff = w_ff = 0.0
        if self.feed_forward:
            vel = np.asarray(step.velocity, float)
            v_ff = float(vel @ rel) / max(d, 1e-6)
            w_ff = float(rel[0] * vel[1] - rel[1] * vel[0]) / max(d * d, 1e-6)
        s["last_w"] = w_ff if step.found else s.get("last_w", 0.0)
        v = v_ff + self._pid("d", e_d, dt, self.distance_gains)
        w = w_ff + self._pid("b", bearing, dt, self.bearing_gains)
        s["t"] = t
        v = float(np.clip(v, -self.robot.max_reverse, self.robot.max_speed))
        if v < 0:
            v = max(v, -self._reverse_limit(camera, dt if dt > 0 else 0.1))
        w = float(np.clip(w, -self.robot.max_turn_rate, self.robot.max_turn_rate))
        limit = self._forward_limit(step, camera, w, t, dt if dt > 0 else 0.1, frame, scan)
        s["blocked"] = bool(limit < v)
        return min(v, limit), w

    def _forward_limit(self, step, camera: Camera, w: float, t: float, dt: float, frame, scan,
                       with_target: bool = True) -> float:
        """The largest forward speed (m/s) every safety rule allows: the path check, then people's
        velocities (``walkers``) and near depth points or scan points (``depth_stop``)."""
        limit = self._speed_limit(step, camera.centre[:2], camera.floor_direction, dt, with_target=with_target)
        if self.walkers:
            limit = min(limit, self._walkers_limit(step, camera, w, t, scan))
        if self.depth_stop and (frame is not None or scan is not None):
            limit = min(limit, self._depth_limit(frame, camera, w, dt, scan))
        return limit

    def _reverse_limit(self, camera: Camera, dt: float) -> float:
        """The largest backward speed (m/s, ≤ ``robot.max_reverse``): with ``reverse_guard`` and ``nav``, the one
        that stops (braking at ``brake`` m/s² after ``dt`` s) before the robot's centre comes within
        ``robot.radius + REVERSE_MARGIN`` m of anything the map shows behind it (read ``REVERSE_LOOK`` m back)."""
        if not self.reverse_guard or self.nav is None:
            return self.robot.max_reverse
        fwd = camera.floor_direction
        back = np.arange(0.0, REVERSE_LOOK + 1e-9, 0.02)
        centre = camera.centre[:2] - self.robot.camera_forward * fwd
        near = np.flatnonzero(self.nav.clearance(centre - back[:, None] * fwd) < self.robot.radius + REVERSE_MARGIN)
        if len(near) == 0:
            return self.robot.max_reverse
        gap = back[near[0] - 1] if near[0] > 0 else 0.0
        return float(np.clip(np.sqrt(2 * self.brake * gap) - self.brake * dt, 0.0, self.robot.max_reverse))

    def _lost_reset(self, t: float) -> None:
        """Clear the PID's state (integrals, derivatives) but what the search needs."""
        s = self._state
        keep = {k: s[k] for k in ("seen", "followed", "search_from", "search_turn", "search_last", "last_w",
                                  "arrived", "movers", "way", "way_to") if k in s}
        self.reset()
        s.update(keep)
        if s.get("search_last", -np.inf) < s.get("seen", -np.inf):         # a new loss
            s["search_from"], s["search_turn"], s["arrived"] = np.inf, 0.0, False
        s["search_last"] = t

    def _pursuit_goal(self, step, pos: np.ndarray, t: float):
        """Where the lost target was last seen (2,) m, while it is to be pursued, or None."""
        last = np.asarray(getattr(step, "last_xy", np.full(2, np.nan)), float)
        if self.pursue is None or not np.all(np.isfinite(last)) or t - self._state.get("seen", -np.inf) > self.pursue:
            return None
        if self._state["arrived"] or np.hypot(*(last - pos)) < self.arrive:
            self._state["arrived"] = True
            return None
        return last

    def _drive_to(self, goal: np.ndarray, step, camera: Camera, t: float, frame, scan, stop_short: float | None = None,
                  speed: float | None = None, with_target: bool = False) -> tuple[float, float]:
        """Turn to face ``goal`` (m) — or the point on the way there round the obstacles (``nav``) —, then
        drive to it, under the same speed limits as the PID: at most ``speed`` m/s (None: ``pursue_speed``),
        slowing to stop ``stop_short`` m short of it (None: inside ``arrive``)."""
        pos, fwd = camera.centre[:2], camera.floor_direction
        rel = self._waypoint(goal, pos - self.robot.camera_forward * fwd) - pos
        bearing = float(np.arctan2(rel @ np.array([-fwd[1], fwd[0]]), rel @ fwd))
        w = float(np.clip(self.bearing_gains[0] * bearing, -self.robot.max_turn_rate, self.robot.max_turn_rate))
        v, limit = 0.0, np.inf
        if abs(bearing) < np.radians(20.0):      # facing it (the camera sees the way): drive
            short = 0.5 * self.arrive if stop_short is None else stop_short
            ahead = np.hypot(*(goal - pos)) - short                 # slowing down to stop ``short`` of it
            v = float(np.clip(self.distance_gains[0] * ahead, 0.0, self.pursue_speed if speed is None else speed))
            limit = self._forward_limit(step, camera, w, t, 0.1, frame, scan, with_target=with_target)
        self._state["blocked"] = bool(limit < v)
        return min(v, limit), w

    def _waypoint(self, goal: np.ndarray, pos: np.ndarray) -> np.ndarray:
        """``goal`` without a map; else the point reached from ``pos`` going ``LOOKAHEAD`` m downhill on the
        shortest-way length to it (:meth:`NavigationGrid.geodesic`, computed once per goal)."""
        if self.nav is None:
            return goal
        s = self._state
        moved = (s.get("way_to") is None or (np.hypot(*(s["way_to"] - goal)) > REPLAN if self.map_approach
                                              else not np.allclose(s["way_to"], goal)))
        if moved:
            s["way"], s["way_to"] = self.nav.geodesic(goal), np.array(goal, float)
        p, here = np.array(pos, float), float(s["way"].sample(pos[None], outside=1e3)[0])
        for _ in range(int(round(LOOKAHEAD / 0.1))):
            near = p + 0.1 * RING
            left = s["way"].sample(near, outside=1e3)
            k = int(np.argmin(left))
            if left[k] >= here:
                break
            p, here = near[k], float(left[k])
        return p if np.hypot(*(p - pos)) > 0.05 else goal

    def _blocked_by_map(self, pos: np.ndarray, rel: np.ndarray, d: float) -> bool:
        """Whether the robot's body (``robot.radius`` + ``MAP_APPROACH_MARGIN``) cannot drive straight from
        ``pos`` (m) along ``rel`` (m, towards the target ``d`` m away) to ``distance`` m short of it."""
        if d <= self.distance + 0.1:
            return False
        way = pos + np.linspace(0.0, 1.0 - self.distance / d, int(np.ceil((d - self.distance) / 0.1)) + 1)[:, None] * rel
        return bool(self.nav.clearance(way).min() < self.robot.radius + MAP_APPROACH_MARGIN)

    def _search(self, t: float, bearing: float, camera: Camera | None = None, step=None) -> tuple[float, float]:
        """Lost: stand and turn slowly towards where the target should be; once that has been in view
        for ``search_look`` seconds without finding it (it turned while hidden, its prediction walked
        on), keep turning the same way round, a full look about (worldtrack; the paper stands). With
        ``search_map``, a prediction off the map or out of line of sight is not looked at, and the look
        about turns towards the most open heading (:meth:`_open_side`)."""
        s = self._state
        if s["search_turn"]:
            return 0.0, s["search_turn"]
        mapped = self.search_map and self.nav is not None and camera is not None and self.search_look is not None
        if mapped:
            pos, pred = camera.centre[:2], np.asarray(step.xy, float)
            if not (self.nav.clearance(pred)[0] > 0 and self.nav.line_of_sight(pos, pred)[0]):
                s["search_from"] = -np.inf                     # nothing to look at there: look about now
        if abs(bearing) < np.radians(15.0) or s["search_from"] == -np.inf:
            s["search_from"] = min(s["search_from"], t)
            if self.search_look is not None and t - s["search_from"] > self.search_look:
                # the most open side (search_map), else the way it was last seen going round the robot (left if not at all)
                side = self._open_side(camera) if mapped else (s.get("last_w", 0.0) or 1.0)
                s["search_turn"] = float(np.copysign(self.search_turn_rate, side))
                if mapped:                                     # (without the map: one more frame towards it, as before)
                    return 0.0, s["search_turn"]
        return 0.0, float(np.clip(self.bearing_gains[0] * bearing, -self.search_turn_rate, self.search_turn_rate))

    def _open_side(self, camera: Camera) -> float:
        """+1 (left) or −1 (right): the side of the robot's heading where the camera, turned, would see farthest
        over the map (``nav``): the free length (≤ ``SEE_FAR`` m) along each of the 16 ``RING`` headings out of
        view (more than ``HALF_VIEW`` off the heading); the longest's side."""
        pos, fwd = camera.centre[:2], camera.floor_direction
        reach = np.arange(0.1, SEE_FAR + 1e-9, 0.1)
        pts = pos + reach[None, :, None] * RING[:, None, :]                          # (16, R, 2)
        blocked = self.nav.clearance(pts.reshape(-1, 2)).reshape(len(RING), len(reach)) <= 0.0
        free = np.where(blocked.any(axis=1), reach[np.argmax(blocked, axis=1)], SEE_FAR)
        off = np.arctan2(RING @ np.array([-fwd[1], fwd[0]]), RING @ fwd)              # bearing of each heading
        free = np.where(np.abs(off) > HALF_VIEW, free, -1.0)
        return 1.0 if off[int(np.argmax(free))] >= 0 else -1.0

    @property
    def blocked(self) -> bool:
        """Whether the last command was held back because somebody was in the robot's path."""
        return bool(self._state.get("blocked", False))

    def _pid(self, name: str, error: float, dt: float, gains: tuple) -> float:
        kp, ki, kd = gains
        s = self._state
        integral = s.get(name + "_i", 0.0)
        deriv = 0.0
        if dt > 0 and name + "_e" in s:
            integral = float(np.clip(integral + error * dt, -self.integral_limit, self.integral_limit))
            deriv = (error - s[name + "_e"]) / dt
        s[name + "_i"], s[name + "_e"] = integral, error
        return kp * error + ki * integral + kd * deriv

    def _depth_limit(self, frame, camera: Camera, w: float, dt: float, scan=None) -> float:
        """The local planner's safety layer (:mod:`~worldtrack.follow.safety`) on the PID: the speed that
        stops 0.35 m (body) short of any near depth point (or scan point) along the next 1.5 s arc at ω."""
        points = near_points(getattr(frame, "depth", None), camera)
        if scan is not None and len(scan):
            points = np.vstack([points, np.asarray(scan, float).reshape(-1, 2)])
        if len(points) == 0:
            return np.inf
        fwd = camera.floor_direction
        yaw = np.arctan2(fwd[1], fwd[0]) + w * np.linspace(0.0, 1.5, 16)
        centre = camera.centre[:2] - 0.1 * fwd
        step_xy = (self.robot.max_speed * 0.1) * np.column_stack([np.cos(yaw), np.sin(yaw)])
        path = centre + np.vstack([np.zeros(2), np.cumsum(step_xy[1:], axis=0)])
        gap = free_path(path, points, 0.35)
        return np.inf if not np.isfinite(gap) else float(max(0.0, np.sqrt(2 * self.brake * gap) - self.brake * dt))

    def _walkers_limit(self, step, camera: Camera, w: float, t: float, scan) -> float:
        """The speed from which the robot stops ``stop_distance`` clear of every other person walking on
        (tracks with their Kalman velocities, the scan's movers with theirs; the target is left to the
        distance control)."""
        xy = [np.asarray(step.others_xy, float).reshape(-1, 2)]
        vel = [np.asarray(getattr(step, "others_velocity", np.zeros((len(xy[0]), 2))), float).reshape(-1, 2)]
        fwd = camera.floor_direction
        centre = camera.centre[:2] - 0.1 * fwd
        if scan is not None:
            movers = self._state.setdefault("movers", ScanMovers())
            found, velocity = movers.update(segments(scan, origin=centre), t)
            away = np.hypot(*(found - np.asarray(step.xy, float)).T) > 0.5     # the target is not a mover
            xy.append(found[away])
            vel.append(velocity[away])
        xy, vel = np.vstack(xy), np.vstack(vel)
        return moving_speed_limit(centre, float(np.arctan2(fwd[1], fwd[0])), w, xy, vel,
                                  clearance=self.stop_distance, brake=self.brake, max_speed=self.robot.max_speed)

    def _speed_limit(self, step, pos: np.ndarray, fwd: np.ndarray, dt: float, with_target: bool = True) -> float:
        """Largest forward speed (m/s) that stops ``stop_distance`` short of anybody in the path (the
        target only by the stop distance: the distance control keeps the robot back from it). With
        ``walkers`` the other tracks (and candidates they explain) are left to :meth:`_walkers_limit`."""
        # a lost target's prediction limits nothing (put behind the robot)
        people = [np.asarray(step.xy, float)[None] if with_target else (pos - 10.0 * fwd)[None]]
        cands = np.asarray(step.candidates.xy, float).reshape(-1, 2)
        chosen = getattr(step, "chosen", -1)
        if len(cands):
            cands = np.delete(cands, chosen, axis=0) if step.found and chosen >= 0 else cands
            if self.walkers and len(step.others_xy) and len(cands):
                d = np.hypot(cands[:, None, 0] - step.others_xy[None, :, 0], cands[:, None, 1] - step.others_xy[None, :, 1])
                cands = cands[d.min(axis=1) > 0.3]
            people.append(cands)
        if len(step.others_xy) and not self.walkers:
            people.append(step.others_xy)
        rel = np.vstack(people) - pos
        ahead = rel @ fwd
        side = np.abs(rel @ np.array([-fwd[1], fwd[0]]))
        if np.any((ahead > 0) & (np.hypot(ahead, side) < self.stop_distance)):
            return 0.0
        gap = ahead[1:][(ahead[1:] > 0) & (side[1:] < self.corridor)] - self.stop_distance
        if len(gap) == 0:
            return np.inf
        return float(max(0.0, np.sqrt(2 * self.brake * max(gap.min(), 0.0)) - self.brake * dt))
