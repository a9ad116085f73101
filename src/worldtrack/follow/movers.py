"""How fast the robot may drive among people who walk (worldtrack, beyond seed 001).

A person standing in the robot's path must stop it; a person walking out of the path, or walking
ahead of it in its own direction (somebody cutting in between the robot and its target), need not.
:func:`moving_speed_limit` tries every forward speed on a grid: the robot drives at that speed for
one reaction ``delay``, then brakes at ``brake`` m/s² to a stop, along its arc at the commanded turn
rate, while every person walks on at their velocity (constant-velocity prediction over ``horizon``
seconds). A speed is admissible if, wherever the robot is still driving towards somebody, its
centre keeps ``clearance`` metres from their predicted centre — or, for somebody already nearer
than that, does not come any nearer. What people do to a robot that stands, or drives away from
them, is their doing (the closed loop counts it apart), so it is not checked. The limit is the
fastest admissible speed; 0 when none is.

A standing person (velocity 0) gives the usual braking limit, ``v·delay + v²/(2·brake) ≤ gap``.

>>> import numpy as np
>>> ahead = np.array([[1.2, 0.0]])                                   # a person 1.2 m ahead
>>> standing = moving_speed_limit((0, 0), 0.0, 0.0, ahead, np.zeros((1, 2)))
>>> walking_away = moving_speed_limit((0, 0), 0.0, 0.0, ahead, np.array([[1.0, 0.0]]))
>>> crossing_out = moving_speed_limit((0, 0), 0.0, 0.0, np.array([[1.2, -0.3]]), np.array([[0.0, -1.0]]))
>>> bool(0.85 < standing < 1.05), bool(walking_away == 1.6), bool(crossing_out > standing)
(True, True, True)
"""

from __future__ import annotations

import numpy as np


def moving_speed_limit(centre, yaw: float, turn_rate: float, people_xy: np.ndarray, people_velocity: np.ndarray,
                       clearance: float = 0.7, brake: float = 1.2, delay: float = 0.1, horizon: float = 2.0,
                       max_speed: float = 1.6, step: float = 0.1) -> float:
    """The fastest forward speed (m/s, on a 0.1 m/s grid up to ``max_speed``) from which the robot can
    still stop without coming within ``clearance`` m of anybody walking on at their velocity.

    centre : (2,) the robot's centre, m; yaw : its heading, rad; turn_rate : rad/s, kept while braking;
    people_xy, people_velocity : (K, 2) m and m/s; clearance : robot radius + a person's + margin, m;
    brake : m/s²; delay : reaction time, s; horizon : how long people are predicted, s; step : s.
    Returns ``max_speed`` with nobody around, 0 when no speed is admissible.
    """
    people_xy = np.asarray(people_xy, float).reshape(-1, 2)
    if len(people_xy) == 0:
        return float(max_speed)
    velocity = np.asarray(people_velocity, float).reshape(-1, 2)
    speeds = np.round(np.arange(0.0, max_speed + 1e-9, 0.1), 6)                  # (S,)
    times = np.arange(0.0, horizon + 1e-9, step)                                  # (T,)
    profile = np.clip(speeds[:, None] - brake * np.clip(times[None] - delay, 0.0, None), 0.0, None)  # (S, T)
    heading = yaw + turn_rate * times                                               # (T,)
    moves = profile[:, :-1, None] * step * np.stack([np.cos(heading[:-1]), np.sin(heading[:-1])], -1)[None]
    robot = np.asarray(centre, float)[None, None] + np.concatenate(
        [np.zeros((len(speeds), 1, 2)), np.cumsum(moves, axis=1)], axis=1)        # (S, T, 2)
    people = people_xy[None] + times[:, None, None] * velocity[None]                # (T, K, 2)
    d = np.linalg.norm(robot[:, :, None, :] - people[None], axis=-1)                # (S, T, K)
    allowed = np.minimum(clearance, d[0, 0] - 1e-6)                                 # (K,) nearer now: no nearer
    # Only where the robot drives towards them: what people do to a robot that stands or drives away
    # (somebody walking up behind a braking robot) is theirs, not its.
    along = np.stack([np.cos(heading), np.sin(heading)], -1)                        # (T, 2)
    towards = np.einsum("tc,stkc->stk", along, people[None] - robot[:, :, None, :]) > 0
    driving = (profile > 0)[:, :, None] & towards                                   # (S, T, K)
    ok = np.all((d >= allowed[None, None]) | ~driving, axis=(1, 2))
    if not ok[0]:
        # Someone walks at the robot whatever it does: stand (their doing, not the robot's).
        return 0.0
    # Admissible speeds form a prefix in practice; take the fastest of the first run.
    bad = np.flatnonzero(~ok)
    return float(speeds[bad[0] - 1] if len(bad) else speeds[-1])
