"""Semi-real test of the decision (seed 001): PETS 2009 S2.L1 with known white-balance jumps.

Question: on real clothes and real crowds, how often does the colour + position decision pick the
right person, as the camera's white balance jumps more and more — with and without undoing the
gains?

PETS 2009 S2.L1 View_001 (795 frames at 7 fps; a fixed camera, no depth): every person of Milan's
ground truth visible for at least 10 s is taken as the target in turn (19 people) and followed from
the first frame they are visible to their last. The candidates are the ground-truth people
themselves (their feet back-projected to the floor, their boxes as silhouettes); a person more
than half covered by nearer boxes is no candidate that frame (no detector would see them) — the
detection stage is not under test. Every frame is re-recorded with known R/B gains: every 1–2 s
the gains jump by exactly ``size`` steps (|ΔR| + |ΔB|, split at random, random signs, each within
512 ± 300), three jump sequences (seeds 0, 1, 2) per size. Labels per frame: A the target chosen,
B someone else, C nobody though the target was a candidate; precision A/(A+B), recall A/(A+C),
pooled over targets and jump sequences.

Run: ``.venv/bin/python benchmarks/follow_pets.py [--quick] [--set NAME=VALUE]`` (skips with one line when
the data is absent; ``--set`` adds a row of the default with that setting). Writes ``benchmarks/results/follow_pets.md``. About 5 minutes.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table  # noqa: E402
from follow_common import (PETS, follow_pets, gain_jumps, load_pets, pets_observations, pets_targets,  # noqa: E402
                           save_tagged)
from follow_synth import set_variant  # noqa: E402

from worldtrack.eval.follow import counts  # noqa: E402
from worldtrack.errors import InputError  # noqa: E402
from worldtrack.follow import FollowConfig  # noqa: E402

SIZES = (0, 100, 200, 300, 400)
VARIANTS = {
    "colour only": ("colour-only", {}),
    "position only": ("position-only", {}),
    "the paper's D (gains not undone)": ("paper", {}),
    "the paper's D + gain undo": ("paper+undo", {}),
    "worldtrack default (gains undone)": ("default", {}),
    "worldtrack default, gains not undone": ("default", {"normalise": "none"}),
}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="first 200 frames, one jump sequence (prints only)")
    ap.add_argument("--sizes", default=",".join(map(str, SIZES)), help="jump sizes in gain steps (default 0-400 by 100)")
    ap.add_argument("--jump-seeds", default="0,1,2", help="seeds of the jump sequences (default 0,1,2)")
    ap.add_argument("--default-only", action="store_true", help="only the two worldtrack default rows")
    ap.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                    help="also a row of the worldtrack default with this FollowConfig setting (a number, e.g. "
                         "reid_any_track_after=inf), on the same observations; repeatable")
    args = ap.parse_args(argv)
    try:
        extra = set_variant(args.set)
    except (ValueError, InputError) as err:
        print(f"follow_pets: --set: {err}", file=sys.stderr)
        return 2
    variants = {k: v for k, v in VARIANTS.items() if k.startswith("worldtrack")} if args.default_only else dict(VARIANTS)
    variants.update(extra)
    t0 = time.perf_counter()
    pets = load_pets(200 if args.quick else None)
    if pets is None:
        print(f"follow_pets: skipped — {PETS} not found")
        return 0
    targets = pets_targets(pets, 20 if args.quick else 70)
    sizes = [int(v) for v in args.sizes.split(",")]
    jump_seeds = (0,) if args.quick else tuple(int(v) for v in args.jump_seeds.split(","))
    results = {name: {} for name in variants}
    for size in sizes:
        for js in jump_seeds:
            gains = gain_jumps(np.random.default_rng(js), pets.n, 7.0, float(size))
            cache = {}
            for name, (preset, over) in variants.items():
                cfg = FollowConfig.preset(preset, **over)
                key = (cfg.normalise, cfg.grey_bins)
                if key not in cache:
                    cache[key] = pets_observations(pets, cfg, gains)
                labels = np.concatenate([follow_pets(pets, tid, cfg, cache[key]) for tid in targets])
                results[name].setdefault(size, []).append(labels)
        line = ", ".join(f"{name}: {counts(np.concatenate(r[size])).precision:.3f}/"
                         f"{counts(np.concatenate(r[size])).recall:.3f}" for name, r in results.items())
        print(f"jump {size} steps — {line} ({time.perf_counter() - t0:.0f} s)", file=sys.stderr, flush=True)
    rows = []
    for name, r in results.items():
        cells = []
        for size in sizes:
            c = counts(np.concatenate(r[size]))
            cells.append(f"{c.precision:.3f} / {c.recall:.3f}")
        rows.append([name, *cells])
    frames = len(results["worldtrack default (gains undone)"][sizes[0]][0])
    table = markdown_table(["variant (precision / recall)", *[f"jumps of {s} steps" for s in sizes]], rows)
    text = (f"{len(targets)} targets, {frames} target-frames per jump sequence, {len(jump_seeds)} jump sequence(s) per "
            f"size; candidates = the visible ground-truth people. Gains jump every 1–2 s by exactly the stated "
            f"|ΔR| + |ΔB|.\n\n{table}\n")
    print(text)
    save_tagged("follow_pets", ("_default" if args.default_only else "") + ("_set" if extra else ""),
                "Following on PETS 2009 S2.L1 with white-balance jumps (seed 001)", text, args.quick, time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
