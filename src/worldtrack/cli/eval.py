"""``worldtrack eval GT PRED``: score tracks against ground truth on the floor, in metres.

Prints CLEAR-MOT and identity metrics (motmetrics, Euclidean distance on the floor with a gate
in metres), HOTA (TrackEval, similarity 1 − distance / gate) and the papers' mean position error, |ΔX| and |ΔY|; optionally per-frame counts
(CSV), a plot (PNG) or the metrics as JSON.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import re
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from worldtrack.errors import InputError

if TYPE_CHECKING:
    import numpy as np


#: Most vertices of an --area polygon.
MAX_AREA_POINTS = 1000


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "eval", help="score tracks against ground truth (MOTA, MOTP in metres, IDF1, HOTA, errors)",
        description="Compare predicted tracks with ground truth frame by frame on the floor. "
                    "GT and PRED are tracks.csv / gt.csv files or MOTChallenge text with world "
                    "x,y,z (columns 8-10). Frames evaluated: every GT frame, plus predicted "
                    "frames inside the GT frame range (their predictions are false positives). "
                    "HOTA is TrackEval's, with similarity max(0, 1 - distance/gate).")
    p.add_argument("gt", metavar="GT", help="ground-truth tracks (gt.csv, tracks.csv or MOT txt)")
    p.add_argument("pred", metavar="PRED", help="predicted tracks (tracks.csv or MOT txt)")
    p.add_argument("--gate", default="0.5", metavar="METRES",
                   help="largest distance at which a prediction may match a person (default 0.5 m)")
    p.add_argument("--area", metavar="AREA",
                   help="evaluate only inside this floor polygon: a file of x1,y1,x2,y2,... ('#' comments) "
                        "or the numbers themselves (metres, >= 3 points; write --area=-1,0,... when the "
                        "first number is negative)")
    p.add_argument("--per-frame", metavar="CSV",
                   help="write per-frame counts: frame,num_gt,num_pred,matches,misses,fp,switches,"
                        "mean_error_m")
    p.add_argument("--plot", metavar="PNG",
                   help="write a plot: error over time per GT track, and GT vs predicted paths")
    p.add_argument("--json", action="store_true", help="print the metrics as one JSON object")
    p.set_defaults(func=run)


def parse_gate(text: str) -> float:
    """``--gate``: a positive, finite number of metres."""
    try:
        gate = float(text)
    except ValueError:
        raise InputError(f"--gate: expected a distance in metres, got {text!r}") from None
    if not (math.isfinite(gate) and gate > 0):
        raise InputError(f"--gate: expected a positive distance in metres, got {text!r}")
    return gate


def read_area(text: str) -> np.ndarray:
    """``--area``: a polygon file (numbers x1,y1,x2,y2,…, '#' comments) or the numbers, → (M, 2) m."""


    import numpy as np
    path = Path(text)
    if path.is_file():
        try:
            lines = path.read_text(encoding="utf-8").splitlines()
        except (OSError, UnicodeDecodeError) as e:
            raise InputError(f"--area {text}: cannot read ({getattr(e, 'strerror', None) or e})") from None
        body = ",".join(ln.split("#", 1)[0].strip() for ln in lines if ln.split("#", 1)[0].strip())
        body = re.sub(r"[\s,;]+", ",", body).strip(",")
        try:
            return parse_area(body)
        except InputError as e:
            raise InputError(f"--area {text}: {str(e).removeprefix('--area: ')}") from None
    if not re.fullmatch(r"[-+0-9.eE,\s]+", text):
        raise InputError(f"--area {text!r}: no such file, and not numbers x1,y1,x2,y2,...")
    return parse_area(text)


def parse_area(text: str) -> np.ndarray:
    """``--area x1,y1,x2,y2,…`` → (M, 2) polygon in metres, M ≥ 3."""


    import numpy as np
    parts = [s.strip() for s in text.split(",")]
    try:
        values = [float(s) for s in parts]
    except ValueError:
        raise InputError(f"--area: expected numbers x1,y1,x2,y2,... in metres, got {text!r}") from None
    if len(values) % 2 or not 6 <= len(values) <= 2 * MAX_AREA_POINTS or not all(math.isfinite(v) for v in values):
        raise InputError(f"--area: expected x1,y1,x2,y2,... with 3 to {MAX_AREA_POINTS} finite (x, y) points, "
                         f"got {len(values)} numbers")
    return np.asarray(values, dtype=float).reshape(-1, 2)


def run(args: argparse.Namespace) -> int:
    # Heavy imports here, so `worldtrack --help` stays fast.
    from worldtrack.eval.mot import evaluate_detailed
    from worldtrack.eval.tables import position_errors
    from worldtrack.io.tracks import read_tracks

    gate = parse_gate(args.gate)
    area = read_area(args.area) if args.area else None
    gt = read_tracks(args.gt)
    pred = read_tracks(args.pred)

    result = evaluate_detailed(gt, pred, gate=gate, area=area)
    gt_in, pred_in = result.gt, result.pred   # the rows compared (area, GT frame range)
    pos = position_errors(gt_in, pred_in, gate=gate)
    metrics: dict[str, Any] = dict(result.metrics)
    metrics.update(mean_error_m=pos.mean_m, mean_abs_dx_m=pos.mean_abs_dx_m,
                   mean_abs_dy_m=pos.mean_abs_dy_m, num_position_pairs=pos.num_pairs)

    if args.per_frame:
        _write_per_frame(args.per_frame, result.per_frame)
    if args.plot:
        from worldtrack.viz.eval_plots import plot_evaluation
        plot_evaluation(args.plot, gt_in, pred_in, result.pairs, gate=gate, area=area,
                        title=plot_title(args.pred, args.gt, metrics))

    if args.json:
        print(json.dumps({k: _json_value(v) for k, v in metrics.items()}, sort_keys=False))
        return 0
    print(f"ground truth  {args.gt}: {len(gt.ids())} tracks, {len(gt)} rows, "
          f"frames {gt.frame.min()}-{gt.frame.max()}")
    print(f"predicted     {args.pred}: {len(pred.ids())} tracks, {len(pred)} rows")
    outside = len(pred) - len(pred.select(_within(pred.frame, gt.frame)))
    if outside:
        print(f"              ({outside} predicted rows outside the GT frame range ignored)")
    where = "whole floor" if area is None else f"inside a {len(area)}-point area"
    print(f"gate {gate:g} m, {where}, {metrics['num_frames']} frames")
    print(format_table(metrics))
    if args.per_frame:
        print(f"per-frame counts: {args.per_frame}")
    if args.plot:
        print(f"plot: {args.plot}")
    return 0


def plot_title(pred: str, gt: str, m: dict[str, Any]) -> str:
    """A short title: the predictions by folder and name, the ground truth by name, and the scores.

    >>> plot_title("/data/run3/tracks.csv", "/data/gt.csv", {"mota": 0.91, "idf1": 0.85, "gate_m": 0.5})
    'run3/tracks.csv vs gt.csv: MOTA 0.910, IDF1 0.850 (0.5 m gate)'
    """
    def name(path: str) -> str:
        p = Path(path)
        return f"{p.parent.name}/{p.name}" if p.parent.name else p.name

    def f3(v: Any) -> str:
        return "n/a" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{v:.3f}"

    return f"{name(pred)} vs {Path(gt).name}: MOTA {f3(m['mota'])}, IDF1 {f3(m['idf1'])} ({m['gate_m']:g} m gate)"


def format_table(m: dict[str, Any]) -> str:
    """The metrics as an aligned two-column table."""
    from worldtrack.eval.hota import INSTALL_HINT

    def f3(v: Any) -> str:
        return "n/a" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{v:.3f}"

    def metres(v: Any) -> str:
        s = f3(v)
        return s if s == "n/a" else f"{s} m"

    rows = [
        ("MOTA", f3(m["mota"])),
        ("MOTP (mean matched distance)", metres(m["motp_m"])),
        ("IDF1", f3(m["idf1"])),
        ("IDP / IDR", f"{f3(m['idp'])} / {f3(m['idr'])}"),
        ("precision / recall", f"{f3(m['precision'])} / {f3(m['recall'])}"),
        ("ID switches", str(m["num_switches"])),
        ("fragmentations", str(m["num_fragmentations"])),
        ("mostly tracked / partly / lost",
         f"{m['mostly_tracked']} / {m['partially_tracked']} / {m['mostly_lost']}"),
        ("false positives", str(m["num_false_positives"])),
        ("misses", str(m["num_misses"])),
        ("matches / GT objects / predictions",
         f"{m['num_matches']} / {m['num_objects']} / {m['num_predictions']}"),
        ("HOTA (DetA / AssA / LocA)", f"n/a (TrackEval not installed: {INSTALL_HINT})" if m["hota"] is None
         else f"{f3(m['hota'])} ({f3(m['hota_deta'])} / {f3(m['hota_assa'])} / {f3(m['hota_loca'])})"),
        ("mean error", metres(m["mean_error_m"])),
        ("mean |dX|", metres(m["mean_abs_dx_m"])),
        ("mean |dY|", metres(m["mean_abs_dy_m"])),
    ]
    width = max(len(k) for k, _ in rows)
    return "\n".join(f"  {k:<{width}}  {v}" for k, v in rows)


def _within(frames: np.ndarray, gt_frames: np.ndarray) -> np.ndarray:


    import numpy as np
    return (frames >= gt_frames.min()) & (frames <= gt_frames.max())


def _write_per_frame(path: str, per_frame: dict[str, np.ndarray]) -> None:
    cols = [("frame", "frame"), ("num_gt", "num_gt"), ("num_pred", "num_pred"),
            ("matches", "matches"), ("misses", "misses"), ("fp", "false_positives"),
            ("switches", "switches"), ("mean_error_m", "mean_error_m")]
    try:
        with open(path, "w", encoding="utf-8", newline="") as f:
            w = csv.writer(f, lineterminator="\n")
            w.writerow([name for name, _ in cols])
            data = [per_frame[key] for _, key in cols]
            for k in range(len(per_frame["frame"])):
                row = [str(int(c[k])) for c in data[:-1]]
                err = float(data[-1][k])
                row.append("" if math.isnan(err) else f"{err:.6f}")
                w.writerow(row)
    except OSError as e:
        raise InputError(f"{path}: cannot write: {e.strerror or e}") from None


def _json_value(v: Any) -> Any:


    import numpy as np
    if v is None or isinstance(v, (bool, str)):
        return v
    if isinstance(v, (int, np.integer)):
        return int(v)
    v = float(v)
    return None if math.isnan(v) or math.isinf(v) else v


if __name__ == "__main__":  # pragma: no cover
    from worldtrack.cli import main
    sys.exit(main(["eval", *sys.argv[1:]]))
