"""The three trackers on real footage: every folder of ``../shared/data`` with video, calibration and GT.

Question: on recorded video with an official calibration and published ground truth, how do the
ellipsoid tracker, the particle tracker and the blobs baseline score in metres on the floor?

Today that is PETS 2009 S2.L1, View_001 (``pets2009_s2l1``), processed as
``examples/pets2009/README.md`` does it, with the library functions behind its commands:

1. scene ``examples/scenes/pets2009_view001.yaml`` (the official Tsai calibration, 480×360);
2. background: 80 frames sampled evenly over the video, ``estimate_background(method="mode")`` (what
   ``worldtrack background`` does);
3. ground truth: Milan's cropped CVML boxes, ``worldtrack.io.gt_import.read_boxes`` +
   ``boxes_to_world`` (scale 0.625, 7 fps — what ``worldtrack gt import`` does);
4. tracking: all 795 frames, time stamps at 7 fps, default presets (the particle tracker with seeds
   0, 1, 2, averaged: one seed's MOTA moves by up to ±0.05; the ellipsoid tracker and the blobs
   baseline are deterministic but just as chaotic, so each is run three times, started on frame 0,
   1 and 2, and averaged) and the ``worldtrack track``
   default foreground (``colour``, threshold 30; the blobs baseline runs its own MOG2 started from the
   background); frames are decoded once and shared by the three trackers;
5. scoring: ``worldtrack.eval.evaluate_detailed`` inside Milan's tracking area
   (``examples/pets2009/tracking_area.txt``) with a 1 m gate — MOTA, IDF1, ID switches — and the mean
   position error of the matched pairs (``position_errors``, 1 m gate, over the rows in the area);
   "IDF1 kept ids" scores the same rows against Milan's whole-view boxes (``Recipe.gt_ids``): the
   cropped file gives a person who steps out of the area and back a new id, the whole-view file
   keeps it (PETS: 4 people, about 500 of 3955 rows), so a tracker that follows them outside the
   area is charged for it in IDF1 and not in this column;
   frames/s is the tracker alone (``step``, and the ellipsoid tracker's warm start).

Two conventions for where a person is: PETS's world ground truth is the bottom centre of each annotated
box back-projected to the floor, the near edge of the feet (the data's own, the default). With
``--truth-beyond-m M`` every ground-truth row (both files) is moved ``M`` metres farther from the point
below View_001 along its line of sight before scoring (the area test is then made on the moved rows), e.g.
0.1 for the body's centre (the feet reach about 0.1 m towards the camera). Nothing else changes.

Folders without what this needs are skipped with one line saying why (``eth_ewap`` has world
trajectories but no video, so no image-based tracker can run on it); when ``../shared/data`` is
absent the script prints one line and exits 0.

Run: ``.venv/bin/python benchmarks/real_data.py [--quick]``. Writes
``benchmarks/results/real_data.md``. About 2 minutes. ``--quick`` (a smoke run, prints only): the
first 200 frames.
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import DATA, ROOT, markdown_table, save_result, setting_value  # noqa: E402

from worldtrack.cli.eval import read_area  # noqa: E402
from worldtrack.eval import evaluate_detailed, position_errors  # noqa: E402
from worldtrack.experiment import predictions_table, step_tracker  # noqa: E402
from worldtrack.foreground.estimate import estimate_background  # noqa: E402
from worldtrack.io.gt_import import boxes_to_world, read_boxes  # noqa: E402
from worldtrack.trackers.base import Frame  # noqa: E402
from worldtrack.io.tracks import TrackTable  # noqa: E402
from worldtrack.foreground import make_foregrounds  # noqa: E402
from worldtrack.foreground.background import SHADOW_TESTS  # noqa: E402
from worldtrack.scene.load import load_scene  # noqa: E402
from worldtrack.trackers import METHODS, make_tracker, method_shadow_test, method_threshold  # noqa: E402

GATE_M = 1.0
FOREGROUND = "colour"         # worldtrack track's default (threshold 30; the particle tracker's own 25), as the README's command runs it
#: The foreground's shadow test for every method (``--shadow-test``); None: each method's own.
SHADOW_TEST: list[str | None] = [None]
#: The tracker whose results depend on its random seed, and how many seeds it runs with.
RANDOM_METHODS = ("particle",)
PARTICLE_SEEDS = 3
START_FRAMES = 3
BACKGROUND_SAMPLES = 80


@dataclass(frozen=True)
class Recipe:
    """How to run one data folder: its files (relative to the folder) and the README's settings."""

    video: str
    gt: str
    scene: Path
    camera: str
    area: Path
    scale: float
    fps: float
    #: The same annotator's boxes of the whole view (None: none), to score IDF1 with the ids a person
    #: keeps when they step out of the tracking area and back (the cropped file renumbers them).
    gt_ids: str | None = None


RECIPES = {
    "pets2009_s2l1": Recipe(video="video/View_001_480x360.avi", gt="gt/PETS2009-S2L1-cropped.xml",
                            scene=ROOT / "examples/scenes/pets2009_view001.yaml", camera="View_001",
                            area=ROOT / "examples/pets2009/tracking_area.txt", scale=0.625, fps=7.0,
                            gt_ids="gt/PETS2009-S2L1.xml"),
}
VIDEO_SUFFIXES = (".avi", ".mp4", ".mov", ".mkv")


def why_skipped(folder: Path) -> str | None:
    """None if the folder can be run, else one line saying why not."""
    videos = [p for p in folder.rglob("*") if p.suffix.lower() in VIDEO_SUFFIXES]
    if not videos:
        return f"{folder.name}: skipped — no video (world trajectories only), so no image-based tracker can run on it"
    recipe = RECIPES.get(folder.name)
    if recipe is None:
        return f"{folder.name}: skipped — has video but no recipe here (scene, GT format, scale, area)"
    missing = [p for p in (folder / recipe.video, folder / recipe.gt, recipe.scene, recipe.area) if not p.exists()]
    if missing:
        return f"{folder.name}: skipped — missing {', '.join(str(p) for p in missing)}"
    return None


def read_video(path: Path, limit: int | None) -> list[np.ndarray]:
    cap = cv2.VideoCapture(str(path))
    frames = []
    while limit is None or len(frames) < limit:
        ok, img = cap.read()
        if not ok:
            break
        frames.append(img)
    cap.release()
    return frames


def track(method: str, scene, camera: str, background: np.ndarray, frames: list,
          fps: float, first: int = 0, **options) -> tuple[TrackTable, float]:
    """Run one tracker over the frames from index ``first`` on; (predictions, frames/s of the
    tracker, warm start included). ``options`` go to :func:`make_tracker` (e.g. ``seed`` for the particle tracker)."""
    fgs = make_foregrounds(scene, {camera: background}, FOREGROUND, method_threshold(method),
                           shadow_test=SHADOW_TEST[0] or method_shadow_test(method))
    tracker = make_tracker(method, scene, fgs, **options)
    rows, seconds = step_tracker(tracker, ((k, k / fps, {camera: Frame(img, k / fps, k)})
                                           for k, img in enumerate(frames) if k >= first))
    return predictions_table(rows), (len(frames) - first) / seconds


def beyond_along_ray(table: TrackTable, camera_xy: np.ndarray, metres: float) -> TrackTable:
    """``table`` with every row moved ``metres`` (m) farther from the camera's floor point ``camera_xy`` (2,)
    along its line of sight (``--truth-beyond-m``); ``table`` itself with 0."""
    if metres == 0:
        return table
    dx, dy = table.x - camera_xy[0], table.y - camera_xy[1]
    n = np.maximum(np.hypot(dx, dy), 1e-9)
    return TrackTable.from_arrays(table.frame, table.id, table.x + metres * dx / n, table.y + metres * dy / n,
                                  time=table.time)


def run_folder(folder: Path, limit: int | None, particle_seeds: int, start_frames: int,
               methods: tuple[str, ...] = METHODS, overrides: dict | None = None,
               truth_beyond_m: float = 0.0) -> list[list]:
    recipe = RECIPES[folder.name]
    scene = load_scene(recipe.scene)
    cam = scene.camera(recipe.camera)
    t0 = time.perf_counter()
    frames = read_video(folder / recipe.video, limit)
    sample = np.unique(np.linspace(0, len(frames) - 1, min(BACKGROUND_SAMPLES, len(frames))).round().astype(int))
    background = estimate_background([frames[i] for i in sample], method="mode")
    gt = boxes_to_world(read_boxes(folder / recipe.gt), cam, scale=recipe.scale, fps=recipe.fps).table
    gt = beyond_along_ray(gt.select(gt.frame < len(frames)), cam.centre[:2], truth_beyond_m)
    area = read_area(str(recipe.area))
    gt_ids = gt
    if recipe.gt_ids is not None and (folder / recipe.gt_ids).exists():
        gt_ids = boxes_to_world(read_boxes(folder / recipe.gt_ids), cam, scale=recipe.scale, fps=recipe.fps).table
        gt_ids = beyond_along_ray(gt_ids.select(gt_ids.frame < len(frames)), cam.centre[:2], truth_beyond_m)
    print(f"{folder.name}: {len(frames)} frames decoded, background from {len(sample)}, {len(gt)} GT rows "
          f"({time.perf_counter() - t0:.1f} s)", file=sys.stderr)
    for method in methods:      # warm-up: Numba's compilation (or cache load) is not timed
        track(method, scene, recipe.camera, background, frames[:5], recipe.fps)
    rows = []
    for method in methods:
        # (seed, first frame) of each run: a random tracker's seeds, or a deterministic one started
        # on each of the first frames in turn (both are chaotic: one decision taken differently
        # early changes everything after it, so one run is one draw).
        runs_of = ([(seed, 0) for seed in range(particle_seeds)] if method in RANDOM_METHODS
                   else [(None, first) for first in range(start_frames)])
        runs = []
        for seed, first in runs_of:
            options = {} if seed is None else {"seed": seed}
            if overrides and method == "ellipsoid":
                options["overrides"] = overrides
            pred, fps = track(method, scene, recipe.camera, background, frames, recipe.fps, first, **options)
            ev = evaluate_detailed(gt.select(gt.frame >= first), pred, gate=GATE_M, area=area)
            m = ev.metrics
            hota = np.nan if m["hota"] is None else m["hota"]
            idf1_kept = evaluate_detailed(gt_ids.select(gt_ids.frame >= first), pred, gate=GATE_M, area=area).metrics["idf1"]
            runs.append([m["mota"], m["idf1"], idf1_kept, hota, m["num_switches"],
                         position_errors(ev.gt, ev.pred, gate=GATE_M).mean_m, m["recall"], m["precision"], fps])
            print(f"  {method:9s}{f' from frame {first}' if seed is None else f' seed {seed}'} MOTA {m['mota']:.3f} IDF1 {m['idf1']:.3f} "
                  f"(kept ids {idf1_kept:.3f}) HOTA {hota:.3f} switches {m['num_switches']} error {runs[-1][5]:.3f} m {fps:.1f} frames/s",
                  file=sys.stderr)
        a = np.array(runs, dtype=float)
        mean = a.mean(axis=0)
        cells = list(mean)
        if len(runs) > 1:  # MOTA and IDF1 with their spread over the runs
            cells[0], cells[1] = (f"{mean[j]:.3f} ± {a[:, j].std(ddof=1):.3f}" for j in (0, 1))
        rows.append([folder.name, len(frames), method, len(runs)] + cells)
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="the first 200 frames only")
    ap.add_argument("--particle-seeds", type=int, default=PARTICLE_SEEDS,
                    help="runs of the (random) particle tracker with seeds 0, 1, ...; the table gives their mean")
    ap.add_argument("--start-frames", type=int, default=START_FRAMES,
                    help="runs of each deterministic tracker, started on frame 0, 1, ...; the table gives their mean")
    ap.add_argument("--methods", nargs="+", choices=METHODS, default=list(METHODS), help="the trackers to run")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="an ellipsoid setting by dotted path (e.g. identity.enabled=false); results are then only printed")
    ap.add_argument("--shadow-test", choices=SHADOW_TESTS, default=None,
                    help="the foreground's shadow test for every method (default: each method's own, "
                         "evidence for the particle tracker); results are then only printed")
    ap.add_argument("--truth-beyond-m", type=float, default=0.0, metavar="M",
                    help="score against the ground truth moved M metres farther along the camera's line of sight "
                         "(PETS's truth is the box's bottom centre on the floor, the near edge of the feet; "
                         "about 0.1 puts it where the person stands); results are then only printed")
    args = ap.parse_args(argv)
    if not np.isfinite(args.truth_beyond_m):
        ap.error("--truth-beyond-m: expected a finite number of metres")
    overrides = {k: setting_value(v) for k, v in (s.split("=", 1) for s in args.set)}
    SHADOW_TEST[0] = args.shadow_test
    if not DATA.is_dir():
        print(f"real data: skipped — {DATA} does not exist")
        return 0
    t_start = time.perf_counter()
    rows, notes = [], []
    for folder in sorted(p for p in DATA.iterdir() if p.is_dir()):
        reason = why_skipped(folder)
        if reason:
            print(reason)
            notes.append(reason)
            continue
        rows += run_folder(folder, 200 if args.quick else None, 1 if args.quick else args.particle_seeds,
                           1 if args.quick else args.start_frames, tuple(args.methods), overrides, args.truth_beyond_m)
    elapsed = time.perf_counter() - t_start
    if not rows:
        return 0
    table = markdown_table(["data", "frames", "method", "runs", "MOTA", "IDF1", "IDF1 kept ids", "HOTA", "ID switches", "mean error m",
                            "recall", "precision", "frames/s"], rows)
    text = (f"Inside the tracking area, gate {GATE_M} m; default presets, foreground `{FOREGROUND}` (threshold 30; particle: its own 25 and the evidence shadow test; blobs: MOG2); "
            f"frames/s of the tracker alone (its steps, and the ellipsoid tracker's warm start). Each row is the mean over `runs` runs (MOTA and IDF1 ± their "
            f"standard deviation): the particle tracker with seeds 0, 1, ...; the deterministic trackers started on "
            f"frame 0, 1, ... in turn, each scored on the frames it saw. Both kinds are chaotic: one early decision "
            f"taken differently changes everything after it, and one run's MOTA moves by up to ±0.05. 'IDF1 kept ids': "
            f"the same rows scored against the annotator's whole-view boxes, where a person who steps out of the "
            f"tracking area and back keeps their id (the cropped ground truth gives them a new one).\n\n{table}\n\n" + "\n".join(f"- {n}" for n in notes) + "\n")
    print(text)
    save_result("real_data", "The trackers on real footage", text,
                args.quick or bool(overrides) or tuple(args.methods) != tuple(METHODS) or args.shadow_test is not None
                or args.truth_beyond_m != 0,
                elapsed)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
