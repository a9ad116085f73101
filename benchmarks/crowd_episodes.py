"""Where the 10-person crowd's MOTA is lost: its error rows grouped into episodes, by kind.

:mod:`crowd_seeds` counts misses and false positives row by row; one event (a track slid onto a
neighbour, a person never born) costs many rows. Here each person's consecutive missed frames
and each track's consecutive unmatched frames are one **episode**, named by the cause most of its
rows have (:func:`worldtrack.eval.error_causes`' causes: a miss with no track within 1 m is
"none", one whose nearest track holds somebody else "shared", else "displaced"; a false positive
farther than 1 m from everyone is a "ghost", one near somebody already held a "dup", else
"displaced"). It prints, over the seeds, rows and episodes by kind, the rows in the first 10 frames,
the people in view at frame 0 who were missed from frame 0 on (issue 37: "everyone already in view
at frame 0 is tracked from frame 0") and for how many frames, and each seed's longest episodes.

>>> from worldtrack.io.tracks import TrackTable
>>> gt = TrackTable.from_arrays([0, 1, 2, 0, 1, 2], [1, 1, 1, 2, 2, 2], [0.0] * 3 + [3.0] * 3, [0.0] * 6)
>>> pred = TrackTable.from_arrays([0, 1, 2], [7, 7, 7], [0.1, 0.1, 0.1], [0.0] * 3)
>>> [(e.kind, e.who, e.frames) for e in episodes(gt, pred, {(0, 1): 7, (1, 1): 7, (2, 1): 7})]
[('miss none', 2, [0, 1, 2])]

Usage::

    .venv/bin/python benchmarks/crowd_episodes.py --seeds 20-39
    .venv/bin/python benchmarks/crowd_episodes.py --seeds 20-22 --set births.people_occlude=true

Prints only (no results file).
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from pathlib import Path
from typing import NamedTuple

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import setting_value  # noqa: E402
from crowd_seeds import FRAMES, PEOPLE, _seed_list, run_seed  # noqa: E402

from worldtrack.eval import evaluate_detailed  # noqa: E402
from worldtrack.eval.mot import drop_ignored  # noqa: E402
from worldtrack.experiment import visibility  # noqa: E402

NEAR_M = 1.0
EARLY = 10


class Episode(NamedTuple):
    """Consecutive error rows of one person (a miss) or one track (a false positive)."""

    kind: str
    who: int
    frames: list[int]


def _runs(table, ids_frames: set, kind: str, near_kind) -> list[Episode]:
    """Episodes of ``table``'s rows whose (frame, id) is not in ``ids_frames``; ``near_kind(row)``
    names each row's cause."""
    out = []
    for who in np.unique(table.id).tolist():
        rows = np.flatnonzero(table.id == who)
        run: list[tuple[int, str]] = []
        for r in rows[np.argsort(table.frame[rows])].tolist() + [None]:
            if r is not None and (int(table.frame[r]), who) not in ids_frames:
                run.append((int(table.frame[r]), near_kind(r)))
                continue
            if run:
                name = Counter(k for _, k in run).most_common(1)[0][0]
                out.append(Episode(f"{kind} {name}", who, [f for f, _ in run]))
            run = []
    return out


def episodes(gt, pred, matched: dict) -> list[Episode]:
    """Miss and false-positive episodes of scored tables ``gt``, ``pred`` with ``matched``
    {(frame, person id): track id}; longest first."""
    held = {(f, t) for (f, _), t in matched.items()}

    def nearest(table, r, other):
        here = np.flatnonzero(other.frame == table.frame[r])
        d = np.hypot(other.x[here] - table.x[r], other.y[here] - table.y[r])
        return (None, np.inf) if not len(d) else (int(other.id[here][np.argmin(d)]), float(d.min()))

    def miss_kind(r):
        track, d = nearest(gt, r, pred)
        return "none" if d > NEAR_M else ("shared" if (int(gt.frame[r]), track) in held else "displaced")

    def fp_kind(r):
        person, d = nearest(pred, r, gt)
        return "ghost" if d > NEAR_M else ("dup" if (int(pred.frame[r]), person) in matched else "displaced")

    out = _runs(gt, set(matched), "miss", miss_kind) + _runs(pred, held, "fp", fp_kind)
    return sorted(out, key=lambda e: -len(e.frames))


def seed_episodes(seed: int, options: dict, frames: int = FRAMES) -> tuple[list[Episode], list[str], int, int]:
    """One seed: its episodes, the people missed from frame 0 (one line each), switches and rows."""
    r = run_seed(seed, frames, PEOPLE, options)
    gt_all, pred_all = r["tables"]
    gt, pred = drop_ignored(gt_all, pred_all, visibility(gt_all) < 0.2, 0.5)
    pairs = evaluate_detailed(gt, pred, 0.5).pairs
    matched = {(int(f), int(g)): int(t) for f, g, t in zip(pairs["frame"], pairs["gt_id"], pairs["pred_id"])}
    eps = episodes(gt, pred, matched)
    late = []
    for e in eps:
        if e.kind.startswith("miss") and e.frames[0] == 0:
            r0 = np.flatnonzero((gt.frame == 0) & (gt.id == e.who))[0]
            vis = "/".join(f"{gt.column(c)[r0]:.2f}" for c in gt.columns if c.startswith("vis_"))
            late.append(f"seed {seed} person {e.who}: {len(e.frames)} frames ({e.kind}), height "
                        f"{gt.column('height')[r0]:.2f} m, visible {vis}")
    return eps, late, int(pairs["switch"].sum()), len(gt)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--seeds", type=_seed_list, nargs="+", required=True, help="seeds and ranges, e.g. 20-39")
    p.add_argument("--frames", type=int, default=FRAMES)
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="an ellipsoid setting by dotted path")
    p.add_argument("--longest", type=int, default=3, help="episodes printed per seed (default 3)")
    args = p.parse_args(argv)
    options = {k: setting_value(v) for k, v in (s.split("=", 1) for s in args.set)}
    rows, count, early, lates, switches, total = Counter(), Counter(), Counter(), [], 0, 0
    for seed in sum(args.seeds, []):
        eps, late, sw, n = seed_episodes(seed, options, args.frames)
        switches, total, lates = switches + sw, total + n, lates + late
        for e in eps:
            rows[e.kind] += len(e.frames)
            count[e.kind] += 1
            early[e.kind] += sum(f < EARLY for f in e.frames)
        lost = sum(len(e.frames) for e in eps) + sw
        print(f"seed {seed}: MOTA {1 - lost / n:.3f}; longest: " + "; ".join(
            f"{e.kind} {e.who} frames {e.frames[0]}-{e.frames[-1]}" for e in eps[:args.longest]), flush=True)
    print(f"\nerror rows {sum(rows.values()) + switches} of {total} person rows (switches {switches}):")
    for kind, n in rows.most_common():
        print(f"  {kind:16s} rows {n:5d}  episodes {count[kind]:4d}  rows in frames 0-{EARLY - 1}: {early[kind]}")
    print(f"\npeople in view at frame 0 missed from frame 0 on: {len(lates)}, "
          f"{sum(int(s.split(': ')[1].split()[0]) for s in lates)} rows")
    print("\n".join("  " + s for s in lates))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
