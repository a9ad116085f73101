"""Ellipsoid (seed 000) vs particle filter (seed 004) vs the blobs baseline on the same rendered frames.

Question (issue 5's acceptance): is the ellipsoid tracker ahead of the tracking-by-detection
baseline (MOG2 blobs + Stone Soup) on MOTA in every occlusion scenario — and at what cost in
speed and memory?

Every scenario is rendered once at 320×240 (seed 0, each scenario's natural length) and the three
trackers, each with its default preset and the default foreground (colour difference against the
scenario's background plate; the blobs baseline runs its own MOG2 started from that plate), track
the same frames through ``worldtrack.experiment.run_scenario`` (gate 0.5 m; people less than 20 %
visible in every camera are neither required nor forbidden). Per scenario and method: MOTA, IDF1,
ID switches, mean position error of matched pairs, frames/s of ``tracker.step`` alone, and peak
memory.

Peak memory is measured in a second pass, so that it does not slow the timed one: the tracker is
built and stepped over all frames under ``tracemalloc``, which started after the frames were
rendered; the figure is the peak of traced allocations above the start (Python objects and NumPy
arrays). Memory that OpenCV (the MOG2 model, morphology) and Numba allocate outside Python's
allocator is not seen by tracemalloc.

Scenarios (cameras): ``two-crossing`` with ``passing="image"`` and ``"close"`` (2: one person
passes behind the other in camera 1; they pass 0.5 m apart), ``crowd`` with 5, 10, 20 walkers (2
corner cameras of a 10 × 8 m hall with pillars and a table), ``desk-occlusion`` (1: a desk hides
the feet), ``entry`` (1: pairs entering side by side through a backlit door) — the occlusion
scenarios — and ``static-grid`` (1 person, nothing in front of them) as a control without
occlusion. 640×480 would take about 4 times as long to render and track, so 320×240 keeps the
whole run at about 2.5 minutes.

Run: ``.venv/bin/python benchmarks/compare_methods.py [--quick]``. Writes
``benchmarks/results/compare_methods.md``. ``--quick`` (a smoke run, prints only): two scenarios,
60 frames.
"""

from __future__ import annotations

import argparse
import sys
import time
import tracemalloc
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table, render_images, save_result  # noqa: E402

from worldtrack.experiment import bundle_frames, run_scenario, step_tracker, synthetic_threshold, synthetic_tracker  # noqa: E402
from worldtrack.trackers.base import Frame  # noqa: E402
from worldtrack.foreground import make_foregrounds  # noqa: E402
from worldtrack.synth import make_scenario  # noqa: E402
from worldtrack.trackers import METHODS, make_tracker, method_shadow_test  # noqa: E402

SIZE = (320, 240)
SEED = 0
GATE_M = 0.5
FOREGROUND = "colour"

#: (label, scenario, parameters, occlusion scenario?)
SCENARIOS = [
    ("two-crossing (image)", "two-crossing", {"passing": "image"}, True),
    ("two-crossing (close)", "two-crossing", {"passing": "close"}, True),
    ("crowd 5", "crowd", {"people": 5}, True),
    ("crowd 10", "crowd", {"people": 10}, True),
    ("crowd 20", "crowd", {"people": 20}, True),
    ("desk-occlusion", "desk-occlusion", {}, True),
    ("entry", "entry", {}, True),
    ("static-grid (control)", "static-grid", {"camera": "cam1"}, False),
]
QUICK = ["two-crossing (image)", "crowd 5"]


def peak_memory_mb(scenario, bundles, method: str) -> float:
    """Peak traced allocation (MB) of building ``method``'s tracker and stepping it over ``bundles``."""
    tracemalloc.start()
    base = tracemalloc.get_traced_memory()[0]
    # Not experiment.synthetic_tracker: here ``fgs`` stays referenced while stepping, as it was for the
    # published figures (the blobs baseline does not keep the foreground models; dropping them lowers its peak).
    cams = scenario.camera_ids
    fgs = make_foregrounds(scenario.scene, {c: scenario.background(c) for c in cams}, FOREGROUND,
                           synthetic_threshold(method, FOREGROUND), shadow_test=method_shadow_test(method))
    tracker = make_tracker(method, scenario.scene, fgs)
    for b in bundles:
        tracker.step({c: Frame(b.views[c].image, b.time, b.frame) for c in cams}, b.time)
    peak = tracemalloc.get_traced_memory()[1] - base
    tracemalloc.stop()
    return peak / 2**20


def warm_up(scenario, bundles) -> None:
    """Step every tracker over a few frames, so Numba's compilation (or cache load) is not timed."""
    for method in METHODS:
        step_tracker(synthetic_tracker(scenario, method, foreground=FOREGROUND), bundle_frames(bundles[:5]), row=None)


def compare(label: str, name: str, params: dict, occlusion: bool, frames: int | None) -> list[list]:
    sc = make_scenario(name, size=SIZE, frames=frames, seed=SEED, **params)
    t0 = time.perf_counter()
    bundles = render_images(sc)
    print(f"{label}: {len(bundles)} frames, {len(sc.camera_ids)} camera(s), rendered in "
          f"{time.perf_counter() - t0:.1f} s", file=sys.stderr)
    warm_up(sc, bundles)
    rows = []
    for method in METHODS:
        r = run_scenario(sc, method, foreground=FOREGROUND, gate=GATE_M, bundles=bundles)
        mem = peak_memory_mb(sc, bundles, method)
        m = r.metrics
        rows.append([label, "yes" if occlusion else "no", method, m["mota"], m["idf1"], m["hota"], m["num_switches"],
                     r.errors.mean_m, r.fps, mem])
        print(f"  {method:9s} MOTA {m['mota']:6.3f} IDF1 {m['idf1']:.3f} switches {m['num_switches']:3d} "
              f"error {r.errors.mean_m:.3f} m  {r.fps:6.1f} frames/s  {mem:.1f} MB", file=sys.stderr)
    return rows


def verdict(rows: list[list]) -> str:
    """Is the ellipsoid tracker ahead of blobs on MOTA in every occlusion scenario?"""
    by = {(r[0], r[2]): r for r in rows}
    occl = [r[0] for r in rows if r[1] == "yes" and r[2] == "ellipsoid"]
    ahead = [s for s in occl if by[(s, "ellipsoid")][3] > by[(s, "blobs")][3]]
    behind = [s for s in occl if s not in ahead]
    text = f"Ellipsoid ahead of blobs on MOTA in {len(ahead)} of {len(occl)} occlusion scenarios"
    return text + (f"; not in: {', '.join(behind)}." if behind else ".")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="two scenarios, 60 frames each")
    args = ap.parse_args(argv)
    t_start = time.perf_counter()
    rows = []
    for label, name, params, occlusion in SCENARIOS:
        if args.quick and label not in QUICK:
            continue
        rows += compare(label, name, params, occlusion, 60 if args.quick else None)
    elapsed = time.perf_counter() - t_start
    table = markdown_table(["scenario", "occlusion", "method", "MOTA", "IDF1", "HOTA", "ID switches", "mean error m",
                            "frames/s", "peak memory MB (tracemalloc)"], rows)
    summary = verdict(rows)
    text = (f"{SIZE[0]}×{SIZE[1]}, seed {SEED}, default presets, foreground `{FOREGROUND}` (blobs: its own MOG2), "
            f"gate {GATE_M} m. frames/s: `tracker.step` only. Peak memory: tracemalloc peak while building "
            "the tracker and stepping it over all frames (frames excluded; OpenCV's and Numba's own buffers "
            f"not seen).\n\n{table}\n\n{summary}\n")
    print(text)
    save_result("compare_methods", "Ellipsoid vs particle vs blobs baseline on the same frames", text,
                args.quick, elapsed)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
