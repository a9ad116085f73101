"""Run a tracker on a synthetic scenario and score it against the exact ground truth.

What the demo, the benchmarks and the end-to-end tests share: render the scenario, track it with
timing of the tracker alone, build ground-truth and predicted :class:`TrackTable`\\ s, leave out
people who are barely visible (and predictions that found them), and compute the MOT and paper
metrics.

>>> from worldtrack.synth import make_scenario
>>> r = run_scenario(make_scenario("two-crossing", size=(160, 120), seed=0))   # doctest: +SKIP
>>> r.metrics["mota"], r.errors.mean_m, r.fps                                  # doctest: +SKIP
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable, Iterable, Iterator

import numpy as np

from worldtrack.eval.mot import drop_ignored, evaluate
from worldtrack.eval.tables import PositionErrors, position_errors
from worldtrack.trackers.base import Frame
from worldtrack.io.tracks import TrackTable
from worldtrack.foreground import SYNTHETIC_COLOUR_THRESHOLD, make_foregrounds
from worldtrack.trackers import make_tracker, method_shadow_test, method_threshold
from worldtrack.trackers.base import warm_started


@dataclass
class ExperimentResult:
    """Ground truth, predictions and scores of one run.

    Attributes
    ----------
    gt, pred : TrackTable — what was scored (ignored people and their matches removed)
    gt_all, pred_all : TrackTable — everything
    metrics : dict — :func:`worldtrack.eval.evaluate` output
    errors : PositionErrors — mean position error and |ΔX|, |ΔY| of matched pairs
    seconds : float — time spent in ``tracker.step`` only
    frames : int
    tracker : the tracker object, for inspection
    """

    gt: TrackTable
    pred: TrackTable
    gt_all: TrackTable
    pred_all: TrackTable
    metrics: dict
    errors: PositionErrors
    seconds: float
    frames: int
    tracker: object = field(repr=False)

    @property
    def fps(self) -> float:
        return self.frames / self.seconds if self.seconds > 0 else float("inf")


def gt_table(bundles) -> TrackTable:
    """Ground-truth rows of rendered bundles as a table with every gt.csv column."""
    rows = [r for b in bundles for r in b.gt]
    if not rows:
        return TrackTable.from_arrays([], [], [], [], time=[])
    cols = [c for c in rows[0] if c not in ("frame", "time", "id", "x", "y")]
    extra = {c: np.array([r.get(c, np.nan) for r in rows], dtype=float) for c in cols}
    return TrackTable.from_arrays([r["frame"] for r in rows], [r["id"] for r in rows],
                                  [r["x"] for r in rows], [r["y"] for r in rows],
                                  time=[r["time"] for r in rows], extra=extra)


def visibility(gt: TrackTable) -> np.ndarray:
    """(N,) the best visible fraction of each ground-truth row over all cameras."""
    vis = [gt.column(c) for c in gt.columns if c.startswith("vis_")]
    return np.max(np.vstack(vis), axis=0) if vis else np.ones(len(gt))


def synthetic_threshold(method: str, foreground: str = "colour") -> float | None:
    """The foreground threshold of ``method`` on the synthetic world: the method's own, else for colour
    the synthetic world's 20 (noise σ ≈ 3), else None (the kind's default).

    >>> synthetic_threshold("ellipsoid"), synthetic_threshold("particle"), synthetic_threshold("ellipsoid", "grey")
    (20.0, 25.0, None)
    """
    own = method_threshold(method)
    if own is not None:
        return own
    return SYNTHETIC_COLOUR_THRESHOLD if foreground == "colour" else None


def synthetic_tracker(scenario, method: str = "ellipsoid", preset: str = "default", foreground: str = "colour",
                      threshold: float | None = None, cameras: list[str] | None = None,
                      shadow_texture_ncc: float | None = None, shadow_test: str | None = None, **options):
    """A tracker for a synthetic scenario, its foregrounds made from the scenario's background plates.

    Parameters
    ----------
    scenario : worldtrack.synth.Scenario
    method, preset, options : passed to :func:`worldtrack.trackers.make_tracker`
    foreground, threshold : the foreground model (see :func:`worldtrack.foreground.make_foregrounds`);
        the threshold defaults to the method's own (:func:`worldtrack.trackers.method_threshold`),
        else, for colour, to the synthetic world's 20
    cameras : the cameras to track with (default: all)
    shadow_texture_ncc : the foreground's texture test of shadow-like pixels (default off; see
        :func:`worldtrack.foreground.make_foregrounds`)
    shadow_test : the foreground's shadow test, "colour" or "evidence" (default the method's own,
        :func:`worldtrack.trackers.method_shadow_test`)
    """
    if threshold is None:
        threshold = synthetic_threshold(method, foreground)
    cams = list(cameras or scenario.camera_ids)
    foregrounds = make_foregrounds(scenario.scene, {c: scenario.background(c) for c in cams}, foreground, threshold,
                                   shadow_texture_ncc=shadow_texture_ncc,
                                   shadow_test=shadow_test or method_shadow_test(method, preset))
    return make_tracker(method, scenario.scene, foregrounds, preset=preset, **options)


def bundle_frames(bundles, cameras: list[str] | None = None) -> Iterator[tuple[int, float, dict[str, Frame]]]:
    """``(frame, time, {camera: Frame})`` of each rendered bundle: the views of ``cameras`` (default: all)."""
    for b in bundles:
        cams = b.views if cameras is None else cameras
        yield b.frame, b.time, {c: Frame(b.views[c].image, b.time, b.frame) for c in cams}


def track_row(index: int, t: float, track) -> tuple:
    """``(frame, time, id, x, y)`` of a reported track: the default row of :func:`step_tracker`."""
    return (index, t, track.id, track.x, track.y)


def step_tracker(tracker, frames: Iterable[tuple[int, float, dict]],
                 row: Callable | None = track_row) -> tuple[list, float]:
    """Step ``tracker`` over ``(index, time, {camera: Frame})`` items (e.g. :func:`bundle_frames`).

    Returns ``row(index, time, track)`` for every reported track, in order (nothing when ``row``
    is None), and the seconds spent in the tracker: ``tracker.step`` and its warm start, if it has
    one (:func:`worldtrack.trackers.base.warm_started`).
    """
    rows: list = []
    seconds = 0.0
    items = warm_started(tracker, frames)
    while True:
        t0 = time.perf_counter()
        item = next(items, None)    # the first item also runs the tracker's warm start, if any
        if item is None:
            break
        index, t, views = item
        tracks = tracker.step(views, t)
        seconds += time.perf_counter() - t0
        if row is not None:
            rows += [row(index, t, tr) for tr in tracks]
    return rows, seconds


def predictions_table(rows) -> TrackTable:
    """A TrackTable of :func:`track_row` rows ``(frame, time, id, x, y)``."""
    a = np.array(rows, dtype=float).reshape(-1, 5)
    return TrackTable.from_arrays(a[:, 0].astype(int), a[:, 2].astype(int), a[:, 3], a[:, 4], time=a[:, 1])


def run_scenario(scenario, method: str = "ellipsoid", preset: str = "default", foreground: str = "colour",
                 threshold: float | None = None, min_visibility: float = 0.2, gate: float = 0.5,
                 score_rows: Callable[[TrackTable], np.ndarray] | None = None, init_from_gt: bool = False,
                 cameras: list[str] | None = None, bundles=None, shadow_texture_ncc: float | None = None,
                 shadow_test: str | None = None, **options) -> ExperimentResult:
    """Track a synthetic scenario and score it.

    Parameters
    ----------
    scenario : worldtrack.synth.Scenario
    method, preset, options : passed to :func:`worldtrack.trackers.make_tracker`
    foreground, threshold : the foreground model (see :func:`worldtrack.foreground.make_foregrounds`);
        the threshold defaults to the method's own (:func:`worldtrack.trackers.method_threshold`),
        else, for colour, to the synthetic world's 20
    min_visibility : ground truth less visible than this in every camera is not scored
    gate : metres
    score_rows : optional ``gt -> (N,) bool`` choosing the ground-truth rows to score (e.g. only
        standing still with head and feet visible); the others are ignored like invisible ones
    init_from_gt : start every person present in the first frame at their true position
        (the paper's static measurements start from a known person)
    cameras : use only these cameras (default: all)
    bundles : already rendered bundles (to render once and track several ways)
    shadow_texture_ncc, shadow_test : see :func:`synthetic_tracker`
    """
    if bundles is None:
        bundles = scenario.render()
    cams = list(cameras or scenario.camera_ids)
    tracker = synthetic_tracker(scenario, method, preset, foreground, threshold, cams, shadow_texture_ncc,
                                shadow_test, **options)
    if init_from_gt and bundles:
        for r in bundles[0].gt:
            tracker.init_track(r["x"], r["y"], track_id=int(r["id"]))
    rows, seconds = step_tracker(tracker, bundle_frames(bundles, cams))
    pred_all = predictions_table(rows)
    gt_all = gt_table(bundles)
    ignore = visibility(gt_all) < min_visibility
    if score_rows is not None:
        ignore |= ~np.asarray(score_rows(gt_all), dtype=bool)
    gt, pred = drop_ignored(gt_all, pred_all, ignore, gate)
    if score_rows is not None:
        pred = pred.select(np.isin(pred.frame, gt.frame))
    metrics = evaluate(gt, pred, gate=gate)
    return ExperimentResult(gt, pred, gt_all, pred_all, metrics, position_errors(gt, pred, gate=gate),
                            seconds, len(bundles), tracker)


def standing_with_head_and_feet(camera_ids: list[str]) -> Callable[[TrackTable], np.ndarray]:
    """``score_rows`` for seed 000's Table 1 (a): still, head and feet visible in some camera."""
    def rows(gt: TrackTable) -> np.ndarray:
        still = gt.column("speed") == 0
        whole = np.zeros(len(gt), dtype=bool)
        for c in camera_ids:
            whole |= (gt.column(f"head_{c}") > 0) & (gt.column(f"feet_{c}") > 0)
        return still & whole
    return rows
