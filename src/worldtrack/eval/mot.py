"""CLEAR-MOT and identity metrics of world-coordinate tracks against ground truth.

The counting (matching with history, switches, fragmentations, MT/PT/ML, IDF1's global
assignment) is ``motmetrics``'; this module only decides *what is compared*: per frame, the
Euclidean distance in metres between ground-truth and predicted floor positions ``(x, y)``,
with pairs farther apart than ``gate`` forbidden (NaN).

Frames evaluated
----------------
Every frame that has a ground-truth row, plus every frame with a predicted row that lies within
the ground truth's frame range ``[min, max]``. A CSV has no row for a frame in which nobody is
present, so inside the range such a frame is taken as "annotated, nobody there" and its
predictions are false positives; predictions before the first or after the last ground-truth
frame are ignored (nothing says what was there). If your ground truth is annotated only on
every n-th frame, subsample the predictions to those frames first.

Area
----
With ``area`` (a floor polygon), ground-truth and predicted rows outside it are dropped before
matching, as the PETS literature evaluates inside a tracking area. The set of frames is decided
before this filter, so a frame whose people are all outside still counts as a frame.

HOTA
----
``hota`` (and its parts ``hota_deta``, ``hota_assa``, ``hota_loca``) is TrackEval's HOTA on the
same rows and frames, with the similarity ``max(0, 1 − d / gate)`` (:mod:`worldtrack.eval.hota`);
None when TrackEval is not installed. MOTA and IDF1 do not depend on it.

Note: ``motmetrics.distances.norm2squared_matrix`` returns *squared* distances (its ``max_d2``
is a squared gate) and, in motmetrics 1.4.0, calls ``np.asfarray``, which NumPy 2 removed; we
compute the (metre) distance matrix ourselves, so ``motp`` is a mean distance in metres.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from worldtrack.errors import InputError
from worldtrack.eval.hota import evaluate_hota
from worldtrack.io.tracks import TrackTable
from worldtrack.scene.floor import points_in_polygon

#: The default gate: a prediction more than this many metres from a person cannot match them.
DEFAULT_GATE_M = 0.5
#: Most rows (people) one frame of either table may hold: the frame's distance matrix and its
#: assignment grow with the square and the cube of it.
MAX_PER_FRAME = 2000

#: motmetrics metric names computed by :func:`summarize`.
MOTMETRICS_NAMES: tuple[str, ...] = (
    "mota", "motp", "idf1", "idp", "idr", "num_switches", "num_fragmentations", "precision",
    "recall", "mostly_tracked", "partially_tracked", "mostly_lost", "num_false_positives",
    "num_misses", "num_objects", "num_predictions", "num_frames", "num_unique_objects",
    "num_detections")

# Event types that are one (GT, prediction) pair: a match or a match with an id switch.
_PAIR_EVENTS = ("MATCH", "SWITCH")


@dataclass(frozen=True)
class FrameDistances:
    """What one frame gives the accumulator.

    Attributes
    ----------
    frame : int
    gt_ids : (G,) int64
    pred_ids : (P,) int64
    distance : (G, P) float64
        Distance between ground truth ``i`` and prediction ``j``; NaN where they may not pair.
    """

    frame: int
    gt_ids: np.ndarray
    pred_ids: np.ndarray
    distance: np.ndarray


@dataclass(frozen=True)
class MotEvaluation:
    """Everything :func:`evaluate_detailed` found.

    Attributes
    ----------
    metrics : dict
        What :func:`evaluate` returns (see there).
    gt, pred : TrackTable
        The rows that were compared: inside ``area``, predictions within the evaluated frames.
    pairs : dict of str → (K,) ndarray
        Every matched (ground truth, prediction) pair, switches included: ``frame, gt_id,
        pred_id, distance`` (metres), ``switch`` (bool).
    per_frame : dict of str → (F,) ndarray
        Per evaluated frame: ``frame, num_gt, num_pred, matches`` (switches included),
        ``misses, false_positives, switches, mean_error_m`` (NaN without matches).
    """

    metrics: dict[str, Any]
    gt: TrackTable = field(repr=False)
    pred: TrackTable = field(repr=False)
    pairs: dict[str, np.ndarray] = field(repr=False)
    per_frame: dict[str, np.ndarray] = field(repr=False)


def floor_distances(gt_xy: ArrayLike, pred_xy: ArrayLike, gate: float) -> np.ndarray:
    """Euclidean distance matrix in metres, NaN beyond the gate.

    Parameters
    ----------
    gt_xy : (G, 2) array_like, metres
    pred_xy : (P, 2) array_like, metres
    gate : float, metres
        Pairs with distance > ``gate`` become NaN (may not be matched).

    Returns
    -------
    (G, P) float64 ndarray, metres
    """
    a = np.asarray(gt_xy, dtype=float).reshape(-1, 2)
    b = np.asarray(pred_xy, dtype=float).reshape(-1, 2)
    d = np.sqrt(np.sum((a[:, None, :] - b[None, :, :]) ** 2, axis=-1))  # ‖g_i − p_j‖, not squared
    d[d > gate] = np.nan
    return d


def inside_area(table: TrackTable, area: ArrayLike) -> np.ndarray:
    """(N,) bool: which rows of ``table`` lie inside the floor polygon ``area`` (M, 2), metres."""
    return points_in_polygon(table.xy, _check_area(area))


def evaluated_frames(gt: TrackTable, pred: TrackTable) -> np.ndarray:
    """Sorted frames to evaluate: all ground-truth frames and predicted ones within their range."""
    gt_frames = np.unique(gt.frame)
    if gt_frames.size == 0:
        return gt_frames
    p = np.unique(pred.frame)
    p = p[(p >= gt_frames[0]) & (p <= gt_frames[-1])]
    return np.union1d(gt_frames, p)


def frame_distances(gt: TrackTable, pred: TrackTable, frames: ArrayLike,
                    gate: float) -> Iterator[FrameDistances]:
    """Per frame of ``frames``: ids present in each table and their distance matrix (metres)."""
    return _sorted_frame_distances(gt.sorted(), pred.sorted(), frames, gate)


def _frame_bounds(row_frames: np.ndarray, frames: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """``(lo, hi)``: the rows of frame ``frames[k]`` in the sorted ``row_frames`` are ``lo[k]:hi[k]``."""
    return np.searchsorted(row_frames, frames, "left"), np.searchsorted(row_frames, frames, "right")


def _sorted_frame_distances(gt: TrackTable, pred: TrackTable, frames: ArrayLike,
                            gate: float) -> Iterator[FrameDistances]:
    """:func:`frame_distances` of tables already :meth:`~TrackTable.sorted`."""
    frames = np.asarray(frames, dtype=np.int64)
    g_lo, g_hi = _frame_bounds(gt.frame, frames)
    p_lo, p_hi = _frame_bounds(pred.frame, frames)
    gxy, pxy = gt.xy, pred.xy
    for k, f in enumerate(frames):
        gs, ps = slice(g_lo[k], g_hi[k]), slice(p_lo[k], p_hi[k])
        yield FrameDistances(int(f), gt.id[gs], pred.id[ps], floor_distances(gxy[gs], pxy[ps], gate))


def accumulate(frames: Iterable[FrameDistances | tuple]) -> "Any":
    """Feed per-frame distance matrices to a ``motmetrics.MOTAccumulator``.

    Parameters
    ----------
    frames : iterable of :class:`FrameDistances` or ``(frame, gt_ids, pred_ids, distance)``
        ``distance`` (G, P) in whatever unit MOTP should be reported in, NaN = may not pair.

    Returns
    -------
    motmetrics.MOTAccumulator
    """
    import motmetrics as mm

    acc = mm.MOTAccumulator(auto_id=False)
    for item in frames:
        f, oids, hids, dist = (item.frame, item.gt_ids, item.pred_ids, item.distance) \
            if isinstance(item, FrameDistances) else item
        dist = np.asarray(dist, dtype=float).reshape(len(oids), len(hids))
        acc.update(np.asarray(oids), np.asarray(hids), dist, frameid=int(f))
    return acc


def summarize(acc: Any) -> dict[str, float | int]:
    """The :data:`MOTMETRICS_NAMES` of an accumulator as plain Python numbers (motmetrics names;
    ``motp`` is the mean matched distance in the unit fed to :func:`accumulate`)."""
    import motmetrics as mm

    raw = mm.metrics.create().compute(acc, metrics=list(MOTMETRICS_NAMES), return_dataframe=False)
    out: dict[str, float | int] = {}
    for k in MOTMETRICS_NAMES:
        v = raw[k]
        out[k] = int(v) if (k.startswith("num_") or k.startswith(("mostly", "partially"))) else float(v)
    return out


def evaluate_detailed(gt: TrackTable, pred: TrackTable, gate: float = DEFAULT_GATE_M,
                      area: ArrayLike | None = None) -> MotEvaluation:
    """Like :func:`evaluate`, and also the matched pairs and per-frame counts."""
    if not (np.isfinite(gate) and gate > 0):
        raise InputError(f"gate: expected a positive distance in metres, got {gate!r}")
    if len(gt) == 0:
        raise InputError(f"{gt.source or 'ground truth'}: no rows to evaluate against")
    gt, pred = gt.sorted(), pred.sorted()
    frames = evaluated_frames(gt, pred)
    for table in (gt, pred):
        _check_per_frame(table)
    if area is not None:
        ring = _check_area(area)
        gt = gt.select(inside_area(gt, ring))
        pred = pred.select(inside_area(pred, ring))
    pred = pred.select((pred.frame >= frames[0]) & (pred.frame <= frames[-1]))
    per_frame_d = list(_sorted_frame_distances(gt, pred, frames, gate))   # select() keeps the order
    acc = accumulate(per_frame_d)
    m = summarize(acc)

    metrics: dict[str, Any] = {
        "mota": m["mota"],
        "motp_m": m["motp"],
        "idf1": m["idf1"], "idp": m["idp"], "idr": m["idr"],
        "num_switches": m["num_switches"], "num_fragmentations": m["num_fragmentations"],
        "precision": m["precision"], "recall": m["recall"],
        "mostly_tracked": m["mostly_tracked"], "partially_tracked": m["partially_tracked"],
        "mostly_lost": m["mostly_lost"],
        "num_false_positives": m["num_false_positives"], "num_misses": m["num_misses"],
        "num_objects": m["num_objects"], "num_predictions": m["num_predictions"],
        "num_matches": m["num_detections"],  # matches including those with an id switch
        "num_unique_objects": m["num_unique_objects"],
        "num_frames": m["num_frames"],
        "gate_m": float(gate),
    }
    ev = acc.mot_events
    ev_frame = ev.index.get_level_values("FrameId").to_numpy(dtype=np.int64)
    ev_type = np.asarray(ev["Type"].cat.categories.astype(str))[ev["Type"].cat.codes.to_numpy()]
    is_pair = np.isin(ev_type, _PAIR_EVENTS)
    pairs = {
        "frame": ev_frame[is_pair],
        "gt_id": ev["OId"].to_numpy(dtype=float)[is_pair].astype(np.int64),
        "pred_id": ev["HId"].to_numpy(dtype=float)[is_pair].astype(np.int64),
        "distance": ev["D"].to_numpy(dtype=float)[is_pair],
        "switch": ev_type[is_pair] == "SWITCH",
    }

    def per(mask: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
        idx = np.searchsorted(frames, ev_frame[mask])
        return np.bincount(idx, weights=weights, minlength=frames.size)

    n_pairs = per(is_pair).astype(np.int64)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean_err = per(is_pair, pairs["distance"]) / n_pairs
    per_frame = {
        "frame": frames,
        "num_gt": _count_per_frame(gt.frame, frames),
        "num_pred": _count_per_frame(pred.frame, frames),
        "matches": n_pairs,
        "misses": per(ev_type == "MISS").astype(np.int64),
        "false_positives": per(ev_type == "FP").astype(np.int64),
        "switches": per(ev_type == "SWITCH").astype(np.int64),
        "mean_error_m": np.where(n_pairs > 0, mean_err, np.nan),
    }
    del acc, ev   # motmetrics' events go before HOTA builds its similarity matrices (peak memory)
    metrics.update(hota_metrics(gt, pred, gate, frames, _handed_over(per_frame_d)))
    return MotEvaluation(metrics=metrics, gt=gt, pred=pred, pairs=pairs, per_frame=per_frame)


def evaluate(gt: TrackTable, pred: TrackTable, gate: float = DEFAULT_GATE_M,
             area: ArrayLike | None = None) -> dict[str, Any]:
    """CLEAR-MOT and identity metrics of ``pred`` against ``gt`` on the floor, in metres.

    Parameters
    ----------
    gt, pred : TrackTable
        Ground truth and tracker output; positions ``x, y`` in metres, matched by ``frame``.
    gate : float, metres
        Largest distance at which a prediction may match a person (default 0.5 m).
    area : (M, 2) array_like, metres, optional
        Floor polygon; only rows inside it count.

    Returns
    -------
    dict
        ``mota``; ``motp_m`` (mean distance of matched pairs, metres); ``idf1, idp, idr``;
        ``num_switches, num_fragmentations``; ``precision, recall``; ``mostly_tracked,
        partially_tracked, mostly_lost``; ``num_false_positives, num_misses, num_objects``
        (ground-truth rows), ``num_predictions``, ``num_matches`` (switches included),
        ``num_unique_objects``, ``num_frames``; ``gate_m``; ``hota, hota_deta, hota_assa,
        hota_loca`` (TrackEval's HOTA, similarity ``1 − d / gate``; None without TrackEval).
        Ratios are NaN where undefined (e.g. no ground truth
        inside ``area``).

    Raises
    ------
    InputError
        A non-positive gate, a malformed area, or ground truth without rows.

    Examples
    --------
    >>> from worldtrack.io.tracks import read_tracks                    # doctest: +SKIP
    >>> evaluate(read_tracks("gt.csv"), read_tracks("gt.csv"))["mota"]  # doctest: +SKIP
    1.0
    """
    return evaluate_detailed(gt, pred, gate=gate, area=area).metrics


def hota_metrics(gt: TrackTable, pred: TrackTable, gate: float, frames: np.ndarray,
                 distances: Iterable[np.ndarray] | None = None) -> dict[str, float | None]:
    """``hota, hota_deta, hota_assa, hota_loca`` of the compared rows (None without TrackEval);
    ``distances``: the frames' gated distance matrices when already computed."""
    h = evaluate_hota(gt, pred, gate, frames, distances)
    if h is None:
        return dict.fromkeys(("hota", "hota_deta", "hota_assa", "hota_loca"))
    return {"hota": h.hota, "hota_deta": h.deta, "hota_assa": h.assa, "hota_loca": h.loca}


def _handed_over(per_frame_d: list[FrameDistances]) -> Iterator[np.ndarray]:
    """The frames' distance matrices, each dropped from ``per_frame_d`` once handed out, so that
    HOTA's similarity matrices replace them instead of adding to the peak memory."""
    for k in range(len(per_frame_d)):
        item, per_frame_d[k] = per_frame_d[k], None
        yield item.distance


def _count_per_frame(row_frames: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """How many of the sorted ``row_frames`` fall on each of ``frames``."""
    lo, hi = _frame_bounds(row_frames, frames)
    return (hi - lo).astype(np.int64)


def _check_per_frame(table: TrackTable) -> None:
    """:class:`InputError` if a frame of the sorted ``table`` holds more than :data:`MAX_PER_FRAME` rows."""
    if len(table) <= MAX_PER_FRAME:
        return
    starts = np.flatnonzero(np.r_[True, np.diff(table.frame) != 0])
    counts = np.diff(np.r_[starts, len(table)])
    k = int(np.argmax(counts))
    if counts[k] > MAX_PER_FRAME:
        raise InputError(f"{table.source or 'tracks'}: frame {table.frame[starts[k]]} has {counts[k]:,} rows; "
                         f"at most {MAX_PER_FRAME:,} people per frame are evaluated")


def _check_area(area: ArrayLike) -> np.ndarray:
    ring = np.asarray(area, dtype=float)
    if ring.ndim != 2 or ring.shape[1] != 2 or ring.shape[0] < 3 or not np.all(np.isfinite(ring)):
        raise InputError(f"area: expected a floor polygon of at least 3 (x, y) points in metres, "
                         f"got an array of shape {ring.shape}")
    return ring


def drop_ignored(gt: TrackTable, pred: TrackTable, ignore: ArrayLike,
                 gate: float = DEFAULT_GATE_M) -> tuple[TrackTable, TrackTable]:
    """Remove ground truth that should not be scored, and the predictions that found it.

    People barely in view (a hand at the image border, somebody fully behind a pillar) are
    neither required nor forbidden: as in the MOTChallenge protocol, each frame's predictions
    are first matched to *all* ground truth (Hungarian on distance, within ``gate``); predictions
    matched to an ignored person are then dropped together with that person's rows.

    Parameters
    ----------
    gt, pred : TrackTable
    ignore : (len(gt),) bool — ground-truth rows not to score (e.g. ``max vis_<cam> < 0.2``)
    gate : float, metres

    Returns
    -------
    gt_kept, pred_kept : TrackTable
    """
    from scipy.optimize import linear_sum_assignment

    ignore = np.asarray(ignore, dtype=bool)
    if ignore.shape != (len(gt),):
        raise ValueError(f"ignore: expected {len(gt)} flags, got shape {ignore.shape}")
    keep_pred = np.ones(len(pred), dtype=bool)
    g_order, p_order = np.argsort(gt.frame, kind="stable"), np.argsort(pred.frame, kind="stable")
    gf, pf = gt.frame[g_order], pred.frame[p_order]
    for f in np.unique(gt.frame[ignore]):
        gi = g_order[np.searchsorted(gf, f, "left"):np.searchsorted(gf, f, "right")]
        pi = p_order[np.searchsorted(pf, f, "left"):np.searchsorted(pf, f, "right")]
        if len(pi) == 0:
            continue
        d = floor_distances(gt.xy[gi], pred.xy[pi], gate)
        cost = np.where(np.isnan(d), 1e6, d)
        rows, cols = linear_sum_assignment(cost)
        for r, c in zip(rows, cols):
            if cost[r, c] < 1e6 and ignore[gi[r]]:
                keep_pred[pi[c]] = False
    return gt.select(~ignore), pred.select(keep_pred)
