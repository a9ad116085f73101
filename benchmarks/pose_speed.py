"""Seed 003 speed: ms per frame of the pose trackers at 640×480 on one core.

Times ``step`` on pre-rendered frames (rendering not counted): the face tracker (PF1LM10 as
worldtrack runs it, and as the paper does: every template point ranked in the particle filter)
and the upper body (PF1LM15, 1500 candidates per cascade stage). Each is run ``--repeats`` times
over the same frames; the table gives the min and median of the runs' median ms per frame, and
the ratio to one MOG2 apply at 640×480 measured in the same run (before and after). Targets: face
≤ 20 ms, body ≤ 80 ms (paper: 45 ms face PF1LM10, 228 ms body PF1LM15 on real video).

    .venv/bin/python benchmarks/pose_speed.py
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table, mog2_apply_time, save_result  # noqa: E402

from worldtrack.pose import RigidTracker, TrackerConfig  # noqa: E402
from worldtrack.pose.body_tracker import BodyConfig, BodyTracker  # noqa: E402
from worldtrack.synth.faces import face_model, face_sequence, make_face  # noqa: E402
from worldtrack.synth.upper_body import body_sequence  # noqa: E402


def per_frame_ms(make, frames, step) -> float:
    tr = make()
    times = []
    for f in frames[1:]:
        t0 = time.perf_counter()
        step(tr, f)
        times.append(1000 * (time.perf_counter() - t0))
    return statistics.median(times[2:])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=30)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args()
    if a.quick:
        a.frames, a.repeats = 10, 1
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[-1]})
    t_start = time.time()
    face = make_face(4)
    fseq = face_sequence(face, "sim1", seed=300, n_frames=a.frames)
    fframes = list(fseq.frames())
    bseq = body_sequence(3, n_frames=a.frames)
    bframes = [bseq.render(k) for k in range(a.frames)]
    model = face_model(face)
    cases = {
        "face PF1LM10 (worldtrack default)": (lambda: RigidTracker(model, fseq.intr, fframes[0].R, fframes[0].t),
                                              fframes, lambda tr, f: tr.step(f.image), 20),
        "face PF1LM10 (paper: all points, random walk)": (
            lambda: RigidTracker(model, fseq.intr, fframes[0].R, fframes[0].t,
                                 TrackerConfig(motion="none", pf_points=None)), fframes, lambda tr, f: tr.step(f.image), 20),
        "body PF1LM15 (cascade + joint LM)": (lambda: BodyTracker(bseq.true_model, bseq.intr, bframes[0].params),
                                              bframes, lambda tr, f: tr.step(f.image, f.depth), 80),
    }
    mog2 = [1000 * mog2_apply_time(640, 480)]
    rows = []
    for name, (make, frames, step, target) in cases.items():
        runs = [per_frame_ms(make, frames, step) for _ in range(a.repeats)]
        rows.append([name, f"{min(runs):.1f}", f"{statistics.median(runs):.1f}", target])
        print(name, [round(r, 1) for r in runs], file=sys.stderr, flush=True)
    mog2.append(1000 * mog2_apply_time(640, 480))
    ref = statistics.mean(mog2)
    for r in rows:
        r.append(f"{float(r[2]) / ref:.1f}")
    text = (f"{a.repeats} runs of {a.frames - 3} timed frames each at 640×480, one core. Reference in this run: one "
            f"MOG2 apply at 640×480 = {mog2[0]:.2f} ms before, {mog2[1]:.2f} ms after.\n\n"
            + markdown_table(["tracker", "min ms/frame", "median ms/frame", "target ms", "median / MOG2"], rows))
    print(text)
    save_result("pose_speed", "Seed 003: pose tracking speed", text, a.quick, time.time() - t_start)


if __name__ == "__main__":
    main()
