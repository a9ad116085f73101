"""HOTA of world-coordinate tracks: TrackEval's own ``HOTA`` metric, fed floor distances in metres.

HOTA (Luiten et al., IJCV 2021) splits tracking quality into detection (DetA) and association
(AssA): ``HOTA_α = sqrt(DetA_α · AssA_α)``, averaged over 19 localisation thresholds
``α = 0.05, 0.10, …, 0.95``. The counting (the per-frame Hungarian matching that prefers pairs
whose identities agree over the whole sequence, the association scores) is TrackEval's
:class:`trackeval.metrics.HOTA`; this module only decides *what is compared*: the similarity of a
person and a track in a frame is

    sim = max(0, 1 − d / gate)

with ``d`` their distance on the floor in metres, so a pair counts at threshold ``α`` when it is
within ``(1 − α) · gate`` metres: the 19 thresholds run from 0.05 · gate to 0.95 · gate. The frames
and rows compared are those of :func:`worldtrack.eval.evaluate_detailed` (its area and frame
range), which calls :func:`evaluate_hota` and reports ``hota``, ``hota_deta``, ``hota_assa`` and
``hota_loca`` beside MOTA and IDF1.

TrackEval comes from PyPI ``trackeval==1.3.0``, installed **without its dependencies**
(``pip install --no-deps trackeval==1.3.0``, as the Makefile does): it declares ``opencv-python``
(a second OpenCV owning ``cv2`` beside our ``opencv-python-headless``) and ``pycocotools``, which
its HOTA class does not use. Without TrackEval, :func:`evaluate_hota` returns None and the metrics say n/a.
"""

from __future__ import annotations

import contextlib
import io
from dataclasses import dataclass
from collections.abc import Iterable
from functools import cache
from typing import Any

import numpy as np

from worldtrack.io.tracks import TrackTable

#: How to install TrackEval the way the project does (shown when it is missing).
INSTALL_HINT = "pip install --no-deps trackeval==1.3.0"


@dataclass(frozen=True)
class HotaResult:
    """HOTA and its parts, each the mean over TrackEval's 19 thresholds α.

    Attributes
    ----------
    hota : float — sqrt(DetA · AssA), averaged over α
    deta : float — detection accuracy TP / (TP + FN + FP)
    assa : float — association accuracy of the matched pairs
    loca : float — mean similarity of the matched pairs (1 − d / gate)
    per_alpha : dict of str → (19,) ndarray — TrackEval's arrays (``HOTA``, ``DetA``, ``AssA``, …)
    """

    hota: float
    deta: float
    assa: float
    loca: float
    per_alpha: dict[str, np.ndarray]


@cache
def _hota_metric() -> Any:
    """TrackEval's HOTA metric object, or None when TrackEval is not installed.

    Importing ``trackeval`` imports its datasets, one of which prints a line about the missing
    ``pycocotools``; that line is swallowed here.
    """
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            from trackeval.metrics import HOTA
    except ImportError:
        return None
    return HOTA()


def hota_available() -> bool:
    """True when TrackEval is installed (see the module notes)."""
    return _hota_metric() is not None


def _dense_ids(ids: np.ndarray) -> tuple[np.ndarray, int]:
    """Ids renumbered 0 … K−1 (TrackEval indexes its count arrays by id), and K."""
    unique, dense = np.unique(ids, return_inverse=True)
    return dense.reshape(-1).astype(np.int64), int(unique.size)


def sequence_data(gt: TrackTable, pred: TrackTable, frames: np.ndarray, gate: float,
                  distances: Iterable[np.ndarray] | None = None) -> dict[str, Any]:
    """TrackEval's per-sequence ``data`` dict for ``frames``, similarity ``max(0, 1 − d / gate)``.

    Parameters
    ----------
    gt, pred : TrackTable — positions in metres
    frames : (F,) int — the frames evaluated, in order (frames without rows are empty time steps)
    gate : metres
    distances : iterable of F (G, P) ndarrays, metres, optional
        The frames' distance matrices, in order, if already computed (NaN = beyond the gate, similarity 0),
        as :func:`worldtrack.eval.evaluate_detailed` passes them; computed here otherwise.

    Returns
    -------
    dict with ``num_timesteps, num_gt_ids, num_tracker_ids, num_gt_dets, num_tracker_dets`` and, per
    time step, ``gt_ids``, ``tracker_ids`` (dense ids) and ``similarity_scores`` (G, P)
    """
    gt, pred = gt.sorted(), pred.sorted()
    frames = np.asarray(frames, dtype=np.int64)
    gt_dense, n_gt = _dense_ids(gt.id)
    pred_dense, n_pred = _dense_ids(pred.id)
    g_lo, g_hi = np.searchsorted(gt.frame, frames, "left"), np.searchsorted(gt.frame, frames, "right")
    p_lo, p_hi = np.searchsorted(pred.frame, frames, "left"), np.searchsorted(pred.frame, frames, "right")
    gxy, pxy = gt.xy, pred.xy
    gt_ids, tracker_ids, similarity = [], [], []
    given = None if distances is None else iter(distances)
    for k in range(frames.size):
        gs, ps = slice(g_lo[k], g_hi[k]), slice(p_lo[k], p_hi[k])
        d = np.linalg.norm(gxy[gs, None, :] - pxy[None, ps, :], axis=-1) if given is None else next(given)
        gt_ids.append(gt_dense[gs])
        tracker_ids.append(pred_dense[ps])
        similarity.append(np.fmax(0.0, 1.0 - d / gate))   # fmax: NaN (beyond the gate) → 0
    return {"num_timesteps": int(frames.size), "num_gt_ids": n_gt, "num_tracker_ids": n_pred,
            "num_gt_dets": int(sum(g.size for g in gt_ids)),
            "num_tracker_dets": int(sum(p.size for p in tracker_ids)),
            "gt_ids": gt_ids, "tracker_ids": tracker_ids, "similarity_scores": similarity}


def evaluate_hota(gt: TrackTable, pred: TrackTable, gate: float, frames: np.ndarray | None = None,
                  distances: Iterable[np.ndarray] | None = None) -> HotaResult | None:
    """HOTA of ``pred`` against ``gt`` on the floor, with TrackEval's ``HOTA`` metric.

    Parameters
    ----------
    gt, pred : TrackTable
        Ground truth and tracks, positions ``x, y`` in metres, matched by ``frame``.
    gate : float, metres
        Distance at which the similarity ``1 − d / gate`` reaches 0.
    frames : (F,) int, optional
        The frames to evaluate (default: every frame of either table).
    distances : iterable of F (G, P) ndarrays, metres, optional
        Each frame's distance matrix, rows and columns in :meth:`TrackTable.sorted` order (NaN
        beyond the gate); saves computing them again when the caller has them.

    Returns
    -------
    HotaResult, or None when TrackEval is not installed.

    Examples
    --------
    >>> t = TrackTable.from_arrays([0, 1, 1], [1, 1, 2], [0.0, 1.0, 5.0], [0.0, 0.0, 5.0])
    >>> round(evaluate_hota(t, t, gate=1.0).hota, 6)
    1.0
    """
    metric = _hota_metric()
    if metric is None:
        return None
    if frames is None:
        frames = np.union1d(gt.frame, pred.frame)
    with np.errstate(invalid="ignore", divide="ignore"):   # 0/0 of ids never near each other
        res = metric.eval_sequence(sequence_data(gt, pred, frames, gate, distances))
    per_alpha = {k: np.asarray(res[k], dtype=float) for k in metric.float_array_fields + metric.integer_array_fields}
    return HotaResult(hota=float(per_alpha["HOTA"].mean()), deta=float(per_alpha["DetA"].mean()),
                      assa=float(per_alpha["AssA"].mean()), loca=float(per_alpha["LocA"].mean()),
                      per_alpha=per_alpha)
