"""The unit of |W| (seed 001, eq. 3): how large a white-balance change makes colour useless?

Question: α = p·|W| with p = 0.25 and α_th = 0.8 switches colour off at |W| = 3.2 units; the paper
counts gains in 1024 steps but does not say what one unit of |W| is. Measured here: the gain
change at which the true target's RBhat against its template (taken at the old gains, gains *not*
undone) reaches the median RBhat of the other people — beyond it colour cannot tell the target
from anyone. The unit that puts α_th there is ``p·|W|* / α_th`` steps.

Procedure, on PETS 2009 S2.L1 (real clothes, ground-truth boxes) and on the synthetic courtyard
(front light, steady white balance, plan-view candidates matched to the ground truth): every
reference frame (every 20th, each visible person in turn as the target) gives the template; the
next 7 frames are recorded again with the R and B gains changed by |W| = |ΔR| + |ΔB| steps
(split at random, random signs) for |W| = 0 … 500, and the target's RBhat is measured against the
template; the other visible people's RBhat at unchanged gains gives the reference.

Run: ``.venv/bin/python benchmarks/follow_wb_unit.py [--quick]``. Writes
``benchmarks/results/follow_wb_unit.md``. About 2 minutes.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table, save_result  # noqa: E402
from follow_common import apply_gains, load_pets  # noqa: E402

from worldtrack.eval.follow import match_candidates  # noqa: E402
from worldtrack.follow import FollowConfig  # noqa: E402
from worldtrack.follow.colour import bhattacharyya, histograms  # noqa: E402
from worldtrack.follow.planview import detect  # noqa: E402
from worldtrack.follow.silhouette import box_silhouettes, silhouettes  # noqa: E402

SIZES = np.arange(0, 501, 50)
CFG = FollowConfig.preset("paper")        # the paper's HS histogram, gains not undone


def random_gains(rng: np.random.Generator, size: float) -> tuple[float, float]:
    share = rng.uniform(0, 1)
    dr, db = size * np.array([share, 1 - share]) * rng.choice([-1.0, 1.0], 2)
    return 512.0 + dr, 512.0 + db


def curves_from(samples) -> tuple[np.ndarray, float]:
    """samples: iterable of (image, silhouettes (H, W) int32, n, target index, other indices)."""
    rng = np.random.default_rng(0)
    target = [[] for _ in SIZES]
    others = []
    for ref, later in samples:
        img, sil, n, i, rest = ref
        template = histograms(img, sil, n, CFG)[i:i + 1]
        for img2, sil2, n2, i2, rest2 in later:
            for k, size in enumerate(SIZES):
                h = histograms(apply_gains(img2, random_gains(rng, size)), sil2, n2, CFG)
                target[k].append(bhattacharyya(h[i2:i2 + 1], template)[0, 0])
            if len(rest2):
                h0 = histograms(img2, sil2, n2, CFG)
                others += bhattacharyya(h0[rest2], template)[:, 0].tolist()
    return np.array([np.median(t) for t in target]), float(np.median(others))


def crossing(curve: np.ndarray, level: float) -> float:
    """|W| (steps) where the rising curve first reaches ``level`` (linear interpolation; inf if never)."""
    above = np.flatnonzero(curve >= level)
    if len(above) == 0:
        return float("inf")
    j = above[0]
    if j == 0:
        return 0.0
    return float(SIZES[j - 1] + (level - curve[j - 1]) / (curve[j] - curve[j - 1]) * (SIZES[j] - SIZES[j - 1]))


def pets_samples(limit: int | None):
    pets = load_pets(limit)
    if pets is None:
        return None
    for k0 in range(0, pets.n - 8, 20):
        vis = pets.visible[k0]
        for pid in pets.ids[k0][vis]:
            def view(k):
                v = pets.visible[k]
                ids = pets.ids[k][v]
                if pid not in ids:
                    return None
                sil = box_silhouettes(pets.frames[k].shape[:2], pets.boxes[k][v])
                i = int(np.flatnonzero(ids == pid)[0])
                return pets.frames[k], sil, len(ids), i, np.flatnonzero(ids != pid)
            ref = view(k0)
            later = [x for x in (view(k) for k in range(k0 + 1, k0 + 8)) if x is not None]
            yield ref, later


def synthetic_samples(seeds, frames: int):
    from worldtrack.synth import make_scenario
    for seed in seeds:
        sc = make_scenario("follow-target", size=(160, 120), frames=frames, seed=seed, segments=("front",),
                           clear_route=True, lookalike=0)
        walk = sc.scene.distance_field(0.05)
        views = []
        for b in sc.frames():
            v = b.views["robot"]
            c = detect(v.sensor_depth, v.camera, CFG, walk)
            sil = silhouettes(c.labels, c.stride, v.sensor_depth, c.depth)
            people = [(r["id"], (r["x"], r["y"])) for r in b.gt if r["vis_robot"] >= 0.7]
            m = match_candidates(c.xy, np.array([p[1] for p in people]).reshape(-1, 2))
            views.append((v.image, sil, len(c), {pid: j for (pid, _), j in zip(people, m) if j >= 0}))

        def view(k, pid):
            img, sil, n, owner = views[k]
            if pid not in owner:
                return None
            rest = np.array([j for q, j in owner.items() if q != pid], dtype=int)
            return img, sil, n, owner[pid], rest
        for k0 in range(0, len(views) - 8, 20):
            for pid in views[k0][3]:
                later = [x for x in (view(k, pid) for k in range(k0 + 1, k0 + 8)) if x is not None]
                yield view(k0, pid), later


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer frames (a smoke run; prints only)")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    rows, found = [], {}
    sources = {"synthetic courtyard (seeds 300-302)": synthetic_samples((300, 301, 302), 60 if args.quick else 200),
               "PETS 2009 S2.L1": pets_samples(120 if args.quick else None)}
    for name, samples in sources.items():
        if samples is None:
            print(f"{name}: skipped — data not found")
            continue
        curve, others = curves_from(samples)
        w_star = crossing(curve, others)
        found[name] = w_star
        unit = CFG.p * w_star / CFG.alpha_th
        rows.append([name, *[f"{c:.3f}" for c in curve], f"{others:.3f}", f"{w_star:.0f}", f"{unit:.0f}"])
        print(f"{name}: target RBhat {np.round(curve, 3).tolist()}; others {others:.3f}; |W|* = {w_star:.0f} steps; "
              f"unit = {unit:.0f} steps", file=sys.stderr)
    table = markdown_table(["data", *[f"RBhat at {s}" for s in SIZES], "others' median", "|W|* steps",
                            "unit = p·|W|*/α_th steps"], rows)
    text = ("Median RBhat of the true target against its template as the white-balance gains change by |W| steps "
            "(not undone), the other people's median RBhat against the same template, the change |W|* at which "
            "they meet, and the unit of |W| that makes α = p·|W| reach α_th = 0.8 there (p = 0.25). "
            f"worldtrack's default: wb_unit = {FollowConfig().wb_unit:g} steps.\n\n{table}\n")
    print(text)
    save_result("follow_wb_unit", "The unit of |W| (seed 001)", text, args.quick, time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
