"""Seed 000 on ``crowd`` with 10 people over many scenario seeds: issue 4's MOTA ≥ 0.90 target.

One seed of a 10-person crowd is a handful of encounters; whether the tracker meets the target
depends on which ones the seed deals (MOTA ranges over ~0.80–0.94 between seeds with the same
code). So this renders ``crowd`` (2 cameras in opposite corners of the 10 × 8 m hall, facing each other;
640×480, 80 frames at 10 frames/s) for several seeds, tracks each with the ellipsoid tracker's
default preset and colour foreground through :func:`worldtrack.experiment.run_scenario` (gate
0.5 m; people less than 20 % visible in every camera are neither required nor forbidden), and
reports per seed and overall:
MOTA, IDF1, false positives, misses, ID switches, mean position error — and what the errors are
(:func:`worldtrack.eval.error_causes`, 1 m): false positives that are ghosts (no person within 1 m:
a track left on a wall or in a corner), duplicates or displaced; misses with no track near, under a
track that is somebody else's (two people close together), or displaced. A second table counts
misses and false positives by how many cameras see the place: where only one does, a person's
distance along its line of sight rests on their height alone.

Usage::

    .venv/bin/python benchmarks/crowd_seeds.py                    # seeds 0-79, ~10 min
    .venv/bin/python benchmarks/crowd_seeds.py --seeds 0-9        # ~1.5 min
    .venv/bin/python benchmarks/crowd_seeds.py --quick            # smoke run: 2 seeds, 40 frames
    .venv/bin/python benchmarks/crowd_seeds.py --seeds 0 1 --set rescue.gain=0.1 --quick
    .venv/bin/python benchmarks/crowd_seeds.py --texture-ncc 0     # the foreground's texture test on

Writes ``benchmarks/results/crowd_seeds.md`` (not with ``--quick``, ``--set`` or ``--texture-ncc``).
"""

from __future__ import annotations

import argparse
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table, render_images, save_result, setting_value  # noqa: E402

from worldtrack.eval import CAUSES, error_causes, errors_by_views, evaluate_detailed  # noqa: E402
from worldtrack.experiment import run_scenario  # noqa: E402
from worldtrack.synth import make_scenario  # noqa: E402

SIZE = (640, 480)
FRAMES = 80
PEOPLE = 10
#: Seeds 0 … SEEDS − 1 by default: ten seeds' mean still moves by ±0.02 with the seeds dealt.
SEEDS = 80
GATE_M = 0.5
TARGET_MOTA = 0.90


def render_seed(seed: int, frames: int, people: int, cameras: int = 2) -> tuple:
    """(scenario, its rendered frames, seconds it took) of one seed of ``crowd`` at :data:`SIZE`."""
    sc = make_scenario("crowd", size=SIZE, frames=frames, seed=seed, people=people, cameras=cameras)
    t0 = time.perf_counter()
    bundles = render_images(sc)
    return sc, bundles, time.perf_counter() - t0


def run_seed(seed: int, frames: int, people: int, options: dict, texture_ncc: float | None = None,
             cameras: int = 2, rendered: tuple | None = None, init_from_gt: bool = False) -> dict:
    sc, bundles, render_s = rendered or render_seed(seed, frames, people, cameras)
    r = run_scenario(sc, bundles=bundles, foreground="colour", gate=GATE_M, shadow_texture_ncc=texture_ncc,
                     init_from_gt=init_from_gt, **options)
    m = r.metrics
    pairs = evaluate_detailed(r.gt, r.pred, gate=GATE_M).pairs
    causes = error_causes(r.gt, r.pred, pairs, near=1.0)
    views = errors_by_views(r.gt, r.pred, pairs, sc.scene.cameras.values())
    # Issue 37: everyone in view at frame 0 is tracked from frame 0 (a pair within the gate then).
    at_start = np.unique(r.gt.id[r.gt.frame == 0])
    tracked_at_start = np.unique(pairs["gt_id"][pairs["frame"] == 0])
    return {"seed": seed, "mota": m["mota"], "idf1": m["idf1"], "hota": m["hota"], "fp": m["num_false_positives"],
            "miss": m["num_misses"], "switches": m["num_switches"], "error": r.errors.mean_m,
            "causes": causes, "views": views, "fps": r.frames / max(r.seconds, 1e-9), "render_s": render_s,
            "start": (int(np.isin(at_start, tracked_at_start).sum()), len(at_start)),
            # Issue 37's "tracks held": people tracked (within the gate) in >= 80 % of the frames they
            # are scored in — motmetrics' "mostly tracked" — out of the people scored.
            "held": (m["mostly_tracked"], m["num_unique_objects"]), "tracks": len(r.pred_all) / max(r.frames, 1),
            "tables": (r.gt_all, r.pred_all)}


def views_table(by_views: dict[int, Counter]) -> str:
    """All seeds' person rows, misses, track rows and false positives by how many cameras see the
    place (feet and a 1.6 m head in the image, :func:`worldtrack.eval.errors_by_views`)."""
    rows = [[v, c["people"], c["misses"], f"{c['misses'] / max(c['people'], 1):.1%}", c["tracks"],
             c["false positives"], f"{c['false positives'] / max(c['tracks'], 1):.1%}"]
            for v, c in sorted(by_views.items())]
    return ("By the number of cameras that see the place (people by their true place, tracks by "
            "theirs), all seeds:\n\n"
            + markdown_table(["cameras", "person rows", "misses", "miss rate", "track rows", "false positives",
                              "false-positive rate"], rows))


def _seed_list(text: str) -> list[int]:
    """``"7"`` → [7]; ``"0-79"`` → [0, …, 79]."""
    first, _, last = text.partition("-")
    try:
        return list(range(int(first), int(last or first) + 1))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a seed or a range like 0-79, got {text!r}") from None


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--seeds", type=_seed_list, nargs="+", default=None,
                   help="seeds and ranges, e.g. 0-9 or 3 5 (default 0-79; 0 1 with --quick)")
    p.add_argument("--frames", type=int, default=None, help=f"default {FRAMES} (40 with --quick)")
    p.add_argument("--people", type=int, default=PEOPLE)
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="an ellipsoid setting by dotted path (e.g. rescue.gain=0.1); results are then only printed")
    p.add_argument("--texture-ncc", type=float, default=None,
                   help="the foreground's texture test of shadow-like pixels (off by default); results are then only printed")
    p.add_argument("--quick", action="store_true",
                   help="a smoke run (2 seeds, 40 frames unless given); prints only, writes no results file")
    args = p.parse_args(argv)
    args.seeds = ([0, 1] if args.quick else list(range(SEEDS))) if args.seeds is None else sum(args.seeds, [])
    if args.frames is None:
        args.frames = 40 if args.quick else FRAMES
    options = {k: setting_value(v) for k, v in (s.split("=", 1) for s in args.set)}
    t0 = time.perf_counter()
    rows, total, by_views = [], Counter(), {}
    started = np.zeros(2, int)  # people in view at frame 0 tracked then, and in view
    for seed in args.seeds:
        r = run_seed(seed, args.frames, args.people, options, args.texture_ncc)
        total += r["causes"]
        started += r["start"]
        for v, counts in r["views"].items():
            by_views.setdefault(v, Counter()).update(counts)
        rows.append([seed, r["mota"], r["idf1"], r["hota"], r["fp"], r["miss"], r["switches"], r["error"]]
                    + [r["causes"][c] for c in CAUSES] + [f"{r['start'][0]} of {r['start'][1]}", r["fps"]])
        print(f"seed {seed}: MOTA {r['mota']:.3f} (fp {r['fp']}, miss {r['miss']}, switches {r['switches']}; "
              f"{r['start'][0]} of {r['start'][1]} tracked at frame 0); "
              f"rendered in {r['render_s']:.0f} s", file=sys.stderr, flush=True)
    motas = np.array([row[1] for row in rows])
    headers = (["seed", "MOTA", "IDF1", "HOTA", "false positives", "misses", "ID switches", "mean error m"]
               + list(CAUSES) + ["tracked at frame 0", "frames/s (step)"])
    summary = (f"MOTA over {len(motas)} seeds: mean **{motas.mean():.3f}**, median {np.median(motas):.3f}, "
               f"min {motas.min():.3f}, max {motas.max():.3f}; {int((motas >= TARGET_MOTA).sum())} of "
               f"{len(motas)} seeds ≥ {TARGET_MOTA} (target); people in view at frame 0 tracked at frame 0: "
               f"{started[0]} of {started[1]}. Errors by cause, all seeds: "
               + ", ".join(f"{c} {total[c]}" for c in CAUSES) + ".")
    text = (f"`crowd`, {args.people} people, 2 cameras, {SIZE[0]}x{SIZE[1]}, {args.frames} frames; ellipsoid "
            f"default preset{', options ' + str(options) if options else ''}, colour foreground"
            f"{'' if args.texture_ncc is None else f' with the texture test at NCC <= {args.texture_ncc}'}, gate {GATE_M} m.\n\n"
            f"{markdown_table(headers, rows)}\n\n{summary}\n\n{views_table(by_views)}\n")
    print(text)
    save_result("crowd_seeds", "Ellipsoid tracker (seed 000) on a 10-person crowd over scenario seeds", text,
                args.quick or bool(options) or args.texture_ncc is not None, time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
