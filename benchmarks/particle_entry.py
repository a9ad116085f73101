"""Seed 004 on the synthetic ``entry`` scenario: the height column against the point likelihood.

People walk in side by side (0.5 m apart) through the lobby's south door, walk together, split up,
wait and leave; one more person crosses in from the east door. One camera high on the north wall.
For each tracker configuration and scenario seed this prints, from ``worldtrack.eval``:

* one track on entry — the issue's "every person who enters gets exactly one track within 5 frames
  of being fully in view": the share of people matched within 5 frames of fully in view and covered
  by exactly one track over the first ``ENTRY_WINDOW_S`` (2 s) from then — the tracks matched to
  them and any unmatched track within the gate of them (a duplicate), each from 3 frames on;
* tracks per person — over the whole run, a stricter figure that also counts every later identity
  switch: distinct track ids matched to the person (≥ 3 frames each), and the share of
  people with exactly one;
* frames from "fully in view" (first frame with ≥ 90 % of the body visible, head and feet in the
  image) to the first matched track;
* pairs split on entry — the issue's "people entering side by side 0.5 m apart get separate
  tracks": of the pairs who become fully in view within 1 s of each other less than 0.8 m apart,
  the share matched to two different tracks within 5 frames of that;
* side by side separate — a stricter figure over the whole run: for every two people less than
  0.8 m apart (walking in together, crossing, waiting), the share of frames in which both are
  matched to *different* tracks (a miss of either counts against it);
* mean position error of matched pairs (gate 0.5 m), recall, MOTA, IDF1;
* box contains centre: the share of matched frames whose box ``(x, y, z) ± (sx, sy, sz)`` holds the
  true body centre ``(x, y, height / 2)``.

Every scenario seed runs with each tracker seed (``particle.seed``, default 0 and 1): the
tracker's random draws alone move these figures by about as much as many a change does, so the
table gives each figure's mean over all runs ± its spread over tracker seeds.

Configurations: ``paper-column`` and ``paper-point`` (the method as published:
``ParticleConfig.paper()`` with ``likelihood.model`` ``column-count`` / ``point``) and ``default-column``
/ ``default-point`` (with worldtrack's extensions: ``column-ratio``, and ``point`` with
``weights.power=1``).

Usage::

    .venv/bin/python benchmarks/particle_entry.py                  # 3 seeds × 2 tracker seeds, 320x240, all configs
    .venv/bin/python benchmarks/particle_entry.py --seeds 0 1 2 3 4 5 --tracker-seeds 0 1 2 --configs default-column --jobs 2
    .venv/bin/python benchmarks/particle_entry.py --seeds 0 --configs default-column
    .venv/bin/python benchmarks/particle_entry.py --threshold 25 --set detection.alpha=0.4
    .venv/bin/python benchmarks/particle_entry.py --scenario limb_swing=0 --configs default-column --no-single
        # walkers glide (no leg or arm swing): the error the gait causes is the difference

Writes ``benchmarks/results/particle_entry.md``.
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table, render_images, write_result  # noqa: E402

from worldtrack.config import parse_assignment, with_overrides  # noqa: E402
from worldtrack.eval import evaluate_detailed  # noqa: E402
from worldtrack.experiment import gt_table, synthetic_threshold  # noqa: E402
from worldtrack.foreground import make_foregrounds  # noqa: E402
from worldtrack.io.tracks import TrackTable  # noqa: E402
from worldtrack.synth import make_scenario  # noqa: E402
from worldtrack.trackers import method_shadow_test  # noqa: E402
from worldtrack.trackers.particle import ParticleConfig, ParticleTracker  # noqa: E402


def _config(base: ParticleConfig, settings: dict) -> ParticleConfig:
    """``base`` with ``settings`` by dotted path (a wrong name or value is an InputError naming it)."""
    return with_overrides(base, settings, root="particle")


CONFIGS = {
    "paper-column": lambda o: _config(ParticleConfig.paper(), {"likelihood.model": "column-count", **o}),
    "paper-point": lambda o: _config(ParticleConfig.paper(), {"likelihood.model": "point", **o}),
    "default-column": lambda o: _config(ParticleConfig(), {"likelihood.model": "column-ratio", **o}),
    "default-point": lambda o: _config(ParticleConfig(), {"likelihood.model": "point", "weights.power": 1.0, **o}),
}
GATE_M = 0.5
VIS_EVAL = 0.3      # ground truth rows count from this visible share on
SIDE_BY_SIDE_M = 0.8
ALONE_M = 1.5         # error breakdown: nobody nearer than this
STANDING_MPS = 0.2    # error breakdown: slower than this is standing
ENTRY_WINDOW_S = 2.0  # "on entering": from fully in view, while a pair walks in together
ENTRY_FRAMES = 5      # the "within 5 frames of being fully in view"


@dataclass
class Sequence:
    seed: int
    scenario: object
    bundles: list           # rendered frames: images and ground truth (common.render_images)
    background: np.ndarray

    @property
    def images(self) -> list:
        return [b.views["cam"].image for b in self.bundles]

    @property
    def gt(self) -> list:
        return [b.gt for b in self.bundles]


def render(seed: int, size: tuple[int, int], **overrides) -> Sequence:
    sc = make_scenario("entry", size=size, seed=seed, **overrides)
    return Sequence(seed, sc, render_images(sc), sc.background("cam"))


#: The foreground's threshold (the particle tracker's γ; ``--threshold``): None, the tracker's own 25.
THRESHOLD: list[float | None] = [None]
#: The foreground model's kind (``--foreground``), as ``worldtrack track``'s default.
KIND = ["colour"]


def foreground(seq: Sequence, preset: str = "default") -> dict:
    """The camera's foreground model, as ``worldtrack track`` makes it (colour, shadows set apart, the
    particle tracker's own shadow test for ``preset``)."""
    threshold = synthetic_threshold("particle", KIND[0]) if THRESHOLD[0] is None else THRESHOLD[0]
    return make_foregrounds(seq.scenario.scene, {"cam": seq.background}, KIND[0], threshold,
                            shadow_test=method_shadow_test("particle", preset))


def run(seq: Sequence, config: ParticleConfig, preset: str = "default") -> tuple[TrackTable, float]:
    """Track the sequence with ``config`` of ``preset``; (predictions, seconds per frame)."""
    sc = seq.scenario
    tracker = ParticleTracker(sc.scene, foreground(seq, preset), config)
    rows = []
    t0 = time.perf_counter()
    for k, img in enumerate(seq.images):
        for tr in tracker.step({"cam": img}, k / sc.fps):
            rows.append((k, tr.id, tr.x, tr.y, tr.extra["z"], tr.extra["sx"], tr.extra["sy"], tr.extra["sz"]))
    el = (time.perf_counter() - t0) / len(seq.images)
    a = np.array(rows, dtype=float).reshape(-1, 8)
    pred = TrackTable.from_arrays(a[:, 0].astype(int), a[:, 1].astype(int), a[:, 2], a[:, 3],
                                  extra={"z": a[:, 4], "sx": a[:, 5], "sy": a[:, 6], "sz": a[:, 7]})
    return pred, el


def score(seq: Sequence, pred: TrackTable) -> dict:
    """The figures of the module docstring for one run."""
    gt_all = gt_table(seq.bundles)
    gt = gt_all.select(gt_all.extra["vis_cam"] >= VIS_EVAL)
    ev = evaluate_detailed(gt, pred, gate=GATE_M)
    P = ev.pairs
    out = {"mota": ev.metrics["mota"], "idf1": ev.metrics["idf1"], "recall": ev.metrics["recall"],
           "err_m": float(np.mean(P["distance"])) if len(P["distance"]) else float("nan")}
    # Box contains the true centre (x, y, height / 2).
    prow = {(int(f), int(i)): j for j, (f, i) in enumerate(zip(pred.frame, pred.id))}
    grow = {(int(f), int(i)): j for j, (f, i) in enumerate(zip(gt.frame, gt.id))}
    j = np.array([prow[(int(f), int(i))] for f, i in zip(P["frame"], P["pred_id"])], dtype=int)
    q = np.array([grow[(int(f), int(i))] for f, i in zip(P["frame"], P["gt_id"])], dtype=int)
    if len(j):
        inside = ((np.abs(pred.x[j] - gt.x[q]) <= pred.extra["sx"][j])
                  & (np.abs(pred.y[j] - gt.y[q]) <= pred.extra["sy"][j])
                  & (np.abs(pred.extra["z"][j] - gt.extra["height"][q] / 2) <= pred.extra["sz"][j]))
        out["box_pct"] = 100.0 * float(inside.mean())
    else:
        out["box_pct"] = float("nan")
    # Tracks per person and frames to the first track after fully in view.
    tracks, lat, entry_one = [], [], []
    full_at: dict[int, int] = {}
    window = int(round(ENTRY_WINDOW_S * seq.scenario.fps))
    for gid in np.unique(gt_all.id):
        sel = gt_all.select(gt_all.id == gid)
        full = sel.frame[(sel.extra["vis_cam"] >= 0.9) & (sel.extra["head_cam"] > 0) & (sel.extra["feet_cam"] > 0)]
        if not len(full):
            continue
        full_at[int(gid)] = int(full.min())
        m = P["gt_id"] == gid
        ids, cnt = np.unique(P["pred_id"][m], return_counts=True)
        tracks.append(int((cnt >= 3).sum()))
        first = P["frame"][m].min() if m.any() else None
        lat.append(np.inf if first is None else max(0, int(first) - int(full.min())))
        entry_one.append(lat[-1] <= ENTRY_FRAMES and _entry_tracks(sel, pred, P, gid, int(full.min()), window) == 1)
    out["entry_one_pct"] = 100.0 * float(np.mean(entry_one)) if entry_one else float("nan")
    out["people"] = len(tracks)
    out["tracks_per_person"] = float(np.mean(tracks)) if tracks else float("nan")
    out["one_track_pct"] = 100.0 * float(np.mean(np.array(tracks) == 1)) if tracks else float("nan")
    lat = np.array(lat, dtype=float)
    out["latency_max"] = float(lat.max()) if len(lat) else float("nan")
    out["latency_le5_pct"] = 100.0 * float(np.mean(lat <= ENTRY_FRAMES)) if len(lat) else float("nan")
    # Side by side: both people of a close pair matched to different tracks.
    both, total = 0, 0
    for f in np.unique(gt.frame):
        rows = np.flatnonzero(gt.frame == f)
        for a in range(len(rows)):
            for b in range(a + 1, len(rows)):
                ia, ib = rows[a], rows[b]
                if np.hypot(gt.x[ia] - gt.x[ib], gt.y[ia] - gt.y[ib]) >= SIDE_BY_SIDE_M:
                    continue
                total += 1
                pa = P["pred_id"][(P["frame"] == f) & (P["gt_id"] == gt.id[ia])]
                pb = P["pred_id"][(P["frame"] == f) & (P["gt_id"] == gt.id[ib])]
                both += int(len(pa) > 0 and len(pb) > 0 and pa[0] != pb[0])
    out["side_by_side_pct"] = 100.0 * both / total if total else float("nan")
    split, pairs = _pairs_split_on_entry(gt_all, P, full_at, int(round(seq.scenario.fps)))
    out["pairs_entering"] = pairs
    out["pairs_split_pct"] = 100.0 * split / pairs if pairs else float("nan")
    out.update(error_breakdown(seq, gt_all, gt, pred, j, q))
    return out


def error_breakdown(seq: Sequence, gt_all: TrackTable, gt: TrackTable, pred: TrackTable, j: np.ndarray,
                    q: np.ndarray) -> dict:
    """Where the position error of matched pairs is (:data:`BREAKDOWN_COLUMNS`).

    Parameters
    ----------
    seq : the scenario run
    gt_all, gt : all ground truth rows, and those scored
    pred : the predictions
    j, q : (M,) rows of ``pred`` and ``gt`` of the matched pairs

    Returns
    -------
    dict of mean errors, metres: along and across the camera's line of sight (floor plane); of
    people alone (nobody within ``ALONE_M``) and with somebody within ``SIDE_BY_SIDE_M``; standing
    (below ``STANDING_MPS``) and walking. NaN where no pair falls in a class.
    """
    nan = float("nan")
    keys = [k for k, _ in BREAKDOWN_COLUMNS]
    if not len(j):
        return dict.fromkeys(keys, nan)
    centre = np.asarray(seq.scenario.scene.cameras["cam"].centre, float)[:2]
    gxy = np.column_stack([gt.x[q], gt.y[q]])
    err = np.column_stack([pred.x[j], pred.y[j]]) - gxy
    ray = gxy - centre
    ray /= np.maximum(np.linalg.norm(ray, axis=1, keepdims=True), 1e-9)
    along = np.abs((err * ray).sum(axis=1))
    across = np.abs(err[:, 0] * ray[:, 1] - err[:, 1] * ray[:, 0])
    dist = np.hypot(err[:, 0], err[:, 1])
    # Nearest other person in the same frame (all ground truth, seen or not): one distance matrix
    # per frame, not a scan of the whole table per pair.
    frames, ids = gt.frame[q], gt.id[q]
    nearest = np.full(len(q), np.inf)
    for f in np.unique(frames):
        mine, others = np.flatnonzero(frames == f), np.flatnonzero(gt_all.frame == f)
        d = np.hypot(gxy[mine, None, 0] - gt_all.x[others][None], gxy[mine, None, 1] - gt_all.y[others][None])
        d[ids[mine, None] == gt_all.id[others][None]] = np.inf      # not oneself
        nearest[mine] = d.min(axis=1, initial=np.inf)
    # Own floor speed: the mean step to the frames before and after, where the person is in them.
    where = {(int(f), int(i)): (x, y) for f, i, x, y in zip(gt_all.frame, gt_all.id, gt_all.x, gt_all.y)}
    speed = np.zeros(len(q))
    for k, (f, i, (x, y)) in enumerate(zip(frames.tolist(), ids.tolist(), gxy)):
        steps = [np.hypot(*(np.subtract(where[(f + s, i)], (x, y)))) for s in (-1, 1) if (f + s, i) in where]
        speed[k] = float(np.mean(steps)) * seq.scenario.fps if steps else 0.0

    def mean(mask: np.ndarray) -> float:
        return float(dist[mask].mean()) if mask.any() else nan

    return {"err_along_m": float(along.mean()), "err_across_m": float(across.mean()),
            "err_alone_m": mean(nearest >= ALONE_M), "err_near_m": mean(nearest < SIDE_BY_SIDE_M),
            "err_standing_m": mean(speed < STANDING_MPS), "err_walking_m": mean(speed >= STANDING_MPS),
            "near_pct": 100.0 * float(np.mean(nearest < SIDE_BY_SIDE_M))}


def _pairs_split_on_entry(gt: TrackTable, pairs: dict, full_at: dict[int, int], within: int) -> tuple[int, int]:
    """People who enter side by side, and how many of those pairs get separate tracks on entry.

    A pair enters side by side when both become fully in view (``full_at``: frame) at most
    ``within`` frames apart and stand less than ``SIDE_BY_SIDE_M`` apart at the later of the two
    frames. It is split on entry when, within ``ENTRY_FRAMES`` (5) of that frame, both are
    matched (``pairs``: :func:`evaluate_detailed`'s) to two different tracks in the same frame —
    the issue's "people entering side by side 0.5 m apart get separate tracks". Returns
    (pairs split, pairs).
    """
    where = {(int(f), int(i)): (x, y) for f, i, x, y in zip(gt.frame, gt.id, gt.x, gt.y)}
    match = {(int(f), int(g)): int(p) for f, g, p in zip(pairs["frame"], pairs["gt_id"], pairs["pred_id"])}
    split = total = 0
    ids = sorted(full_at)
    for n, a in enumerate(ids):
        for b in ids[n + 1:]:
            f0 = max(full_at[a], full_at[b])
            if abs(full_at[a] - full_at[b]) > within or (f0, a) not in where or (f0, b) not in where:
                continue
            if np.hypot(*np.subtract(where[(f0, a)], where[(f0, b)])) >= SIDE_BY_SIDE_M:
                continue
            total += 1
            split += any((f, a) in match and (f, b) in match and match[(f, a)] != match[(f, b)]
                         for f in range(f0, f0 + ENTRY_FRAMES + 1))
    return split, total


def _entry_tracks(person: TrackTable, pred: TrackTable, pairs: dict, gid: int, start: int, window: int) -> int:
    """How many tracks a person has on entering: over frames ``start … start + window`` (from the
    first frame fully in view), the distinct tracks matched to the person plus the unmatched tracks
    within the gate of the person (a duplicate the matching left over), each counted from 3 frames on.
    """
    in_window = lambda f: (f >= start) & (f <= start + window)   # noqa: E731
    m = (pairs["gt_id"] == gid) & in_window(pairs["frame"])
    ids = [pairs["pred_id"][m]]
    # Unmatched tracks in the window within the gate of the person.
    matched = set(zip(pairs["frame"].astype(int).tolist(), pairs["pred_id"].astype(int).tolist()))
    rows = np.flatnonzero(in_window(pred.frame))
    rows = rows[[(int(pred.frame[r]), int(pred.id[r])) not in matched for r in rows]]
    here = np.full((start + window + 1, 2), np.nan)
    sel = in_window(person.frame)
    here[person.frame[sel].astype(int)] = np.column_stack([person.x[sel], person.y[sel]])
    at = here[pred.frame[rows].astype(int)]
    ids.append(pred.id[rows][np.hypot(pred.x[rows] - at[:, 0], pred.y[rows] - at[:, 1]) <= GATE_M])
    _, counts = np.unique(np.concatenate(ids).astype(int), return_counts=True)
    return int((counts >= 3).sum())


def given_starts(seq: Sequence, config: ParticleConfig, preset: str = "default") -> dict:
    """Tracking alone: every person's filter started on the true position, no detection.

    One tracker without detection filters, split or merge; each person gets a tracking filter (with
    the person's id) at the ground-truth position on the first frame the person is fully in view.
    Over every frame in which the person is at least half visible: the mean and median distance
    of the person's own track (no association needed), the share of frames within 0.25 m (an
    ended track counts as a miss) and the share of frames the track is alive.
    """
    sc = seq.scenario
    alone = _config(config, {"detection.births": "none", "split.enabled": False, "merge.enabled": False})
    tracker = ParticleTracker(sc.scene, foreground(seq, preset), alone)
    started: set[int] = set()
    errors, near, alive = [], [], []
    for k, (img, gt) in enumerate(zip(seq.images, seq.gt)):
        t = k / sc.fps
        for r in gt:
            if r["id"] not in started and r["vis_cam"] >= 0.9 and r["head_cam"] and r["feet_cam"]:
                tracker.init_track(r["x"], r["y"], track_id=int(r["id"]), t=t)
                started.add(int(r["id"]))
        tracks = {tr.id: tr for tr in tracker.step({"cam": img}, t)}
        for r in gt:
            if int(r["id"]) not in started or r["vis_cam"] < 0.5:
                continue
            tr = tracks.get(int(r["id"]))
            alive.append(tr is not None)
            if tr is None:
                near.append(False)
                continue
            e = float(np.hypot(tr.x - r["x"], tr.y - r["y"]))
            errors.append(e)
            near.append(e <= 0.25)
    return {"given_err_m": float(np.mean(errors)) if errors else float("nan"),
            "given_median_m": float(np.median(errors)) if errors else float("nan"),
            "given_within_025_pct": 100.0 * float(np.mean(near)) if near else float("nan"),
            "given_alive_pct": 100.0 * float(np.mean(alive)) if alive else float("nan")}


SINGLE_COLUMNS = [("given_err_m", "mean error m"), ("given_median_m", "median error m"),
                  ("given_within_025_pct", "frames within 0.25 m %"), ("given_alive_pct", "track alive %")]

COLUMNS = [("people", "people"), ("entry_one_pct", "one track on entry %"),
           ("tracks_per_person", "tracks/person"), ("one_track_pct", "1 track %"),
           ("latency_le5_pct", "first track ≤ 5 frames %"), ("latency_max", "max frames to track"),
           ("pairs_entering", "pairs entering side by side"), ("pairs_split_pct", "pairs split on entry %"),
           ("side_by_side_pct", "side by side separate %"), ("err_m", "mean error m"),
           ("box_pct", "box holds centre %"), ("recall", "recall"), ("mota", "MOTA"), ("idf1", "IDF1")]
BREAKDOWN_COLUMNS = [("err_m", "mean error m"), ("err_along_m", "along line of sight m"),
                     ("err_across_m", "across m"), ("err_alone_m", f"alone (≥ {ALONE_M} m) m"),
                     ("err_near_m", f"neighbour < {SIDE_BY_SIDE_M} m"), ("near_pct", "with neighbour %"),
                     ("err_standing_m", f"standing (< {STANDING_MPS} m/s) m"), ("err_walking_m", "walking m")]
TOTALS = ("people", "pairs_entering")   # counts: totals over scenario seeds, not means


def summarise(results: list[dict], keys: list[str]) -> dict[str, tuple[float, float]]:
    """Mean over every run and the spread over tracker seeds, per figure.

    Parameters
    ----------
    results : list of dict — one per (scenario seed, tracker seed) run, each with a ``tracker_seed``
        and the figures ``keys``
    keys : the figures to summarise

    Returns
    -------
    {key: (mean, spread)} — ``mean`` over all runs (NaNs ignored); ``spread`` the standard
    deviation, over tracker seeds, of the mean over scenario seeds (0 with one tracker seed): how
    much the figure moves with the tracker's random draws alone, the noise a change must beat
    """
    out = {}
    seeds = sorted({r["tracker_seed"] for r in results})
    for k in keys:
        per = [float(np.nanmean([r[k] for r in results if r["tracker_seed"] == s])) for s in seeds]
        out[k] = (float(np.nanmean([r[k] for r in results])), float(np.std(per, ddof=1)) if len(per) > 1 else 0.0)
    return out


def _pm(mean: float, spread: float, show_spread: bool) -> str:
    """``mean ± spread`` as table text (3 significant digits)."""
    m = f"{mean:.3g}" if abs(mean) < 1000 else f"{mean:.0f}"
    return f"{m} ± {spread:.2g}" if show_spread else m


def _task(job: tuple) -> tuple:
    """One run: (config name, scenario seed, tracker seed) → (score, given-starts figures, s/frame)."""
    name, seq, options, tracker_seed, single = job
    cfg = CONFIGS[name]({**options, "seed": tracker_seed})
    preset = name.split("-")[0]                                    # "paper" or "default"
    pred, spf = run(seq, cfg, preset)
    return score(seq, pred), (given_starts(seq, cfg, preset) if single else None), spf


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2], help="scenario seeds")
    p.add_argument("--tracker-seeds", type=int, nargs="+", default=[0, 1],
                   help="tracker random seeds (particle.seed); every scenario seed runs with each")
    p.add_argument("--size", default="320x240")
    p.add_argument("--configs", nargs="+", default=list(CONFIGS), choices=list(CONFIGS))
    p.add_argument("--set", action="append", default=[], metavar="PATH=VALUE",
                   help="set a field of every configuration by its dotted path (e.g. detection.alpha=0.4)")
    p.add_argument("--scenario", action="append", default=[], metavar="NAME=VALUE",
                   help="override a scenario option (e.g. shadow_strength=0)")
    p.add_argument("--no-single", action="store_true", help="skip the runs with filters started on the truth")
    p.add_argument("--jobs", type=int, default=1, help="worker processes (timings are then not comparable)")
    p.add_argument("--json", default=None, metavar="PATH", help="also write every run's figures as JSON")
    p.add_argument("--name", default="particle_entry", help="result file benchmarks/results/NAME.md")
    p.add_argument("--no-write", action="store_true")
    p.add_argument("--foreground", default="colour", choices=("grey", "colour"),
                   help="the foreground model (default colour, as worldtrack track)")
    p.add_argument("--threshold", type=float, default=None,
                   help="the foreground's threshold, the particle tracker's γ (default: its own 25)")
    args = p.parse_args(argv)
    THRESHOLD[0] = args.threshold
    KIND[0] = args.foreground
    w, h = (int(v) for v in args.size.lower().split("x"))
    options = dict(parse_assignment(s) for s in args.set)
    for name in args.configs:
        CONFIGS[name](options)                  # a wrong name or value: one line, before any rendering
    scen = {k: eval(v, {}) for k, v in (s.split("=", 1) for s in args.scenario)}

    seqs = []
    for seed in args.seeds:
        t0 = time.perf_counter()
        seqs.append(render(seed, (w, h), **scen))
        print(f"rendered seed {seed}: {len(seqs[-1].images)} frames in {time.perf_counter() - t0:.1f} s",
              file=sys.stderr)

    jobs = [(name, seq, options, ts, not args.no_single)
            for name in args.configs for ts in args.tracker_seeds for seq in seqs]
    if args.jobs > 1:
        from concurrent.futures import ProcessPoolExecutor
        with ProcessPoolExecutor(args.jobs) as pool:
            outs = list(pool.map(_task, jobs))
    else:
        outs = [_task(j) for j in jobs]

    show = len(args.tracker_seeds) > 1
    rows, per_seed, single_rows, dump, breakdown_rows = [], [], [], [], []
    for name in args.configs:
        results, singles = [], []
        for (n, seq, _, ts, _), (r, g, spf) in zip(jobs, outs):
            if n != name:
                continue
            r = {**r, "tracker_seed": ts, "seed": seq.seed}
            results.append(r)
            if g is not None:
                singles.append({**g, "tracker_seed": ts})
            dump.append({"config": name, **r, **(g or {}), "ms_per_frame": 1000 * spf})
            per_seed.append([name, seq.seed, ts] + [r[k] for k, _ in COLUMNS] + [1000 * spf])
            print(f"{name:15s} seed {seq.seed} tracker seed {ts}: "
                  + ", ".join(f"{lab} {r[k]:.3g}" for k, lab in COLUMNS), file=sys.stderr)
        summ = summarise(results, [k for k, _ in COLUMNS if k not in TOTALS])
        # Counts (people, pairs) are totals over the scenario seeds: one tracker seed's runs.
        first = [r for r in results if r["tracker_seed"] == args.tracker_seeds[0]]
        rows.append([name] + [int(np.sum([r[k] for r in first])) if k in TOTALS else _pm(*summ[k], show)
                              for k, _ in COLUMNS])
        bd = summarise(results, [k for k, _ in BREAKDOWN_COLUMNS])
        breakdown_rows.append([name] + [_pm(*bd[k], show) for k, _ in BREAKDOWN_COLUMNS])
        if singles:
            ss = summarise(singles, [k for k, _ in SINGLE_COLUMNS])
            single_rows.append([name] + [_pm(*ss[k], show) for k, _ in SINGLE_COLUMNS])
            print(f"{name:15s} given starts: " + ", ".join(f"{lab} {single_rows[-1][i + 1]}"
                                                             for i, (_, lab) in enumerate(SINGLE_COLUMNS)),
                  file=sys.stderr)

    headers = ["config"] + [lab for _, lab in COLUMNS]
    table = markdown_table(headers, rows)
    seed_table = markdown_table(["config", "seed", "tracker seed"] + [lab for _, lab in COLUMNS] + ["ms/frame"],
                                per_seed)
    single_table = markdown_table(["config"] + [lab for _, lab in SINGLE_COLUMNS], single_rows) if single_rows else ""
    breakdown = markdown_table(["config"] + [lab for _, lab in BREAKDOWN_COLUMNS], breakdown_rows)
    cmd = "benchmarks/particle_entry.py " + " ".join(argv if argv is not None else sys.argv[1:])
    print(table)
    print("\nWhere the position error is (mean error of matched pairs, metres):\n")
    print(breakdown)
    if single_table:
        print("\nTracking alone: each person's filter started on the true position, no detection:\n")
        print(single_table)
    if args.json:
        import json
        Path(args.json).write_text(json.dumps(dump, indent=1))
    if not args.no_write:
        spread = (f"Each figure is the mean over all {len(jobs) // len(args.configs)} runs per configuration "
                  f"(scenario seeds × tracker seeds {', '.join(map(str, args.tracker_seeds))}) ± the standard "
                  f"deviation over tracker seeds of the mean over scenario seeds (the tracker's own random "
                  f"noise; a change must beat it)." if show else
                  f"Means over scenario seeds, tracker seed {args.tracker_seeds[0]}.")
        body = (f"Command: `.venv/bin/python {cmd.strip()}`\n\nScenario `entry`, {w}x{h}, seeds "
                f"{', '.join(map(str, args.seeds))}{', ' + str(scen) if scen else ''}; overrides "
                f"{options or 'none'}. Gate {GATE_M} m; ground truth from {int(VIS_EVAL * 100)} % visible. "
                f"{spread} People and pairs: totals over scenario seeds.\n\n{table}\n\n"
                f"Where the position error is: the mean error of matched pairs split into its parts along "
                f"and across the camera's line of sight on the floor, and by situation — nobody within "
                f"{ALONE_M} m, somebody within {SIDE_BY_SIDE_M} m (and the share of matched frames so), "
                f"standing (true floor speed below {STANDING_MPS} m/s) and walking:\n\n{breakdown}\n\n"
                + (f"Tracking alone: every person's filter started on the true position when the person is "
                   f"first fully in view (no detection, split or merge); errors of the person's own track "
                   f"over the frames the person is ≥ 50 % visible:\n\n{single_table}\n\n" if single_table else "")
                + f"Per run:\n\n{seed_table}\n")
        path = write_result(args.name, "Particle tracker (seed 004) on the entry scenario", body)
        print(f"wrote {path}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
