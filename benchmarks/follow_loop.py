"""The closed loop (seed 001): the robot's camera moves by the follower's commands, frame by frame.

Question: does the simulated robot keep the target within ±0.3 m of the set distance (1.8 m) 95 %
of the time, and never drive into anybody or anything?

Each seed's ``follow-target`` sequence (:data:`follow_common.SCENARIO`, 1500 frames at 10 fps,
160×120) is rendered from where the robot is at each frame (:func:`worldtrack.follow.loop.run_closed_loop`):
the default follower, the PID with feed-forward, a unicycle robot (1.6 m/s, 1.5 rad/s, 1.5 m/s²)
with a bumper. The other people were scripted for the scenario's planned robot, not this one, so
they do not make way for it: a person walking into the robot while it stands is counted as a
*contact*, a *collision* only when the robot was driving towards them. The distance is measured
from the camera to the true target. While somebody stands in the robot's path it must wait, so
the fraction is also given without those frames and the 3 s after each (catching up).

Run: ``.venv/bin/python benchmarks/follow_loop.py [--seeds 0-9] [--quick]``. Writes
``benchmarks/results/follow_loop.md``. About 15 minutes.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table  # noqa: E402
from follow_common import SCENARIO, save_tagged, seed_cached  # noqa: E402
from follow_synth import parse_seeds  # noqa: E402

from worldtrack.follow import PIDFollower  # noqa: E402
from worldtrack.follow.planner import LocalPlanner  # noqa: E402
from worldtrack.follow.loop import run_closed_loop  # noqa: E402
from worldtrack.synth import make_scenario  # noqa: E402

DISTANCE = 1.8
TOLERANCE = 0.3
RECOVER_S = 3.0


def run_seed(seed: int, frames: int, size, follower: str = "planner") -> dict:
    sc = make_scenario("follow-target", size=size, frames=frames, seed=seed, distance=DISTANCE, **SCENARIO)
    pid = (LocalPlanner(sc.scene, distance=DISTANCE) if follower == "planner"
           else PIDFollower(distance=DISTANCE, depth_stop=follower == "pid+depth"))
    blocked = []
    result = run_closed_loop(sc, follower=pid, on_frame=lambda b, s, c: blocked.append(pid.blocked))
    blocked = np.array(blocked)
    within = np.abs(result.distance - DISTANCE) <= TOLERANCE
    held = blocked.copy()
    for k in np.flatnonzero(blocked):
        held[k:k + int(RECOVER_S * sc.fps) + 1] = True
    return {"within": within, "free": ~held, "blocked": blocked, "result": result}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", default="0-9")
    ap.add_argument("--frames", type=int, default=1500)
    ap.add_argument("--follower", choices=("pid+depth", "pid", "planner"), default="pid+depth",
                    help="pid+depth: the paper's PID with the depth safety layer (default); pid: the paper's PID; "
                         "planner: the dynamic-window local planner")
    ap.add_argument("--quick", action="store_true", help="dev seed 100, 200 frames (prints only)")
    ap.add_argument("--cache", help="keep each seed's records in this folder (split seeds over processes)")
    ap.add_argument("--tag", default="", help="write results/<name><TAG>.md beside the main table")
    args = ap.parse_args(argv)
    seeds = [100] if args.quick else parse_seeds(args.seeds)
    frames = 200 if args.quick else args.frames
    t0 = time.perf_counter()
    rows, all_within, all_free_within = [], [], []
    totals = {"contacts": 0, "collisions": 0, "bumps": 0}
    causes: dict = {}
    collision_rows = []
    for seed in seeds:
        ts = time.perf_counter()
        s = seed_cached(args.cache, f"loop-{args.follower}-{seed}-{frames}",
                        lambda: run_seed(seed, frames, (160, 120), args.follower))
        r = s["result"]
        err = np.abs(r.distance - DISTANCE)
        all_within.append(s["within"])
        all_free_within.append(s["within"][s["free"]])
        for k in totals:
            totals[k] += getattr(r, k)
        for c in getattr(r, "collision_causes", []):
            causes[c.cause] = causes.get(c.cause, 0) + 1
            collision_rows.append([seed, c.frame, c.person, f"{c.distance:.2f}", f"{c.robot_speed:.2f}",
                                   f"{c.person_speed:.2f}", f"{c.visible:.2f}", "yes" if c.tracked else "no",
                                   "yes" if c.blocked else "no", c.cause])
        rows.append([seed, f"{s['within'].mean():.3f}", f"{s['within'][s['free']].mean():.3f}",
                     f"{s['blocked'].mean():.3f}", f"{np.median(err):.2f}", f"{np.percentile(err, 95):.2f}",
                     f"{err.max():.2f}", f"{r.found.mean():.3f}", r.contacts, r.collisions, r.bumps,
                     f"{r.nearest_person.min():.2f}", f"{r.clearance.min():.2f}"])
        print(f"seed {seed}: within ±{TOLERANCE} m {s['within'].mean():.3f} (free path {s['within'][s['free']].mean():.3f}), "
              f"collisions {r.collisions}, contacts {r.contacts} ({time.perf_counter() - ts:.0f} s)",
              file=sys.stderr, flush=True)
    pooled = np.concatenate(all_within).mean()
    pooled_free = np.concatenate(all_free_within).mean()
    table = markdown_table(["seed", f"within ±{TOLERANCE} m", "same, path free", "robot held (someone in path)",
                            "median |error| m", "95th pct m", "max m", "target found", "contacts",
                            "collisions (robot driving at them)", "bumper stops", "nearest person m",
                            "nearest wall m"], rows)
    text = (f"Follower: {args.follower}. Seeds {', '.join(map(str, seeds))}; {frames} frames at 10 fps, 160x120; "
            f"set distance {DISTANCE} m.\n\n"
            f"- within ±{TOLERANCE} m of the set distance: **{pooled:.3f}** of all frames (target ≥ 0.95); "
            f"{pooled_free:.3f} of the frames when nobody held the robot up (those frames and the {RECOVER_S:g} s "
            f"after left out)\n- collisions (the robot driving at someone within 0.5 m, centre to centre): "
            f"**{totals['collisions']}** frames; contacts of any kind {totals['contacts']}; bumper stops "
            f"{totals['bumps']}\n- collisions by cause: "
            + (", ".join(f"{k} {v}" for k, v in sorted(causes.items())) or "none")
            + f"\n\n{table}\n")
    if collision_rows:
        text += ("\n## Every collision frame\n\nspeeds towards each other (m/s); visible: the person's largest "
                 "visible share in the robot's camera over the last second; tracked: a candidate or track of the "
                 "follower within 0.5 m; held: the path check held the robot.\n\n"
                 + markdown_table(["seed", "frame", "person", "distance m", "robot speed", "person speed", "visible",
                                   "tracked", "held", "cause"], collision_rows) + "\n")
    print(text)
    save_tagged("follow_loop", args.tag, "The closed loop: a simulated robot follows (seed 001)", text, args.quick,
                time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
