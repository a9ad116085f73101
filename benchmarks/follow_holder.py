"""Who holds the lost target's candidate? (closed loop, issue 35; a diagnostic, not a score)

While the target is lost, its true candidate is often held by another person's track, and the
re-identification (:mod:`worldtrack.follow.reid`) does not hand it back. This runs the closed loop
exactly as ``follow_loop.py --follower pid+scan`` does (same scenario, tracker and follower; with
``--cache`` it stores the same records, so follow_loop tabulates them) and logs, frame by frame:

* the frames where the true target's candidate (the candidate nearest it, within 0.5 m) is not the
  target's: who holds it, how long the target has been unseen, RBhat of the candidate against the
  target's templates (``rb_t``), against the holder's own histogram before this frame (``rb_h``),
  and of the holder's histogram against the templates (``rb_th``), the holder's age;
* every candidate another track holds while the target is not found: would the relative test of
  ``FollowConfig.reid_holder_margin`` (``rb_t + margin < rb_h``, unseen longer than the 1.5 s coast)
  take it, and is it the target?

Run: ``.venv/bin/python benchmarks/follow_holder.py --seeds 60,66 [--frames 1500] [--cache DIR]
[--set NAME=VALUE] [--margins 0,0.1,0.2]``. Prints a table per seed (10 min per 1500-frame seed at
load 10-15 on 2 cores).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import follow_loop as fl  # noqa: E402
from common import markdown_table  # noqa: E402
from follow_common import SCENARIO, seed_cached  # noqa: E402
from follow_synth import parse_seeds  # noqa: E402

from worldtrack.errors import InputError  # noqa: E402
from worldtrack.follow import FollowConfig, FollowTracker, PIDFollower  # noqa: E402
from worldtrack.follow.colour import bhattacharyya  # noqa: E402
from worldtrack.follow.loop import run_closed_loop  # noqa: E402
from worldtrack.synth import make_scenario  # noqa: E402

#: s, the tracker's coast (``tracker.COAST_S``): the relative test applies only after it.
COAST_S = 1.5
#: m, the true target's candidate is the nearest candidate within this.
NEAR = 0.5


def run_logged(seed: int, frames: int, settings: dict) -> tuple[dict, list, list]:
    """One closed-loop run (follow_loop's ``run_seed``) with the two logs (module docstring).

    Returns
    -------
    (records as ``follow_loop.run_seed`` returns them, truth rows (dicts), held rows (lists:
    frame, unseen s, holder id, is the truth 0/1, rb_t, rb_h, rb_th))
    """
    tcfg, pset = fl.split_settings(settings)
    sc = make_scenario("follow-target", size=(160, 120), frames=frames, seed=seed, distance=fl.DISTANCE, **SCENARIO)
    pid = fl.make_follower("pid+scan", sc.scene, pset)
    tracker = FollowTracker(FollowConfig.preset("default", **tcfg), sc.scene)
    stash: dict = {}
    step_with = tracker.step_with

    def logged_step(obs, t):
        o = tracker.others
        stash.update(obs=obs, ids=o.ids.copy(), hist=o.hist.copy(), born=o.born.copy(), last_seen=tracker.last_seen)
        return step_with(obs, t)

    tracker.step_with = logged_step
    blocked, truth_rows, held_rows = [], [], []

    def on_frame(bundle, s, command):
        k = len(blocked)
        blocked.append(pid.blocked)
        gt = {r["id"]: np.array([r["x"], r["y"]]) for r in bundle.gt}
        if "obs" not in stash or 1 not in gt or len(stash["obs"].candidates) == 0:
            return
        obs = stash["obs"]
        d = np.hypot(*(obs.candidates.xy - gt[1]).T)
        i = int(np.argmin(d))
        own = {int(h): j for j, h in enumerate(stash["ids"])}

        def holder(m):
            j = own[int(s.owner[m])]
            return (float(bhattacharyya(obs.hists[m:m + 1], stash["hist"][j:j + 1])[0, 0]),
                    float(tracker.templates.rbhat(stash["hist"][j:j + 1])[0]), j)

        if not s.found:
            for m in np.flatnonzero(s.owner > 1):
                if int(s.owner[m]) in own:
                    rb_h, rb_th, _ = holder(m)
                    held_rows.append([k, float(s.t - stash["last_seen"]), int(s.owner[m]), int(m == i and d[i] <= NEAR),
                                      float(s.RBhat[m]), rb_h, rb_th])
        if d[i] > NEAR or s.chosen == i:
            return
        row = dict(frame=k, found=bool(s.found), owner=int(s.owner[i]), rb_t=float(s.RBhat[i]),
                   unseen=float(s.t - stash["last_seen"]) if not s.found else 0.0)
        if int(s.owner[i]) in own:
            rb_h, rb_th, j = holder(i)
            row.update(rb_h=rb_h, rb_th=rb_th, age=float(s.t - stash["born"][j]))
        truth_rows.append(row)

    result = run_closed_loop(sc, tracker=tracker, follower=pid, on_frame=on_frame, side_scan=True)
    blocked = np.array(blocked)
    held = blocked.copy()
    for j in np.flatnonzero(blocked):
        held[j:j + int(fl.RECOVER_S * sc.fps) + 1] = True
    rec = {"within": np.abs(result.distance - fl.DISTANCE) <= fl.TOLERANCE, "free": ~held, "blocked": blocked,
           "result": result}
    return rec, truth_rows, held_rows


def summarise(truth_rows: list, held_rows: list, margins: list[float]) -> list:
    """One table row: frames with the truth's candidate held by another track (and of them with a
    holder histogram), medians of rb_t, rb_h, rb_th and the holder's age, then per margin the frames
    where the relative test fires on the truth / on somebody else."""
    held_truth = [r for r in truth_rows if r["owner"] > 1]
    with_h = [r for r in held_truth if "rb_h" in r]
    med = [f"{np.median([r[k] for r in with_h]):.2f}" if with_h else "-" for k in ("rb_t", "rb_h", "rb_th", "age")]
    h = np.array(held_rows, float).reshape(-1, 7)
    fires = []
    for m in margins:
        f = (h[:, 4] + m < h[:, 5]) & (h[:, 1] > COAST_S)
        fires.append(f"{int((f & (h[:, 3] == 1)).sum())} / {int((f & (h[:, 3] == 0)).sum())}")
    return [len(held_truth), len(with_h), *med, *fires]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", default="60,66")
    ap.add_argument("--frames", type=int, default=1500)
    ap.add_argument("--cache", help="store the run's records where follow_loop.py --cache finds them")
    ap.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help="as in follow_loop.py")
    ap.add_argument("--margins", default="0,0.1,0.2", help="margins of the relative test, comma-separated")
    args = ap.parse_args(argv)
    try:
        settings = {k: float(v) for k, v in (item.split("=", 1) for item in args.set)}
        margins = [float(m) for m in args.margins.split(",")]
        tracker_settings, pid_settings = fl.split_settings(settings)
        FollowConfig.preset("default", **tracker_settings)
        PIDFollower(**pid_settings)
        seeds = parse_seeds(args.seeds)
    except (ValueError, InputError, TypeError) as err:
        print(f"follow_holder: {err}", file=sys.stderr)
        return 2
    key = "".join(f"-{k}={v:g}" for k, v in sorted(settings.items()))
    rows = []
    for seed in seeds:
        logs = {}

        def compute(seed=seed):
            rec, logs["truth"], logs["held"] = run_logged(seed, args.frames, settings)
            return rec

        rec = seed_cached(args.cache, f"loop-pid+scan{key}-{seed}-{args.frames}", compute)
        if "truth" not in logs:
            print(f"follow_holder: seed {seed} was in the cache: run without --cache for the logs", file=sys.stderr)
            continue
        rows.append([seed, f"{rec['within'].mean():.3f}", *summarise(logs["truth"], logs["held"], margins)])
    print(markdown_table(["seed", "within ±0.3 m", "frames truth held by another", "of them with holder histogram",
                          "median rb_t", "median rb_h", "median rb_th", "median holder age s",
                          *[f"margin {m:g} fires truth / other" for m in margins]], rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
