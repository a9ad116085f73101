"""How people move: scripted waypoint paths, random walkers, a robot following a target.

Every generator returns a :class:`Track` sampled at the frame times ``t_k = k / fps``: ground point,
heading, ground speed, presence, sitting and the gait phase that drives the legs. Speeds are real
m/s; a person standing still has speed exactly 0 (consecutive positions are equal), and the limb
swing amplitude follows the speed, so standing legs do not swing.

Random walkers (:func:`random_walkers`) pick goals on the walkable area whose straight path is
clear of walls and obstacles, steer towards them, are pushed away from each other and from
obstacles, and obey two hard constraints at every sub-step: stay ``clearance`` metres inside the
walkable area and keep ``min_separation`` metres between centres (a move that would break either
is undone — the walker waits).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.typing import ArrayLike

from worldtrack.errors import InputError
from worldtrack.scene.model import Scene
from worldtrack.synth.joints import gait_amplitude, stride_length


@dataclass
class Track:
    """One person's motion at the frame times (T frames).

    Attributes
    ----------
    xy : (T, 2) metres — ground point; yaw : (T,) radians — heading
    speed : (T,) m/s — ground speed; present : (T,) bool — in the scene
    sit : (T,) — 0 standing … 1 seated; phase : (T,) radians — gait phase; amplitude : (T,)
    """

    xy: np.ndarray
    yaw: np.ndarray
    speed: np.ndarray
    present: np.ndarray
    sit: np.ndarray
    phase: np.ndarray
    amplitude: np.ndarray

    def __len__(self) -> int:
        return len(self.xy)


def finish_track(xy: ArrayLike, fps: float, height: float, present: ArrayLike | None = None,
                 sit: ArrayLike | None = None, yaw_hint: ArrayLike | None = None,
                 max_turn_rate: float = 4.0, initial_yaw: float | None = None) -> Track:
    """Speed, heading and gait phase from sampled positions.

    Speed is the central difference of the positions (exactly 0 while standing still). The heading
    turns towards the direction of motion at most ``max_turn_rate`` rad/s (``yaw_hint`` where not
    NaN overrides the direction). The gait phase advances by ``2π·speed·dt / stride_length``.
    """
    xy = np.asarray(xy, dtype=float)
    T = len(xy)
    dt = 1.0 / fps
    present = np.ones(T, bool) if present is None else np.asarray(present, bool)
    sit = np.zeros(T) if sit is None else np.asarray(sit, float)
    vel = np.zeros_like(xy)
    if T > 1:
        vel[1:-1] = (xy[2:] - xy[:-2]) / (2 * dt)
        vel[0] = (xy[1] - xy[0]) / dt
        vel[-1] = (xy[-1] - xy[-2]) / dt
    speed = np.linalg.norm(vel, axis=1)
    speed[speed < 1e-9] = 0.0
    yaw = np.zeros(T)
    cur = initial_yaw
    for k in range(T):
        want = None
        if yaw_hint is not None and np.isfinite(yaw_hint[k]):
            want = float(yaw_hint[k])
        elif speed[k] > 0.05:
            want = float(np.arctan2(vel[k, 1], vel[k, 0]))
        if cur is None:
            cur = want if want is not None else 0.0
        elif want is not None:
            diff = (want - cur + np.pi) % (2 * np.pi) - np.pi
            cur = cur + float(np.clip(diff, -max_turn_rate * dt, max_turn_rate * dt))
        yaw[k] = cur
    # Gait: amplitude follows a lightly smoothed speed (no swing while standing).
    kernel = np.array([0.25, 0.5, 0.25])
    smooth = np.convolve(np.pad(speed, 1, mode="edge"), kernel, mode="valid") if T > 2 else speed.copy()
    smooth[speed == 0] = 0.0
    amp = gait_amplitude(smooth) * (1.0 - np.clip(sit, 0, 1))
    phase = np.zeros(T)
    phase[1:] = np.cumsum(2 * np.pi * smooth[1:] * dt / stride_length(height, smooth[1:]))
    return Track(xy, yaw, speed, present, sit, phase, amp)


# ------------------------------------------------------------------------------------ scripted paths

@dataclass(frozen=True)
class Waypoint:
    """A point to walk to, and what to do there.

    Parameters
    ----------
    x, y : float, metres
    dwell : float, seconds — stand (or sit) still on arrival
    speed : float, m/s — preferred speed on the way here
    sit : bool — sit down during the dwell (down and up take ``sit_time`` each)
    face : float or None, radians — heading to turn to while dwelling
    """

    x: float
    y: float
    dwell: float = 0.0
    speed: float = 1.2
    sit: bool = False
    face: float | None = None


def scripted_track(waypoints: Sequence[Waypoint], fps: float, n_frames: int, height: float,
                   start_time: float = 0.0, leave_at_end: bool = False, accel: float = 1.2,
                   sit_time: float = 1.2, initial_yaw: float | None = None) -> Track:
    """Walk from the first waypoint through the others (accelerating and braking at ``accel`` m/s²).

    The person appears at ``start_time`` on the first waypoint (after its dwell, walks on); at the
    end they stay on the last waypoint, or with ``leave_at_end`` disappear on arriving there.
    """
    if not waypoints:
        raise InputError("waypoints: expected at least one")
    dt = 1.0 / fps
    T = n_frames
    xy = np.zeros((T, 2))
    present = np.zeros(T, bool)
    sit = np.zeros(T)
    face = np.full(T, np.nan)
    pos = np.array([waypoints[0].x, waypoints[0].y], dtype=float)
    target = 0
    dwell_left = waypoints[0].dwell
    dwell_total = dwell_left
    v = 0.0
    gone = False
    for k in range(T):
        t = k * dt
        if t + 1e-9 < start_time or gone:
            xy[k] = pos
            continue
        present[k] = True
        xy[k] = pos
        wp = waypoints[target]
        if dwell_left > 0:
            if wp.sit and dwell_total > 0:
                elapsed = dwell_total - dwell_left
                sit[k] = np.clip(min(elapsed, dwell_left) / sit_time, 0.0, 1.0)
            if wp.face is not None:
                face[k] = wp.face
            dwell_left -= dt
            continue
        if target == len(waypoints) - 1:
            if leave_at_end:
                present[k] = False
                gone = True
            continue
        nxt = waypoints[target + 1]
        goal = np.array([nxt.x, nxt.y])
        dist = float(np.linalg.norm(goal - pos))
        brake = np.sqrt(2 * accel * dist) if (nxt.dwell > 0 or target + 1 == len(waypoints) - 1) else np.inf
        v = min(v + accel * dt, nxt.speed, brake)
        step = v * dt
        if step >= dist - 1e-9:
            pos = goal.copy()
            target += 1
            dwell_left = nxt.dwell
            dwell_total = nxt.dwell
            if nxt.dwell > 0:
                v = 0.0
        else:
            pos = pos + (goal - pos) / dist * step
    # xy[k] was recorded before frame k's step: the position at t_k.
    return finish_track(xy, fps, height, present, sit, face, initial_yaw=initial_yaw)


# ------------------------------------------------------------------------------------ random walkers

@dataclass
class WalkerSettings:
    """Random-walker behaviour (speeds m/s, distances m, times s)."""

    speed: tuple = (0.9, 1.4)
    min_separation: float = 0.6
    clearance: float = 0.3
    p_stop: float = 0.3
    dwell: tuple = (1.0, 4.0)
    min_goal_distance: float = 1.5
    substeps: int = 2
    accel: float = 1.5
    dwell_yields: bool = False   # a walker standing still steps aside for people coming at them


def _segment_clear(df, a: np.ndarray, b: np.ndarray, clearance: float) -> bool:
    n = max(2, int(np.ceil(np.linalg.norm(b - a) / 0.05)) + 1)
    pts = a + np.linspace(0.0, 1.0, n)[:, None] * (b - a)
    return bool(np.all(df.sample(pts, outside=-1.0) >= clearance))


def _sample_goal(scene: Scene, df, rng, start: np.ndarray, s: WalkerSettings, region=None) -> np.ndarray | None:
    x0, x1, y0, y1 = scene.walkable.bounds
    for _ in range(60):
        g = np.array([rng.uniform(x0, x1), rng.uniform(y0, y1)])
        if region is not None and not region(g):
            continue
        if df.sample(g[None], outside=-1.0)[0] < s.clearance + 0.2:
            continue
        if np.linalg.norm(g - start) < s.min_goal_distance:
            continue
        if _segment_clear(df, start, g, s.clearance + 0.05):
            return g
    return None


def random_walkers(scene: Scene, n: int, fps: float, n_frames: int, rng: np.random.Generator,
                   heights: Sequence[float], settings: WalkerSettings | None = None,
                   others: Sequence[Track] = (), other_radius: float = 0.6,
                   start: np.ndarray | None = None) -> list[Track]:
    """``n`` people walking between random goals on the walkable area.

    Parameters
    ----------
    others : tracks of people (or a robot) to keep ``other_radius`` metres away from
    start : (n, 2) optional start positions (drawn on the free floor otherwise)
    """
    s = settings or WalkerSettings()
    df = scene.distance_field(0.05)
    x0, x1, y0, y1 = scene.walkable.bounds
    other_xy = np.array([o.xy for o in others]).reshape(len(others), n_frames, 2)
    other_on = np.array([o.present for o in others], dtype=bool).reshape(len(others), n_frames)

    def free(p, k, mine=None):
        if df.sample(p[None], outside=-1.0)[0] < s.clearance + 0.1:
            return False
        if mine is not None and len(mine) and np.min(np.linalg.norm(mine - p, axis=1)) < s.min_separation + 0.2:
            return False
        on = other_on[:, k]
        if on.any() and np.min(np.linalg.norm(other_xy[on, k] - p, axis=1)) < other_radius + 0.2:
            return False
        return True

    if start is None:
        pos = np.zeros((0, 2))
        tries = 0
        while len(pos) < n:
            tries += 1
            if tries > 20000:
                raise InputError(f"people: cannot place {n} walkers {s.min_separation} m apart on this floor")
            p = np.array([rng.uniform(x0, x1), rng.uniform(y0, y1)])
            if free(p, 0, pos):
                pos = np.vstack([pos, p])
    else:
        pos = np.asarray(start, dtype=float).reshape(n, 2).copy()
    pref = rng.uniform(*s.speed, size=n)
    goals = np.array([_sample_goal(scene, df, rng, p, s) for p in pos], dtype=object)
    goal = np.array([g if g is not None else p for g, p in zip(goals, pos)], dtype=float).reshape(n, 2)
    dwell = np.zeros(n)
    stuck = np.zeros(n)
    vel = np.zeros((n, 2))
    dt = 1.0 / (fps * s.substeps)
    out = np.zeros((n_frames, n, 2))
    for k in range(n_frames):
        out[k] = pos
        t_other = min(k + 1, n_frames - 1)
        on = other_on[:, t_other]
        obs = other_xy[on, t_other]
        for _ in range(s.substeps):
            # Goals and dwelling.
            to_goal = goal - pos
            dist = np.linalg.norm(to_goal, axis=1)
            arrived = (dist < 0.25) & (dwell <= 0)
            for i in np.flatnonzero(arrived | (stuck > 3.0)):
                if arrived[i] and rng.random() < s.p_stop:
                    dwell[i] = rng.uniform(*s.dwell)
                g = _sample_goal(scene, df, rng, pos[i], s)
                goal[i] = g if g is not None else pos[i]
                stuck[i] = 0.0
            dwell -= dt
            to_goal = goal - pos
            dist = np.maximum(np.linalg.norm(to_goal, axis=1), 1e-9)
            v_des = (pref * np.minimum(1.0, dist / 0.8) / dist)[:, None] * to_goal
            v_des[dwell > 0] = 0.0
            # Push from other walkers and agents (with a slight keep-right twist against deadlocks).
            push = np.zeros((n, 2))
            agents = np.vstack([pos, obs]) if len(obs) else pos
            diff = pos[:, None, :] - agents[None, :, :]
            d = np.linalg.norm(diff, axis=2)
            np.fill_diagonal(d[:, :n], np.inf)
            reach = np.where(np.arange(len(agents))[None, :] < n, 1.2, other_radius + 0.8)
            w = np.clip((reach - d) / (reach - s.min_separation + 1e-9), 0.0, 1.0) ** 2
            unit = diff / np.maximum(d, 1e-9)[:, :, None]
            side = np.stack([unit[..., 1], -unit[..., 0]], axis=-1)
            moving = ((dwell <= 0) | s.dwell_yields)[:, None, None]
            push += np.sum(w[:, :, None] * (1.2 * unit + 0.6 * side * moving), axis=1)
            # Push from walls and obstacles.
            val = df.sample(pos, outside=-1.0)
            grad = df.gradient(pos)
            gn = np.linalg.norm(grad, axis=1, keepdims=True)
            wo = np.clip((0.75 - val) / 0.45, 0.0, 1.0)[:, None]
            push += wo * 0.8 * grad / np.maximum(gn, 1e-9)
            v_cmd = v_des + push * ((dwell <= 0) | s.dwell_yields)[:, None]
            sp = np.linalg.norm(v_cmd, axis=1, keepdims=True)
            v_cmd *= np.minimum(1.0, 1.3 * pref[:, None] / np.maximum(sp, 1e-9))
            dv = v_cmd - vel
            dvn = np.linalg.norm(dv, axis=1, keepdims=True)
            vel = vel + dv * np.minimum(1.0, s.accel * dt / np.maximum(dvn, 1e-9))
            new = pos + vel * dt
            # Hard constraints: undo moves that leave the floor or come too close.
            bad = df.sample(new, outside=-1.0) < s.clearance
            cand = np.where(bad[:, None], pos, new)
            halved = np.zeros(n, bool)
            for _it in range(2 * n + 2):
                dd = np.linalg.norm(cand[:, None, :] - cand[None, :, :], axis=2)
                np.fill_diagonal(dd, np.inf)
                close = np.any(dd < s.min_separation, axis=1)
                if len(obs):
                    near_new = np.linalg.norm(cand[:, None, :] - obs[None, :, :], axis=2).min(axis=1)
                    hit = near_new < other_radius
                    if s.dwell_yields:   # stepping away from someone already too close is allowed
                        hit &= near_new < np.linalg.norm(pos[:, None, :] - obs[None, :, :], axis=2).min(axis=1)
                    close |= hit
                moved = np.any(cand != pos, axis=1)
                revert = close & moved
                if not revert.any():
                    break
                # First try half the step, then no step (positions before the step were valid).
                half = revert & ~halved
                cand[half] = pos[half] + 0.5 * (cand[half] - pos[half])
                halved |= half
                full = revert & ~half
                cand[full] = pos[full]
            changed = np.any(cand != new, axis=1)
            vel[changed] = 0.0
            stuck = np.where((np.linalg.norm(cand - pos, axis=1) < 0.05 * dt) & (dwell <= 0), stuck + dt, 0.0)
            pos = cand
    return [finish_track(out[:, i], fps, heights[i]) for i in range(n)]


# ------------------------------------------------------------------------------------ graph walks

def graph_route(nodes: np.ndarray, edges: Sequence[tuple[int, int]], start: int, legs: int,
                rng: np.random.Generator) -> list[int]:
    """A random walk of ``legs`` steps on a graph of floor points, not turning back unless forced."""
    nbrs: dict[int, list[int]] = {i: [] for i in range(len(nodes))}
    for a, b in edges:
        nbrs[a].append(b)
        nbrs[b].append(a)
    route = [start]
    prev = -1
    for _ in range(legs):
        cur = route[-1]
        options = [j for j in nbrs[cur] if j != prev] or nbrs[cur]
        nxt = int(options[rng.integers(len(options))])
        prev = cur
        route.append(nxt)
    return route


# ------------------------------------------------------------------------------------ robot

@dataclass
class RobotPath:
    """A robot's pose at the frame times: xy (T, 2), yaw (T,)."""

    xy: np.ndarray
    yaw: np.ndarray


def follow_target(scene: Scene, target: Track, fps: float, distance: float = 1.8, start_xy: ArrayLike | None = None,
                  start_yaw: float | None = None, max_speed: float = 1.6, max_turn_rate: float = 1.5,
                  gain: float = 1.2, accel: float = 1.0, clearance: float = 0.35, avoid: bool = False) -> RobotPath:
    """A robot that turns towards the target and drives to stay ``distance`` metres from it (P control).

    Without ``avoid`` it stops where driving on would bring it within ``clearance`` of a wall or an
    obstacle (and may stay stuck there); with ``avoid`` it steers round them: it heads for the
    direction nearest the target's whose point 0.5 m ahead keeps the clearance (15° steps, up to 90°).
    """
    T = len(target)
    dt = 1.0 / fps
    df = scene.distance_field(0.05)
    if start_xy is None:
        back = np.array([np.cos(target.yaw[0]), np.sin(target.yaw[0])])
        start_xy = target.xy[0] - distance * back
    pos = np.asarray(start_xy, dtype=float).copy()
    yaw = float(np.arctan2(*(target.xy[0] - pos)[::-1])) if start_yaw is None else float(start_yaw)
    v = 0.0
    xy = np.zeros((T, 2))
    yaws = np.zeros(T)
    for k in range(T):
        xy[k], yaws[k] = pos, yaw
        to = target.xy[min(k + 1, T - 1)] - pos
        dist = float(np.linalg.norm(to))
        want = float(np.arctan2(to[1], to[0]))
        if avoid:
            want = _free_heading(df, pos, want, clearance + 0.05)
        diff = (want - yaw + np.pi) % (2 * np.pi) - np.pi
        yaw += float(np.clip(diff, -max_turn_rate * dt, max_turn_rate * dt))
        v_cmd = float(np.clip(gain * (dist - distance), 0.0, max_speed)) * max(0.0, np.cos(diff))
        v += float(np.clip(v_cmd - v, -accel * dt, accel * dt))
        new = pos + v * dt * np.array([np.cos(yaw), np.sin(yaw)])
        need = clearance
        if avoid:   # inside the clearance zone, any step that gets out of it is allowed
            need = min(clearance, float(df.sample(pos[None], outside=-1.0)[0]) + 1e-3)
        if df.sample(new[None], outside=-1.0)[0] >= need:
            pos = new
        else:
            v = 0.0
    return RobotPath(xy, yaws)


def _free_heading(df, pos: np.ndarray, want: float, clearance: float, lookahead: float = 0.5) -> float:
    """The heading nearest ``want`` (rad) whose point ``lookahead`` m ahead keeps ``clearance`` m free
    and whose first 0.1 m does not come nearer an obstacle than the robot already is (if inside)."""
    offsets = np.radians([0, 15, -15, 30, -30, 45, -45, 60, -60, 75, -75, 90, -90])
    heads = want + offsets
    unit = np.column_stack([np.cos(heads), np.sin(heads)])
    here = float(df.sample(pos[None], outside=-1.0)[0])
    far = df.sample(pos[None] + lookahead * unit, outside=-1.0) >= clearance
    near = df.sample(pos[None] + 0.1 * unit, outside=-1.0) >= min(clearance, here)
    free = np.flatnonzero(far & near)
    return float(heads[free[0]]) if len(free) else want


def track_from_robot(robot: RobotPath, fps: float) -> Track:
    """The robot as a Track (so walkers can keep away from it); never rendered."""
    T = len(robot.xy)
    return Track(robot.xy, robot.yaw, np.zeros(T), np.ones(T, bool), np.zeros(T), np.zeros(T), np.zeros(T))
