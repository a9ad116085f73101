"""Evaluation pictures: position error over time and a floor plan of true vs predicted paths.

Matplotlib through the Agg canvas only (no ``pyplot`` state, no display needed).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from numpy.typing import ArrayLike

from worldtrack.errors import InputError
from worldtrack.io.tracks import TrackTable

_UNMATCHED = "0.55"  # grey for predicted tracks that never matched anyone


def _colour(k: int) -> Any:
    from matplotlib import colormaps
    cmap = colormaps["tab10"] if k < 10 else colormaps["tab20"]
    return cmap(k % cmap.N)


def assign_pred_to_gt(pairs: dict[str, np.ndarray], pred_ids: ArrayLike) -> dict[int, int | None]:
    """One-to-one pairing of predicted ids with ground-truth ids, for colouring.

    Maximises the number of frames in which paired ids were matched (Hungarian method on the
    (GT × predicted) count matrix); a predicted id left over, or paired with nobody it ever
    matched, maps to None.

    Parameters
    ----------
    pairs : dict with (K,) ``gt_id`` and ``pred_id``
        Matched pairs, as in :attr:`worldtrack.eval.mot.MotEvaluation.pairs`.
    pred_ids : (P,) array_like of int
    """
    from scipy.optimize import linear_sum_assignment

    pred_ids = np.asarray(pred_ids, dtype=np.int64)
    out: dict[int, int | None] = {int(p): None for p in pred_ids}
    if pairs["gt_id"].size == 0 or pred_ids.size == 0:
        return out
    g_ids = np.unique(pairs["gt_id"])
    gi = np.searchsorted(g_ids, pairs["gt_id"])
    pi = np.searchsorted(pred_ids, pairs["pred_id"])
    known = (pi < pred_ids.size) & (pred_ids[np.minimum(pi, pred_ids.size - 1)] == pairs["pred_id"])
    count = np.zeros((g_ids.size, pred_ids.size))
    np.add.at(count, (gi[known], pi[known]), 1.0)
    r, c = linear_sum_assignment(-count)
    for i, j in zip(r, c):
        if count[i, j] > 0:
            out[int(pred_ids[j])] = int(g_ids[i])
    return out


def plot_evaluation(path: str | Path, gt: TrackTable, pred: TrackTable,
                    pairs: dict[str, np.ndarray], gate: float | None = None,
                    area: ArrayLike | None = None, title: str | None = None) -> None:
    """Write a PNG with two panels.

    Left: position error (metres) of every matched pair over time, one line per ground-truth
    track. Right: floor plan (x, y in metres, equal aspect) with ground-truth paths solid and
    predicted paths dashed; colours are per ground-truth id, and each predicted id takes the
    colour of the ground-truth id it is paired with one-to-one by :func:`assign_pred_to_gt`
    (grey if none). A correct track is a dashed line over a solid one of the same colour; an
    identity swap shows as a dashed line leaving its colour's path.

    Parameters
    ----------
    path : str or Path
        Output PNG.
    gt, pred : TrackTable
    pairs : dict of (K,) arrays ``frame, gt_id, pred_id, distance``
        Matched pairs (see :func:`worldtrack.eval.mot.evaluate_detailed`).
    gate : float, metres, optional
        Drawn as a horizontal line on the error panel.
    area : (M, 2) array_like, metres, optional
        Evaluation area, drawn on the floor plan.
    title : str, optional
    """
    gt, pred = gt.sorted(), pred.sorted()
    gt_ids = gt.ids()
    colour = {int(g): _colour(k) for k, g in enumerate(gt_ids)}

    fig = Figure(figsize=(12, 5.5), layout="constrained")
    FigureCanvasAgg(fig)
    ax_err, ax_map = fig.subplots(1, 2, width_ratios=(1.2, 1))

    # Time axis: ground-truth time stamps if the file had them, else frame numbers.
    gt_frames = gt.frame
    have_time = gt.time.size > 0 and np.all(np.isfinite(gt.time))
    if have_time:
        uniq, first = np.unique(gt_frames, return_index=True)
        k = np.minimum(np.searchsorted(uniq, pairs["frame"]), uniq.size - 1)
        t_pairs = np.where(uniq[k] == pairs["frame"], gt.time[first][k], np.nan)
        ax_err.set_xlabel("time [s]")
    else:
        t_pairs = pairs["frame"].astype(float)
        ax_err.set_xlabel("frame")
    for g in gt_ids:
        sel = pairs["gt_id"] == g
        if np.any(sel):
            # Break the line where the track was not matched (frame gap > 1).
            f = pairs["frame"][sel]
            order = np.argsort(f)
            f, t, d = f[order], t_pairs[sel][order], pairs["distance"][sel][order]
            gap = np.flatnonzero(np.diff(f) > 1) + 1
            t = np.insert(t, gap, np.nan)
            d = np.insert(d, gap, np.nan)
            ax_err.plot(t, d, "-", color=colour[int(g)], lw=1.2, label=f"GT {g}")
            if len(gt_ids) > 12:            # too many for a legend: name each line where it ends
                last = np.flatnonzero(np.isfinite(d))[-1]
                ax_err.annotate(f"{g}", (t[last], d[last]), xytext=(2, 0), textcoords="offset points",
                                fontsize=6, color=colour[int(g)], va="center")
    if gate is not None:
        ax_err.axhline(gate, color="k", ls=":", lw=0.8, label=f"gate {gate:g} m")
    ax_err.set_ylabel("position error [m]")
    ax_err.set_ylim(bottom=0)
    ax_err.set_title("error of matched pairs")
    ax_err.grid(alpha=0.3)
    if len(gt_ids) <= 12:
        ax_err.legend(fontsize="small", loc="upper right", title="ground-truth id")
    else:
        ax_err.plot([], [], "-", color="0.3", label="one line per ground-truth id (named at its end)")
        ax_err.legend(fontsize="small", loc="upper right")

    if area is not None:
        ring = np.asarray(area, dtype=float)
        closed = np.vstack([ring, ring[:1]])
        ax_map.fill(ring[:, 0], ring[:, 1], color="0.92", zorder=0)
        ax_map.plot(closed[:, 0], closed[:, 1], color="0.6", lw=0.8, zorder=0)
    for g in gt_ids:
        rows = gt.id == g
        ax_map.plot(gt.x[rows], gt.y[rows], "-", color=colour[int(g)], lw=1.6)
        ax_map.plot(gt.x[rows][:1], gt.y[rows][:1], "o", color=colour[int(g)], ms=4)
        ax_map.annotate(f"{g}", (gt.x[rows][0], gt.y[rows][0]), xytext=(3, 3), textcoords="offset points",
                        fontsize=7, color=colour[int(g)])
    owner = assign_pred_to_gt(pairs, pred.ids())
    for pid, g in owner.items():
        rows = pred.id == pid
        c = colour.get(g, _UNMATCHED) if g is not None else _UNMATCHED
        ax_map.plot(pred.x[rows], pred.y[rows], "--", color=c, lw=1.1)
    ax_map.plot([], [], "-", color="k", label="ground truth (id at start)")
    ax_map.plot([], [], "--", color="k", label="predicted, in the colour of its person")
    ax_map.plot([], [], "--", color=_UNMATCHED, label="predicted, matched nobody")
    ax_map.set_aspect("equal", adjustable="datalim")
    ax_map.set_xlabel("x [m]")
    ax_map.set_ylabel("y [m]")
    ax_map.set_title("floor plan")
    ax_map.grid(alpha=0.3)
    ax_map.legend(fontsize="small", loc="best")
    if title:
        fig.suptitle(title, fontsize="medium")
    try:
        fig.savefig(path, dpi=100)
    except OSError as e:
        raise InputError(f"{path}: cannot write: {e.strerror or e}") from None
