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


def per_frame_ms(make, frames, step) -> tuple[float, float]:
    """Median wall-clock and CPU (process) ms per frame, the first frames (compilation) left out; on a
    core shared with other work the CPU time leaves out the time the process waited for the core."""
    tr = make()
    wall, cpu = [], []
    for f in frames[1:]:
        t0, c0 = time.perf_counter(), time.process_time()
        step(tr, f)
        wall.append(1000 * (time.perf_counter() - t0))
        cpu.append(1000 * (time.process_time() - c0))
    return statistics.median(wall[2:]), statistics.median(cpu[2:])


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
        "face PF1LM10 (paper: extrema only, all in the PF, random walk)": (
            lambda: RigidTracker(model, fseq.intr, fframes[0].R, fframes[0].t,
                                 TrackerConfig(motion="none", pf_points=None, edge_points=False)), fframes, lambda tr, f: tr.step(f.image), 20),
        "body PF1LM15 (cascade + joint LM)": (lambda: BodyTracker(bseq.true_model, bseq.intr, bframes[0].params),
                                              bframes, lambda tr, f: tr.step(f.image, f.depth), 80),
    }
    mog2 = [1000 * mog2_apply_time(640, 480)]
    rows = []
    for name, (make, frames, step, target) in cases.items():
        runs = [per_frame_ms(make, frames, step) for _ in range(a.repeats)]
        wall, cpu = [r[0] for r in runs], [r[1] for r in runs]
        rows.append([name, f"{min(wall):.1f}", f"{statistics.median(wall):.1f}", f"{min(cpu):.1f}",
                     f"{statistics.median(cpu):.1f}", target])
        print(name, "wall", [round(r, 1) for r in wall], "cpu", [round(r, 1) for r in cpu], file=sys.stderr, flush=True)
    mog2.append(1000 * mog2_apply_time(640, 480))
    ref = statistics.mean(mog2)
    for r in rows:
        r.append(f"{float(r[2]) / ref:.1f}")
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    text = (f"{a.repeats} runs of {a.frames - 3} timed frames each at 640×480, one core. Reference in this run: one "
            f"MOG2 apply at 640×480 = {mog2[0]:.2f} ms before, {mog2[1]:.2f} ms after; load average at the end "
            f"{load:.1f} on {os.cpu_count()} cores. Wall: time.perf_counter; CPU: time.process_time (leaves out the "
            f"time spent waiting for a shared core).\n\n"
            + markdown_table(["tracker", "min wall ms/frame", "median wall ms/frame", "min CPU ms/frame",
                              "median CPU ms/frame", "target ms", "median wall / MOG2"], rows))
    print(text)
    save_result("pose_speed", "Seed 003: pose tracking speed", text, a.quick, time.time() - t_start)


if __name__ == "__main__":
    main()
