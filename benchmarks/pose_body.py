"""Seed 003, 14-DoF upper-body tracking on synthetic RGB-D: Tables 7 and 8 in the paper's layout.

Seven sequences (``worldtrack.synth.upper_body``, no1–no7), 640×480, 30 fps, depth in 5 mm steps
like the paper's simulation; several tracker seeds each. Cells: mean angle (degrees) between the
estimated and the true main axis of each limb, the paper's figure in brackets. ``PFxLM0`` is the
paper's conventional method (the torso → right arm → left arm cascade of particle filters, x
stages); ``PFxLMy`` adds y iterations of the joint 14-DoF LM. Failures: a limb more than 15° off
for 5 frames in a row (the tracker is re-initialised at the true pose; counted). Time: median ms
per frame, this process pinned to one core, beside one MOG2 apply at 640×480 in the same run.

    .venv/bin/python benchmarks/pose_body.py                      # sequences 1-7, seeds 0-2
"""

from __future__ import annotations

import argparse
import os
import shlex
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table, mog2_apply_time, save_result, write_result  # noqa: E402

from worldtrack.pose import FailureRule, axis_angle_deg  # noqa: E402
from worldtrack.pose.body import limb_axes  # noqa: E402
from worldtrack.pose.body_tracker import BodyConfig, BodyTracker  # noqa: E402
from worldtrack.synth.upper_body import body_sequence  # noqa: E402

LIMB_ORDER = ("r_upper_arm", "l_upper_arm", "r_forearm", "l_forearm")
PAPER_LM0 = {1: [[4.340, 3.476, 5.214, 4.170], [3.416, 3.539, 4.183, 3.354], [3.142, 3.378, 4.195, 5.115],
                 [4.557, 4.894, 6.306, 6.764], [3.449, 3.510, 11.433, 4.441], [6.016, 4.121, 21.360, 4.232],
                 [3.910, 5.123, 9.615, 11.832]],
             2: [[1.692, 1.475, 1.609, 1.475], [1.582, 1.553, 1.517, 1.537], [1.330, 1.315, 1.239, 1.457],
                 [1.737, 1.693, 1.662, 1.560], [1.190, 1.496, 1.711, 1.613], [1.242, 1.729, 1.464, 1.702],
                 [1.376, 1.185, 2.149, 1.456]]}
PAPER_LM50 = {1: [[2.627, 1.459, 2.313, 1.188], [1.501, 1.223, 1.254, 0.938], [2.192, 1.335, 2.430, 0.977],
                  [1.757, 1.507, 1.648, 1.133], [1.549, 1.559, 2.055, 1.578], [3.381, 1.349, 9.960, 0.929],
                  [2.279, 1.474, 4.389, 2.188]],
              2: [[1.220, 0.927, 0.818, 0.759], [0.949, 0.999, 0.732, 0.864], [0.974, 0.859, 0.626, 0.614],
                  [1.077, 1.008, 0.772, 0.752], [0.759, 0.951, 0.732, 0.896], [0.884, 0.957, 0.930, 0.766],
                  [0.961, 0.817, 0.914, 0.927]]}


def run(frames, model, intr, stages: int, lm: int, seed: int, depth_weight: str = "fixed") -> dict:
    tr = BodyTracker(model, intr, frames[0].params, BodyConfig(stages=stages, lm_iterations=lm, seed=seed,
                                                               depth_weight=depth_weight))
    rules = {n: FailureRule(15.0, 5) for n in LIMB_ORDER}
    err, ms = [], []
    for f in frames[1:]:
        t0 = time.perf_counter()
        est = tr.step(f.image, f.depth)
        ms.append(1000 * (time.perf_counter() - t0))
        ax = limb_axes(est.params[None], model)
        e = [float(axis_angle_deg(f.axes[n], ax[n][0])) for n in LIMB_ORDER]
        err.append(e)
        if any([rules[n].update(v) for n, v in zip(LIMB_ORDER, e)]):
            tr.reset(f.params)
    return {"err": np.array(err), "ms": ms, "fail": sum(r.failures for r in rules.values())}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sequences", default="1-7")
    ap.add_argument("--seeds", default="0-2")
    ap.add_argument("--frames", type=int, default=60)
    ap.add_argument("--configs", default="PF1LM0,PF1LM15,PF2LM0,PF2LM50")
    ap.add_argument("--tag", default="", help="suffix of the results file name (parallel runs)")
    ap.add_argument("--depth-weight", default="fixed", choices=("fixed", "noise", "kernel", "sandwich"),
                    help="λ fixed (the paper's 0.9) or from the terms' measured noise")
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args()
    rng = lambda s: list(range(int(s.split("-")[0]), int(s.split("-")[1]) + 1)) if "-" in s else [int(s)]
    seqs, seeds, n = rng(a.sequences), rng(a.seeds), a.frames
    if a.quick:
        seqs, seeds, n = seqs[:1], seeds[:1], 15
    configs = [(c, int(c[2]), int(c.split("LM")[1])) for c in a.configs.split(",")]
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[-1]})
    t_start = time.time()
    mog2 = 1000 * mog2_apply_time(640, 480)
    res = {}
    for s in seqs:
        seq = body_sequence(s, n_frames=n)
        frames = [seq.render(k) for k in range(n)]
        for name, st, lm in configs:
            res[(name, s)] = [run(frames, seq.true_model, seq.intr, st, lm, seed, a.depth_weight) for seed in seeds]
            m = np.concatenate([r["err"] for r in res[(name, s)]]).mean(0)
            print(f"no{s} {name}: {np.round(m, 3)} fail {sum(r['fail'] for r in res[(name, s)])}",
                  file=sys.stderr, flush=True)
    out = [f"Sequences no{seqs[0]}–no{seqs[-1]}, {n} frames each at 640×480, tracker seeds {seeds}. "
           f"Reference: one MOG2 apply at 640×480 in this run = {mog2:.1f} ms.\n"]
    head = ["config", "video", "right upper", "left upper", "right lower", "left lower", "failures"]
    rows, summary = [], []
    for name, st, lm in configs:
        paper = PAPER_LM0.get(st) if lm == 0 else PAPER_LM50.get(st) if lm == 50 else None
        for s in seqs:
            m = np.concatenate([r["err"] for r in res[(name, s)]]).mean(0)
            cells = [f"{v:.3f}" + (f" ({paper[s - 1][j]:.3f})" if paper and s <= 7 else "") for j, v in enumerate(m)]
            rows.append([name, f"no{s}", *cells, sum(r["fail"] for r in res[(name, s)])])
        allm = np.array([np.concatenate([r["err"] for r in res[(name, s)]]).mean(0) for s in seqs])
        ms = statistics.median([t for s in seqs for r in res[(name, s)] for t in r["ms"]])
        fails = sum(r["fail"] for s in seqs for r in res[(name, s)])
        summary.append(f"- {name}: worst limb mean over sequences {allm.max():.3f} deg, mean {allm.mean():.3f} deg, "
                       f"{fails} failures, {ms:.0f} ms/frame ({ms / mog2:.1f} x MOG2)")
    out += ["## Tables 7 and 8 — limb-axis error (deg)\n", markdown_table(head, rows), "", "## Summary\n", *summary]
    text = "\n".join(out)
    print(text)
    title = "Seed 003: 14-DoF upper-body tracking (Tables 7 and 8)"
    if not a.tag:
        save_result("pose_body", title, text, a.quick, time.time() - t_start)
    elif not a.quick:                                   # a tagged run: its own file, the real command line
        args = " ".join(shlex.quote(x) for x in sys.argv[1:])
        path = write_result(f"pose_body{a.tag}", title, f"Command: `.venv/bin/python benchmarks/pose_body.py {args}` "
                            f"({time.time() - t_start:.0f} s)\n\n{text}")
        print(f"wrote {path}", file=sys.stderr)


if __name__ == "__main__":
    main()
