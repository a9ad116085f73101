"""Would steering get the robot past somebody who holds it? Each safety rule's speed limit over turn rates.

Question (issue 35, the closed loop's largest out-of-band class): while somebody in the path holds the
PID follower back, does another turn rate let it go faster? If it does, a local planner that steers
round (behind) crossers instead of waiting could take that time back; if every turn rate is held alike,
it cannot, whatever it optimises.

Replays one seed's closed loop (``benchmarks/follow_loop.py``'s pid+scan follower, unchanged) up to
``--until`` frames and, at every frame the follower is held (its forward limit below the PID's speed),
asks its three safety rules — the path check, the people's velocities (walkers) and the depth + scan
points — for the fastest speed along the arc at the PID's turn rate ``w`` and at ``w + δ`` for δ in
±0.3, ±0.6, ±1.0 rad/s. A departure of more than ±0.45 rad/s takes a target 1.8 m ahead out of the
camera's view within about a second. Prints, per held frame, the limits, and the summary: in how many
held frames some departure would let the robot go ≥ 0.1 m/s faster, and by how much (median).

Run: ``.venv/bin/python benchmarks/follow_hold_limits.py --seed 38 --until 300``. A few minutes on a
shared core (the frames are rendered as in the closed loop). Writes
``benchmarks/results/follow_hold_limits<TAG>.md``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table  # noqa: E402
from follow_common import SCENARIO, save_tagged  # noqa: E402
from follow_loop import DISTANCE, make_follower  # noqa: E402

from worldtrack.follow.loop import run_closed_loop  # noqa: E402
from worldtrack.follow.movers import moving_speed_limit  # noqa: E402
from worldtrack.synth import make_scenario  # noqa: E402

DEPARTURES = (-1.0, -0.6, -0.3, 0.0, 0.3, 0.6, 1.0)
MAX_SPEED = 1.6


class _Done(Exception):
    pass


def walkers_limit(pid, step, camera, turn_rate: float) -> float:
    """The follower's walkers limit (its tracks and the scan's movers as it last updated them: calling its
    own method again in the same frame would re-learn the movers from a zero time step) at ``turn_rate``."""
    xy = [np.asarray(step.others_xy, float).reshape(-1, 2)]
    vel = [np.asarray(getattr(step, "others_velocity", np.zeros((len(xy[0]), 2))), float).reshape(-1, 2)]
    movers = pid._state.get("movers")
    if movers is not None and len(movers.xy):
        away = np.hypot(*(movers.xy - np.asarray(step.xy, float)).T) > 0.5
        xy.append(movers.xy[away])
        vel.append(movers.velocity[away])
    fwd = camera.floor_direction
    return moving_speed_limit(camera.centre[:2] - 0.1 * fwd, float(np.arctan2(fwd[1], fwd[0])), turn_rate,
                              np.vstack(xy), np.vstack(vel), clearance=pid.stop_distance, brake=pid.brake,
                              max_speed=pid.robot.max_speed)


def held_limits(seed: int, until: int, frames: int = 1500) -> list:
    """Rows (frame, v, w, limits (3, D): path / walkers / depth over ``DEPARTURES``) for every held frame
    of ``seed``'s pid+scan closed loop up to frame ``until``."""
    sc = make_scenario("follow-target", size=(160, 120), frames=frames, seed=seed, distance=DISTANCE, **SCENARIO)
    pid = make_follower("pid+scan", sc.scene)
    command = pid.command
    rows = []

    def probe(step, camera, t, frame=None, scan=None):
        k = int(round(t * sc.fps))
        if k > until:
            raise _Done
        v, w = command(step, camera, t, frame=frame, scan=scan)
        if pid.blocked and pid._state.get("t") == t:                # held in the PID (not the pursuit)
            pos, fwd = camera.centre[:2], camera.floor_direction
            lim = np.array([[pid._speed_limit(step, pos, fwd, 0.1), walkers_limit(pid, step, camera, w + d),
                             pid._depth_limit(frame, camera, w + d, 0.1, scan)] for d in DEPARTURES]).T
            rows.append((k, float(v), float(w), lim))
        return v, w

    pid.command = probe
    try:
        run_closed_loop(sc, follower=pid, side_scan=True)
    except _Done:
        pass
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seed", type=int, default=38)
    ap.add_argument("--until", type=int, default=300, help="last frame replayed")
    ap.add_argument("--tag", default="")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    rows = held_limits(args.seed, args.until)
    table, gains = [], []
    centre = DEPARTURES.index(0.0)
    in_view = [i for i, d in enumerate(DEPARTURES) if abs(d) <= 0.45]
    for k, v, w, lim in rows:
        allowed = lim.min(axis=0)                                   # (D,) every rule at once
        top = np.minimum(allowed, MAX_SPEED)                        # the PID asks for more than it is allowed
        gain = {name: float(top[idx].max() - top[centre])
                for name, idx in (("in view", in_view), ("any", list(range(len(DEPARTURES)))))}
        gains.append((gain["in view"], gain["any"]))
        table.append([k, f"{v:.2f}", f"{w:+.2f}"] + [
            "/".join(f"{x:.2f}" if np.isfinite(x) else "inf" for x in lim[:, j]) for j in range(len(DEPARTURES))]
            + [f"{gain['in view']:.2f}", f"{gain['any']:.2f}"])
    gains = np.array(gains).reshape(-1, 2)
    n = len(gains)
    summary = (f"Seed {args.seed}, frames 0–{args.until}, pid+scan: **{n}** held frames (the PID's forward speed "
               f"limited below its command). Some turn rate's arc allows ≥ 0.1 m/s faster in "
               f"**{int((gains[:, 0] >= 0.1).sum()) if n else 0}** of them keeping the target in view (|δ| ≤ 0.45 rad/s), "
               f"**{int((gains[:, 1] >= 0.1).sum()) if n else 0}** with any departure up to ±1 rad/s; median gain "
               f"{np.median(gains[:, 0]) if n else 0:.2f} / {np.median(gains[:, 1]) if n else 0:.2f} m/s.\n\n"
               "Each cell: path check / walkers / depth + scan limit (m/s) along the arc at w + δ.\n\n")
    text = summary + markdown_table(["frame", "v (held)", "PID w"] + [f"δ {d:+.1f}" for d in DEPARTURES]
                                    + ["gain in view", "gain any"], table) + "\n"
    print(text)
    save_tagged("follow_hold_limits", args.tag, "Held by somebody: the safety rules' limits over turn rates",
                text, False, time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
