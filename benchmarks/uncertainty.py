"""Is the ellipsoid tracker's σ calibrated, and how good are its reported velocities?

Question (issue 38): ``sigma`` must be a real per-person estimate of the position error (m), and
``vx, vy, speed`` a proper estimate rather than the tracker's internal velocity (which moves in
steps of the matching grid: 0.125 m/s at 10 frames/s).

For every scenario and seed below, the ellipsoid tracker (default preset, colour foreground)
tracks the rendered frames. Each reported row is paired with the ground truth by the MOT
matching of :func:`worldtrack.eval.evaluate_detailed` (gate 1 m; people less than 20 % visible
in every camera are left out). Per pair: the floor error, σ, the reported velocity (the filter
of :mod:`worldtrack.trackers.ellipsoid.velocity`) and the tracker's internal velocity (what
``tracks.csv`` said before), against the truth's velocity (central differences of its positions).

* **σ calibration**: the share of errors within 1 σ and 2 σ (a 2-D Gaussian with σ per axis:
  39 % and 86 %), Spearman's ρ between σ and the error, RMS error / (√2 · RMS σ) (1 when σ
  has the errors' scale), and the log score (mean −log density of the error under the 2-D
  Gaussian of σ, lower is better: it rewards σ that is both right on average and follows the
  error). Beside it, the best *constant* σ (the training pairs' RMS error / √2).
* **By reported mode**: how many rows are ``tracking``, ``occluded``, ``lost``, and their errors.
* **Velocity**: RMSE of the speed and of the velocity vector, before (internal) and after
  (filter). The positions are the same either way (the filter moves nobody).
* ``--fit``: refits the constants of :mod:`worldtrack.trackers.ellipsoid.uncertainty`
  (κ, c_min and the failing factor) on the **training** seeds by Gaussian maximum likelihood and prints them
  beside the module's values. Only the held-out seeds and scenarios are used to judge.

Training seeds (the constants were fitted on them): crowd 1–3, crowd with 1 camera 4–5,
two-crossing 0–1, entry 0–1.
Held-out: crowd 10–15, crowd with 1 camera (10–11) and with 4 (10), two-crossing 2–4, entry
2–3, desk-occlusion (feet hidden, and head and feet), static-grid, two-rooms, sit-down.

Usage::

    .venv/bin/python benchmarks/uncertainty.py            # ~10 min on one core
    .venv/bin/python benchmarks/uncertainty.py --quick    # smoke run: 2 short held-out runs
    .venv/bin/python benchmarks/uncertainty.py --fit      # also refit the constants
    .venv/bin/python benchmarks/uncertainty.py --training --fit   # only fit (training seeds)

Writes ``benchmarks/results/uncertainty.md`` and ``uncertainty_calibration.png`` (the RMS error
per axis against σ, in bins of σ).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np
from scipy.optimize import minimize
from scipy.stats import spearmanr

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import RESULTS, markdown_table, render_images, save_result  # noqa: E402

from worldtrack.eval import evaluate_detailed  # noqa: E402
from worldtrack.experiment import bundle_frames, gt_table, step_tracker, synthetic_tracker, visibility  # noqa: E402
from worldtrack.synth import make_scenario  # noqa: E402
from worldtrack.trackers.ellipsoid import uncertainty as unc  # noqa: E402

GATE_M = 1.0
CROWD = {"size": (640, 480), "frames": 80, "people": 10}
#: (label, scenario, parameters, seeds); the constants were fitted on TRAIN.
TRAIN = [("crowd", "crowd", CROWD, [1, 2, 3]), ("crowd, 1 camera", "crowd", {**CROWD, "cameras": 1, "people": 6}, [4, 5]),
         ("two-crossing", "two-crossing", {}, [0, 1]), ("entry", "entry", {}, [0, 1])]
HELD_OUT = [("crowd", "crowd", CROWD, [10, 11, 12, 13, 14, 15]),
            ("crowd, 1 camera", "crowd", {**CROWD, "cameras": 1, "people": 6}, [10, 11]),
            ("crowd, 4 cameras", "crowd", {**CROWD, "cameras": 4}, [10]),
            ("two-crossing", "two-crossing", {}, [2, 3, 4]), ("entry", "entry", {}, [2, 3]),
            ("desk, feet hidden", "desk-occlusion", {"hide": "feet"}, [1]),
            ("desk, head and feet hidden", "desk-occlusion", {"hide": "head-and-feet"}, [1]),
            ("static-grid", "static-grid", {}, [1]), ("two-rooms", "two-rooms", {}, [1, 2]),
            ("sit-down", "sit-down", {}, [1])]
QUICK = [("crowd (40 frames)", "crowd", {**CROWD, "frames": 40}, [10]), ("two-crossing", "two-crossing", {}, [2])]


def run(name: str, params: dict, seed: int) -> dict:
    """Track one rendered scenario; the rows paired with the truth, as arrays."""
    sc = make_scenario(name, seed=seed, **params)
    bundles = render_images(sc)
    tracker = synthetic_tracker(sc)

    def row(index, t, tr):
        p = tracker.position_map.get(tr.id)
        parts = tracker.uncertainty.components.get(p) if p is not None else None
        fresh = parts is not None and parts.t == t
        return (index, t, tr.id, tr.x, tr.y, tr.sigma, tr.mode, tr.vx, tr.vy, p.vx, p.vy,
                *(parts.curvature if fresh else (np.nan, np.nan)), *(parts.along if fresh else (np.nan, np.nan)),
                bool(fresh and parts.unmeasurable), bool(fresh and parts.failing))

    rows, _ = step_tracker(tracker, bundle_frames(bundles), row=row)
    gt_all = gt_table(bundles)
    gt = gt_all.select(visibility(gt_all) >= 0.2)
    return pair_rows(rows, gt, gt_velocities(gt_all))


def gt_velocities(gt) -> dict[tuple[int, int], np.ndarray]:
    """{(frame, id): (vx, vy) m/s} of the truth, by central differences of its positions in time."""
    out = {}
    for i in np.unique(gt.id):
        sel = np.flatnonzero(gt.id == i)
        sel = sel[np.argsort(gt.time[sel])]
        t, xy = gt.time[sel], gt.xy[sel]
        v = np.gradient(xy, t, axis=0) if len(sel) > 1 else np.zeros_like(xy)
        out.update({(int(f), int(i)): vk for f, vk in zip(gt.frame[sel], v)})
    return out


def pair_rows(rows: list, gt, gt_v: dict) -> dict:
    """The reported rows the MOT matching pairs with the truth, with the truth's place and velocity."""
    from worldtrack.io.tracks import TrackTable
    a = np.array([r[:6] for r in rows], float).reshape(-1, 6)
    pred = TrackTable.from_arrays(a[:, 0].astype(int), a[:, 2].astype(int), a[:, 3], a[:, 4], time=a[:, 1])
    pairs = evaluate_detailed(gt, pred, gate=GATE_M).pairs
    index = {(int(r[0]), int(r[2])): k for k, r in enumerate(rows)}
    gt_index = {(int(f), int(i)): k for k, (f, i) in enumerate(zip(gt.frame, gt.id))}
    out: dict[str, list] = {k: [] for k in ("err", "dx", "dy", "sigma", "mode", "v", "v_old", "v_gt", "curv",
                                             "along", "unmeasurable", "failing")}
    for f, g, p in zip(pairs["frame"], pairs["gt_id"], pairs["pred_id"]):
        r = rows[index[(int(f), int(p))]]
        truth = gt.xy[gt_index[(int(f), int(g))]]
        out["dx"].append(r[3] - truth[0])
        out["dy"].append(r[4] - truth[1])
        out["err"].append(math.hypot(r[3] - truth[0], r[4] - truth[1]))
        out["sigma"].append(r[5])
        out["mode"].append(r[6])
        out["v"].append(r[7:9])
        out["v_old"].append(r[9:11])
        out["v_gt"].append(gt_v[(int(f), int(g))])
        out["curv"].append(r[11:13])
        out["along"].append(r[13:15])
        out["unmeasurable"].append(r[15])
        out["failing"].append(r[16])
    return {k: np.array(v) for k, v in out.items()}


def joined(runs: list[dict]) -> dict:
    return {k: np.concatenate([r[k] for r in runs]) for k in runs[0]}


def calibration(d: dict, sigma: np.ndarray | None = None) -> list:
    """n, mean error, median σ, within 1 σ, within 2 σ, Spearman ρ, RMS error / (√2 RMS σ)."""
    s = d["sigma"] if sigma is None else sigma
    err = d["err"]
    if len(err) == 0:
        return [0] + ["-"] * 7
    z = err / s
    rho = spearmanr(s, err).correlation if np.ptp(s) > 0 else float("nan")
    ratio = math.sqrt(np.mean(err ** 2)) / (math.sqrt(2) * math.sqrt(np.mean(s ** 2)))
    log_score = np.mean(np.log(2 * np.pi * s ** 2) + z ** 2 / 2)     # −log of the 2-D Gaussian density
    return [len(err), float(err.mean()), float(np.median(s)), f"{np.mean(z < 1):.0%}", f"{np.mean(z < 2):.0%}",
            float(rho), float(ratio), float(log_score)]


def speed_errors(d: dict) -> list:
    """Speed and velocity RMSE (m/s), after (filter) and before (internal velocity)."""
    def rmse(v):
        speed = np.hypot(v[:, 0], v[:, 1]) - np.hypot(d["v_gt"][:, 0], d["v_gt"][:, 1])
        return math.sqrt(np.mean(speed ** 2)), math.sqrt(np.mean(np.sum((v - d["v_gt"]) ** 2, axis=1)))
    before, after = rmse(d["v_old"]), rmse(d["v"])
    return [float(before[0]), float(after[0]), float(before[1]), float(after[1]),
            len(np.unique(np.round(np.hypot(*d["v_old"].T), 4))), len(np.unique(np.round(np.hypot(*d["v"].T), 4)))]


def fit_constants(d: dict) -> tuple[float, float, float]:
    """κ, c_min and the failing factor by Gaussian maximum likelihood of the per-axis errors (along and across the line of
    sight) of the rows measured this frame and not unmeasurable."""
    ok = np.isfinite(d["curv"]).all(axis=1) & ~d["unmeasurable"].astype(bool)
    along = d["along"][ok]
    across = np.column_stack([-along[:, 1], along[:, 0]])
    dxy = np.column_stack([d["dx"], d["dy"]])[ok]
    e = np.column_stack([(dxy * along).sum(1), (dxy * across).sum(1)])
    curv = d["curv"][ok]
    failing = d["failing"][ok].astype(bool)[:, None]

    def nll(w):
        k, cmin, fail = np.exp(w)
        var = k ** 2 / np.maximum(curv, cmin) * np.where(failing, fail ** 2, 1.0)
        return float(np.mean(0.5 * np.log(var) + e ** 2 / (2 * var)))
    res = minimize(nll, np.log([unc.SCORE_NOISE, unc.MIN_CURVATURE, unc.FAILING_FACTOR]),
                   method="Nelder-Mead", options={"maxiter": 4000, "xatol": 1e-4, "fatol": 1e-6})
    return tuple(float(v) for v in np.exp(res.x))


def plot_calibration(d: dict, path: Path) -> None:
    """RMS error per axis against σ in bins of σ (equal counts), with the line where they agree."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    order = np.argsort(d["sigma"])
    bins = np.array_split(order, 12)
    s = [np.sqrt(np.mean(d["sigma"][b] ** 2)) for b in bins]
    e = [np.sqrt(np.mean(d["err"][b] ** 2) / 2) for b in bins]
    fig, ax = plt.subplots(figsize=(5.5, 5))
    top = 1.1 * max(max(s), max(e))
    ax.plot([0, top], [0, top], color="0.6", lw=1, label="calibrated (error = σ)")
    ax.plot(s, e, "o-", label="held-out rows, 12 bins of σ")
    ax.set_xlabel("σ reported (RMS in the bin), m")
    ax.set_ylabel("RMS error per axis in the bin, m")
    ax.set_xlim(0, top)
    ax.set_ylim(0, top)
    ax.set_title("Ellipsoid tracker: σ against the error")
    ax.legend(loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="smoke run: two short held-out runs, nothing written")
    ap.add_argument("--fit", action="store_true", help="refit the σ constants on the training seeds")
    ap.add_argument("--training", action="store_true", help="only the training seeds (with --fit: to fit; nothing written)")
    args = ap.parse_args()
    t0 = time.time()
    groups = {"held-out": QUICK} if args.quick else {"training": TRAIN, "held-out": HELD_OUT}
    if args.training:
        groups, args.quick = {"training": TRAIN}, True
    results: dict[str, dict[str, dict]] = {}
    for group, cases in groups.items():
        for label, name, params, seeds in cases:
            runs = []
            for seed in seeds:
                t1 = time.time()
                runs.append(run(name, params, seed))
                print(f"{group} {label} seed {seed}: {len(runs[-1]['err'])} pairs, {time.time() - t1:.0f} s",
                      file=sys.stderr, flush=True)
            results.setdefault(group, {})[f"{label} ({', '.join(map(str, seeds))})"] = joined(runs)
    text = report(results, args.fit)
    print(text)
    if not args.quick:
        held = joined(list(results["held-out"].values()))
        plot_calibration(held, RESULTS / "uncertainty_calibration.png")
    save_result("uncertainty", "Ellipsoid tracker: σ calibration and velocities on synthetic scenes", text,
                args.quick, time.time() - t0)


def report(results: dict[str, dict[str, dict]], fit: bool) -> str:
    cal_head = ["scenario (seeds)", "pairs", "mean error m", "median σ m", "within 1σ", "within 2σ",
                "Spearman ρ(σ, error)", "RMS error / √2 RMS σ", "log score"]
    spd_head = ["scenario (seeds)", "speed RMSE before", "speed RMSE after", "velocity RMSE before",
                "velocity RMSE after", "distinct speeds before", "distinct speeds after"]
    totals = {g: joined(list(r.values())) for g, r in results.items()}
    const = None
    if "training" in totals:
        const = math.sqrt(np.mean(totals["training"]["err"] ** 2) / 2)
    parts = []
    for group, cases in results.items():
        rows = [[k] + calibration(d) for k, d in cases.items()] + [[f"**all {group}**"] + calibration(totals[group])]
        if const is not None:
            rows.append([f"all {group}, constant σ = {const:.3f} m"]
                        + calibration(totals[group], np.full(len(totals[group]["err"]), const)))
        parts.append(f"σ calibration, {group} (a 2-D Gaussian: 39 % within 1σ, 86 % within 2σ):\n\n"
                     + markdown_table(cal_head, rows))
    held = totals.get("held-out", totals.get("training"))
    modes = []
    for m in ("tracking", "occluded", "lost"):
        sel = held["mode"] == m
        sub = {k: v[sel] for k, v in held.items()}
        modes.append([m, f"{sel.mean():.0%}"] + calibration(sub))
    parts.append(f"By reported mode, all {'held-out' if 'held-out' in totals else 'training'} rows:\n\n"
                 + markdown_table(["mode", "share"] + cal_head[1:], modes))
    for group, cases in results.items():
        rows = [[k] + speed_errors(d) for k, d in cases.items()] + [[f"**all {group}**"] + speed_errors(totals[group])]
        parts.append(f"Velocity against the truth, {group} (m/s; before = the tracker's internal velocity, "
                     "after = the reported filter):\n\n" + markdown_table(spd_head, rows))
    if fit and "training" in totals:
        k, cmin, fail = fit_constants(totals["training"])
        parts.append(f"Constants refitted on the training seeds: κ = {k:.3f}, c_min = {cmin:.3f} 1/m², "
                     f"failing factor {fail:.2f} (the module's: κ = {unc.SCORE_NOISE}, c_min = {unc.MIN_CURVATURE}, "
                     f"failing factor {unc.FAILING_FACTOR}).")
    return "\n\n".join(parts)


if __name__ == "__main__":
    main()
