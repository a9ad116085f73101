"""worldtrack beside EPFL's Probabilistic Occupancy Map (POM), the peer: per-frame detection and speed.

Question: given the *same* foreground masks, does worldtrack find people on the floor better than
POM (Fleuret et al., TPAMI 2008), and how fast is each, on one core?

What runs (POM is GPL: it is built into a temporary folder and run as a separate program, see
``pom_peer.py``; none of its code enters worldtrack):

* **Scenes**: ``crowd`` (10 people in the 10 × 8 m hall) with 1, 2 and 4 cameras, 320×240, held-out
  seeds (default 100-102; the crowd tuning used seeds 0-79 and POM's σ was chosen on seed 0),
  40 frames each; and PETS 2009 S2.L1 View_001 (the first 200 frames, 7 frames/s, the background
  and ground truth as ``real_data.py`` makes them), when ``../shared/data`` (or ``$WORLDTRACK_DATA``)
  has it — else one line says it was skipped.
* **Foreground**: one ``colour`` model per camera (``worldtrack.foreground.make_foregrounds``; threshold
  20 on the synthetic scenes, as ``worldtrack.experiment`` uses, 30 on PETS as ``worldtrack track``).
  The ellipsoid and particle trackers read it; POM gets its ``mask()`` (person = 255) as PNGs.
* **POM**: a floor grid every 0.25 m over the walkable area (PETS: inside the tracking area) seen by
  a camera; per camera and location the image box of a standing person of the scene's default size
  (crowd 1.65 × 0.40 m, PETS 1.70 × 0.45 m); prior 0.01 (POM's default); ``SIGMA_IMAGE_DENSITY``
  chosen for POM on data not reported (``POM_SIGMA``: POM's default 0.01 finds 2 people in 10 on
  these masks). A location is a detection when its probability is above 0.5.
* **Ours**: the ellipsoid (paper 000) and particle (paper 004) trackers, default presets; their
  tracks in each frame are that frame's detections.
* **Scoring**, the same for all: people less than 20 % visible in every camera are neither required
  nor forbidden (``drop_ignored``); per frame, detections and people are paired by the Hungarian
  method within the gate (``position_errors``). Precision TP/(TP+FP), recall TP/(TP+FN), MODA
  1 − (FN+FP)/GT, mean error of the pairs — at 0.5 m and 1 m. For the trackers also MOTA, IDF1 and
  HOTA (``worldtrack.eval.evaluate``, gate 0.5 m).
* **Speed**, one core (the process pins itself and POM to ``--core``): the trackers' frames/s (their
  steps, foreground included); POM's solver (its whole run, PNG reading included) and POM + the
  foreground masks it needs; and, as the in-run reference, one OpenCV MOG2 ``apply`` per frame.

Usage::

    .venv/bin/python benchmarks/peer_pom.py                 # ~10 min on a loaded 2-core machine
    .venv/bin/python benchmarks/peer_pom.py --quick         # smoke run: 1 seed, 12 frames, PETS 30 frames

Writes ``benchmarks/results/peer_pom.md`` (not with ``--quick``).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import DATA, markdown_table, mog2_apply_time, render_images, save_result  # noqa: E402
from pom_peer import (PomRun, build, detections, floor_grid, pom_source, seen_by_some_camera,  # noqa: E402
                      why_not_buildable)

from worldtrack.eval import drop_ignored, evaluate, position_errors  # noqa: E402
from worldtrack.eval.mot import inside_area  # noqa: E402
from worldtrack.experiment import gt_table, predictions_table, run_scenario, step_tracker, visibility  # noqa: E402
from worldtrack.foreground import SYNTHETIC_COLOUR_THRESHOLD, make_foregrounds  # noqa: E402
from worldtrack.synth import make_scenario  # noqa: E402

SIZE = (320, 240)
PEOPLE = 10
CAMERAS = (1, 2, 4)
SEEDS = (100, 101, 102)
FRAMES = 40
PETS_FRAMES = 200
GATES_M = (0.5, 1.0)
CELL_M = 0.25
POM_PRIOR = 0.01
#: POM's SIGMA_IMAGE_DENSITY by scene, chosen on data not reported (best MODA at 0.5 m among 0.002, 0.001,
#: 0.0005, 0.0002, 0.0001): crowd seed 0 (12 frames) per camera count; PETS frames 300-359.
POM_SIGMA = {1: 0.0001, 2: 0.0005, 4: 0.002, "pets": 0.001}
POM_THRESHOLD = 0.5
METHODS = ("ellipsoid", "particle")
DATA_DIR = Path(os.environ["WORLDTRACK_DATA"]) if os.environ.get("WORLDTRACK_DATA") else DATA


def detection_counts(gt, pred, gate: float) -> dict[str, float]:
    """TP, FP, FN and the summed distance of the pairs (metres) of per-frame Hungarian pairing."""
    e = position_errors(gt, pred, gate=gate)
    tp = e.num_pairs
    return {"tp": tp, "fp": len(pred) - tp, "fn": len(gt) - tp, "dist": float(e.distance.sum())}


def scored(gt_all, pred_all, ignore: np.ndarray, area: np.ndarray | None = None) -> dict:
    """Detection counts at every gate after leaving out the ignored people (and what found them)."""
    out = {}
    for gate in GATES_M:
        gt, pred = drop_ignored(gt_all, pred_all, ignore, gate)
        if area is not None:
            gt, pred = gt.select(inside_area(gt, area)), pred.select(inside_area(pred, area))
        out[gate] = detection_counts(gt, pred, gate)
    return out


def pom_detect(binary: Path, workdir: Path, scene, cameras: list[str], foregrounds: dict, views: list[dict],
               frame_numbers: np.ndarray, area: np.ndarray | None, core: int | None, sigma: float):
    """POM on ``views`` (per frame ``{camera: image}``): detections, solver seconds, mask seconds, locations."""
    cams = [scene.camera(c) for c in cameras]
    xy = floor_grid(scene, CELL_M, area)
    xy = xy[seen_by_some_camera(cams, xy, scene.people.height, scene.people.width)]
    run = PomRun(workdir, cams, xy, len(views))
    config, _ = run.write_config(scene.people.height, scene.people.width, POM_PRIOR, sigma)
    mask_s = 0.0
    for f, images in enumerate(views):
        for i, c in enumerate(cameras):
            t0 = time.perf_counter()
            mask = foregrounds[c].mask(images[c])
            mask_s += time.perf_counter() - t0
            run.write_mask(i, f, mask)
    solver_s = run.run(binary, config, core)
    det = detections(run.probabilities(), xy, POM_THRESHOLD, frame_numbers)
    return det, solver_s, mask_s, len(xy)


def warm_up(cameras: int) -> None:
    """Run every tracker on a tiny crowd so that Numba's compilation (or cache load) is not timed."""
    sc = make_scenario("crowd", size=SIZE, frames=3, seed=0, people=2, cameras=cameras)
    bundles = render_images(sc)
    for method in METHODS:
        run_scenario(sc, method, foreground="colour", bundles=bundles)


def crowd_case(cameras: int, seed: int, frames: int, binary: Path, workdir: Path, core: int | None) -> list[dict]:
    """Every method on one rendered crowd: a row dict per method."""
    sc = make_scenario("crowd", size=SIZE, frames=frames, seed=seed, people=PEOPLE, cameras=cameras)
    bundles = render_images(sc)
    cams = list(sc.camera_ids)
    gt_all = gt_table(bundles)
    ignore = visibility(gt_all) < 0.2
    rows = []
    for method in METHODS:
        r = run_scenario(sc, method, foreground="colour", gate=GATES_M[0], bundles=bundles)
        rows.append({"method": method, "counts": scored(gt_all, r.pred_all, ignore), "frames": r.frames,
                     "seconds": r.seconds, "mota": r.metrics["mota"], "idf1": r.metrics["idf1"],
                     "hota": r.metrics["hota"]})
    fgs = make_foregrounds(sc.scene, {c: sc.background(c) for c in cams}, "colour", SYNTHETIC_COLOUR_THRESHOLD)
    det, solver_s, mask_s, n = pom_detect(binary, workdir / f"crowd{cameras}_{seed}", sc.scene, cams, fgs,
                                          [{c: b.views[c].image for c in cams} for b in bundles],
                                          np.array([b.frame for b in bundles]), None, core,
                                          POM_SIGMA[cameras])
    rows.append({"method": "POM", "counts": scored(gt_all, det, ignore), "frames": len(bundles),
                 "seconds": solver_s, "mask_seconds": mask_s, "locations": n})
    return rows


def pets_case(frames: int, binary: Path, workdir: Path, core: int | None) -> list[dict] | str:
    """Every method on the first ``frames`` frames of PETS 2009 S2.L1 View_001, or why it was skipped."""
    from real_data import RECIPES, read_video, why_skipped
    from worldtrack.cli.eval import read_area
    from worldtrack.foreground.estimate import estimate_background
    from worldtrack.io.gt_import import boxes_to_world, read_boxes
    from worldtrack.scene.load import load_scene
    from worldtrack.trackers import make_tracker, method_shadow_test
    from worldtrack.trackers.base import Frame

    folder = DATA_DIR / "pets2009_s2l1"
    if not folder.is_dir():
        return f"PETS 2009 S2.L1: skipped — {folder} does not exist (set WORLDTRACK_DATA)"
    reason = why_skipped(folder)
    if reason:
        return reason
    recipe = RECIPES[folder.name]
    scene = load_scene(recipe.scene)
    images = read_video(folder / recipe.video, frames)
    sample = np.unique(np.linspace(0, len(images) - 1, min(80, len(images))).round().astype(int))
    background = estimate_background([images[i] for i in sample], method="mode")
    gt = boxes_to_world(read_boxes(folder / recipe.gt), scene.camera(recipe.camera), scale=recipe.scale,
                        fps=recipe.fps).table
    gt = gt.select(gt.frame < len(images))
    area = read_area(str(recipe.area))
    ignore = np.zeros(len(gt), dtype=bool)
    rows = []
    for method in METHODS:
        fgs = make_foregrounds(scene, {recipe.camera: background}, "colour", shadow_test=method_shadow_test(method))
        tracker = make_tracker(method, scene, fgs)
        out, seconds = step_tracker(tracker, ((k, k / recipe.fps, {recipe.camera: Frame(img, k / recipe.fps, k)})
                                              for k, img in enumerate(images)))
        pred = predictions_table(out)
        m = evaluate(gt, pred, gate=GATES_M[0], area=area)
        rows.append({"method": method, "counts": scored(gt, pred, ignore, area), "frames": len(images),
                     "seconds": seconds, "mota": m["mota"], "idf1": m["idf1"], "hota": m["hota"]})
    fgs = make_foregrounds(scene, {recipe.camera: background}, "colour")
    det, solver_s, mask_s, n = pom_detect(binary, workdir / "pets", scene, [recipe.camera], fgs,
                                          [{recipe.camera: img} for img in images], np.arange(len(images)), area, core,
                                          POM_SIGMA["pets"])
    rows.append({"method": "POM", "counts": scored(gt, det, ignore, area), "frames": len(images),
                 "seconds": solver_s, "mask_seconds": mask_s, "locations": n})
    return rows


def summary_rows(name: str, runs: list[dict], gate: float) -> list[list]:
    """One table row per method: detection figures summed over the runs, tracking figures averaged."""
    by = defaultdict(list)
    for r in runs:
        by[r["method"]].append(r)
    rows = []
    for method, rs in by.items():
        c = {k: sum(r["counts"][gate][k] for r in rs) for k in ("tp", "fp", "fn", "dist")}
        gt = c["tp"] + c["fn"]
        frames = sum(r["frames"] for r in rs)
        fps = frames / max(sum(r["seconds"] for r in rs), 1e-9)
        with_masks = (frames / max(sum(r["seconds"] + r["mask_seconds"] for r in rs), 1e-9)
                      if method == "POM" else fps)

        def mean(key: str) -> str:
            vals = [r[key] for r in rs if r.get(key) is not None]
            return f"{np.mean(vals):.3f}" if vals else "—"

        rows.append([name, method, len(rs), gt, c["tp"] / max(c["tp"] + c["fp"], 1), c["tp"] / max(gt, 1),
                     1 - (c["fn"] + c["fp"]) / max(gt, 1), c["dist"] / max(c["tp"], 1),
                     mean("mota"), mean("idf1"), mean("hota"), fps, with_masks])
    return rows


HEADERS = ["scene", "method", "runs", "person rows", "precision", "recall", "MODA", "mean error m",
           "MOTA", "IDF1", "HOTA", "frames/s", "frames/s incl. masks"]


def ahead_lines(rows: list[list]) -> list[str]:
    """Per scene: how far the better of our trackers is ahead of (or behind) POM in precision and recall."""
    out = []
    for scene in dict.fromkeys(r[0] for r in rows):
        pom = next(r for r in rows if r[0] == scene and r[1] == "POM")
        for r in rows:
            if r[0] == scene and r[1] != "POM":
                out.append(f"- {scene}, {r[1]}: precision {r[4] - pom[4]:+.3f}, recall {r[5] - pom[5]:+.3f}, "
                           f"MODA {r[6] - pom[6]:+.3f}, mean error {r[7] - pom[7]:+.3f} m, "
                           f"speed ×{r[11] / max(pom[12], 1e-9):.2f} of POM with its masks")
    return out


def verdict(rows: list[list]) -> str:
    """The issue's question: is each tracker ahead of POM in both precision and recall in every scene?"""
    out = []
    for method in METHODS:
        mine = [r for r in rows if r[1] == method]
        pom = {r[0]: r for r in rows if r[1] == "POM"}
        behind = [r[0] for r in mine if not (r[4] > pom[r[0]][4] and r[5] > pom[r[0]][5])]
        out.append(f"{method}: ahead of POM in precision and recall in {len(mine) - len(behind)} of {len(mine)} scenes"
                   + (f" (not in: {'; '.join(behind)})" if behind else ""))
    return "; ".join(out) + "."


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--seeds", type=int, nargs="+", default=None, help=f"crowd seeds (default {SEEDS})")
    p.add_argument("--frames", type=int, default=None, help=f"crowd frames (default {FRAMES})")
    p.add_argument("--pets-frames", type=int, default=None, help=f"PETS frames (default {PETS_FRAMES})")
    p.add_argument("--core", type=int, default=1, help="the core to pin to (default 1; -1: do not pin)")
    p.add_argument("--quick", action="store_true", help="1 seed, 12 frames, PETS 30 frames; prints only")
    args = p.parse_args(argv)
    seeds = args.seeds or ([SEEDS[0]] if args.quick else list(SEEDS))
    frames = args.frames or (12 if args.quick else FRAMES)
    pets_frames = args.pets_frames or (30 if args.quick else PETS_FRAMES)
    core = None if args.core < 0 else args.core
    source = pom_source()
    reason = why_not_buildable(source)
    if reason:
        print(reason)
        return 0
    if core is not None and hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {core})
    t_start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="worldtrack-pom-") as tmp:
        workdir = Path(tmp)
        print(f"building POM from {source} in {workdir} ...", file=sys.stderr, flush=True)
        binary = build(source, workdir)
        runs: dict[str, list[dict]] = {}
        for cameras in CAMERAS:
            warm_up(cameras)
            name = f"crowd {PEOPLE}, {cameras} camera{'s' if cameras > 1 else ''}"
            for seed in seeds:
                rs = crowd_case(cameras, seed, frames, binary, workdir, core)
                runs.setdefault(name, []).extend(rs)
                recall = {r["method"]: r["counts"][0.5]["tp"] / max(r["counts"][0.5]["tp"] + r["counts"][0.5]["fn"], 1)
                          for r in rs}
                print(f"{name}, seed {seed}: " + ", ".join(f"{m} recall {v:.3f}" for m, v in recall.items()),
                      file=sys.stderr, flush=True)
        pets = pets_case(pets_frames, binary, workdir, core)
        notes = []
        if isinstance(pets, str):
            print(pets)
            notes.append(pets)
        else:
            runs["PETS 2009 S2.L1"] = pets
    mog2_ms = 1000 * mog2_apply_time(*SIZE)
    tables = []
    for gate in GATES_M:
        rows = [row for name, rs in runs.items() for row in summary_rows(name, rs, gate)]
        tables.append((gate, rows))
    text = (f"crowd: {SIZE[0]}×{SIZE[1]}, {frames} frames, seeds {', '.join(map(str, seeds))}; PETS: View_001, the "
            f"first {pets_frames} frames, inside the tracking area. POM: grid {CELL_M} m, prior {POM_PRIOR}, "
            f"SIGMA_IMAGE_DENSITY {POM_SIGMA} by camera count, detections where p > {POM_THRESHOLD}. "
            f"Precision, recall, MODA and "
            f"mean error are per-frame detection (a tracker's tracks in a frame are its detections) summed over the "
            f"runs (POM's error includes its grid: a uniform point is 0.096 m from the centre of its {CELL_M} m "
            f"cell on average); MOTA, IDF1, HOTA (trackers only, gate 0.5 m) are means over the runs. "
            f"Speed on one core "
            f"(core {core}); in-run reference: one MOG2 apply on a {SIZE[0]}×{SIZE[1]} frame takes {mog2_ms:.2f} ms "
            f"({1000 / mog2_ms:.0f} frames/s).\n\n")
    for gate, rows in tables:
        text += (f"### Gate {gate} m\n\n{markdown_table(HEADERS, rows)}\n\n**{verdict(rows)}**\n\n"
                 "Against POM (ours − POM):\n\n")
        text += "\n".join(ahead_lines(rows)) + "\n\n"
    text += "".join(f"- {n}\n" for n in notes)
    print(text)
    save_result("peer_pom", "worldtrack beside EPFL's Probabilistic Occupancy Map (POM)", text, args.quick,
                time.perf_counter() - t_start)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
