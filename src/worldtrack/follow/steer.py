"""Steering round somebody in the path instead of waiting behind them (worldtrack, beyond seed 001).

The PID (:mod:`~worldtrack.follow.pid`) asks for a speed ``v`` and a turn rate ``w`` to keep its
distance and bearing to the target; its safety rules (the path check, the people's velocities, the
depth and scan points) give the fastest forward speed each turn rate allows, ``limit_at(w)``. When the
PID's own turn rate is held back (somebody crosses in front), a slightly different turn rate often is
not: curving behind a crosser who walks out of the path, or past the side of somebody standing.
:func:`steer_round` is that choice, a dynamic window over the turn rate only — the speed stays the PID's
(its distance keeping), every candidate is checked by the same safety rules along its own arc, and
a turn rate that would take the target out of the camera's view within ``look_ahead`` seconds is not
a candidate. The PID's own turn rate is kept unless another lets the robot go at least ``gain`` m/s
faster; among those, the fastest, less ``cost`` m/s per rad/s of departure from the PID's turn.

>>> import numpy as np
>>> # somebody stands 0.8 m ahead, slightly right: straight on is held, a left curve is not
>>> limit_at = lambda w: 0.3 if w < 0.4 else 1.4
>>> w, limit = steer_round(limit_at, v=1.2, w=0.0, bearing=0.0)
>>> bool(w >= 0.4), limit
(True, 1.4)
>>> steer_round(limit_at, v=1.2, w=0.0, bearing=np.radians(-20.0))[1]   # the target would leave the view
0.3
"""

from __future__ import annotations

import numpy as np

#: Turn-rate departures (rad/s) from the PID's that are tried.
OFFSETS = np.array([-1.0, -0.8, -0.6, -0.4, -0.2, 0.2, 0.4, 0.6, 0.8, 1.0])


def steer_round(limit_at, v: float, w: float, bearing: float, max_turn_rate: float = 1.5,
                view_half_angle: float = np.radians(25.0), look_ahead: float = 1.0, gain: float = 0.15,
                cost: float = 0.3, first_w: float | None = None, turn_step: float = 0.4) -> tuple[float, float]:
    """(turn rate rad/s, forward speed limit m/s) to command instead of the PID's ``w`` held back to
    ``limit_at(w) < v``.

    limit_at : turn rate (rad/s) → the fastest forward speed (m/s) every safety rule allows along that
    arc; v : the PID's speed, m/s; w : its turn rate, rad/s; bearing : the target's bearing now, rad
    (left positive); the turn rate ``w + δ`` moves it by about ``−δ·look_ahead`` rad, which must stay
    within ``view_half_angle``; first_w : the turn rate the robot drives at now (the last command), from
    which it can change by at most ``turn_step`` rad/s in the next frame: each candidate is also checked
    along the arc it will drive first, and allowed the smaller of the two limits (None: not checked).
    """
    held = float(limit_at(w))
    best_w, best_limit, best_score = w, held, min(v, held) + gain
    for delta in OFFSETS:
        cand = float(np.clip(w + delta, -max_turn_rate, max_turn_rate))
        if cand == w or abs(bearing - (cand - w) * look_ahead) > view_half_angle:
            continue
        limit = float(limit_at(cand))
        if first_w is not None and min(v, limit) > min(v, held):
            first = float(np.clip(cand, first_w - turn_step, first_w + turn_step))
            if first != cand:
                limit = min(limit, float(limit_at(first)))
        score = min(v, limit) - cost * abs(cand - w)
        if score > best_score:
            best_w, best_limit, best_score = cand, limit, score
    return best_w, best_limit
