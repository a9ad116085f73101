"""The numbers the papers report, one function each; benchmarks and tests call the same ones.

- Seed 000 (Tables 1–2): mean position error and mean |ΔX|, |ΔY| of matched people
  (:func:`position_errors`).
- Seed 001 (Table 3): precision and recall of following one target (:func:`target_precision_recall`).
- Seed 002: trajectory RMSE inside and outside the cameras' views (:func:`trajectory_rmse_split`).
- Seed 003: rotation error ``arccos((tr(R0·Rᵀ) − 1) / 2)`` in degrees
  (:func:`rotation_errors_deg`) and the angle between true and estimated limb axes
  (:func:`limb_angle_errors_deg`).

Pure NumPy/SciPy: no files, no plots.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import linear_sum_assignment

from worldtrack.eval.mot import _frame_bounds
from worldtrack.geometry.rotation import rotation_angle_deg
from worldtrack.io.tracks import TrackTable


@dataclass(frozen=True)
class PositionErrors:
    """Errors of matched (ground truth, prediction) pairs, seed 000's "mean error, X, Y".

    Attributes
    ----------
    mean_m : float, metres
        Mean Euclidean distance of the pairs; NaN without pairs.
    mean_abs_dx_m, mean_abs_dy_m : float, metres
        Mean |ΔX| and |ΔY|.
    frame, gt_id, pred_id : (K,) int64
        The pairs.
    dx, dy : (K,) float64, metres
        Prediction minus ground truth.
    distance : (K,) float64, metres
    """

    mean_m: float
    mean_abs_dx_m: float
    mean_abs_dy_m: float
    frame: np.ndarray
    gt_id: np.ndarray
    pred_id: np.ndarray
    dx: np.ndarray
    dy: np.ndarray
    distance: np.ndarray

    @property
    def num_pairs(self) -> int:
        return int(self.frame.size)


def position_errors(gt: TrackTable, pred: TrackTable, gate: float = 0.5) -> PositionErrors:
    """Position errors of people matched frame by frame (seed 000, Tables 1–2).

    In every frame present in both tables, ground truth and predictions are paired by the
    Hungarian method (:func:`scipy.optimize.linear_sum_assignment`) on their floor distance:
    first the most pairs within ``gate``, then the smallest total distance. Unlike CLEAR-MOT's
    MOTP this ignores identities and earlier frames, so on crossings it can pair differently.

    Parameters
    ----------
    gt, pred : TrackTable
        Positions ``x, y`` in metres, matched by ``frame``.
    gate : float, metres
        Pairs farther apart than this are not matched.

    Returns
    -------
    PositionErrors

    Examples
    --------
    >>> gt = TrackTable.from_arrays([0, 0], [1, 2], [0.0, 3.0], [0.0, 0.0])
    >>> pr = TrackTable.from_arrays([0, 0], [7, 8], [3.1, 0.0], [0.0, 0.2])
    >>> e = position_errors(gt, pr, gate=0.5)
    >>> round(e.mean_m, 3), round(e.mean_abs_dx_m, 3), round(e.mean_abs_dy_m, 3)
    (0.15, 0.05, 0.1)
    """
    if not (np.isfinite(gate) and gate > 0):
        raise ValueError(f"gate must be a positive distance in metres, got {gate!r}")
    gt, pred = gt.sorted(), pred.sorted()
    frames = np.intersect1d(gt.frame, pred.frame)
    g_lo, g_hi = _frame_bounds(gt.frame, frames)
    p_lo, p_hi = _frame_bounds(pred.frame, frames)
    gxy, pxy = gt.xy, pred.xy
    gi_all: list[np.ndarray] = []
    pi_all: list[np.ndarray] = []
    for k in range(frames.size):
        a, b = gxy[g_lo[k]:g_hi[k]], pxy[p_lo[k]:p_hi[k]]
        d = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=-1)
        allowed = d <= gate
        if allowed.sum(axis=0).max(initial=0) <= 1 and allowed.sum(axis=1).max(initial=0) <= 1:
            # No person and no prediction has two candidates: the assignment below would take
            # exactly these pairs (rows ascending, as linear_sum_assignment returns them).
            r, c = np.nonzero(allowed)
            gi_all.append(g_lo[k] + r)
            pi_all.append(p_lo[k] + c)
            continue
        # A forbidden pair costs more than any set of allowed ones: maximise pairs, then
        # minimise their summed distance.
        big = 2.0 * gate * (min(d.shape) + 1)
        r, c = linear_sum_assignment(np.where(allowed, d, big))
        ok = d[r, c] <= gate
        gi_all.append(g_lo[k] + r[ok])
        pi_all.append(p_lo[k] + c[ok])
    gi = np.concatenate(gi_all) if gi_all else np.zeros(0, np.int64)
    pi = np.concatenate(pi_all) if pi_all else np.zeros(0, np.int64)
    dx = pred.x[pi] - gt.x[gi]
    dy = pred.y[pi] - gt.y[gi]
    dist = np.hypot(dx, dy)
    mean = (lambda v: float(np.mean(v)) if v.size else float("nan"))
    return PositionErrors(mean_m=mean(dist), mean_abs_dx_m=mean(np.abs(dx)),
                          mean_abs_dy_m=mean(np.abs(dy)), frame=gt.frame[gi], gt_id=gt.id[gi],
                          pred_id=pred.id[pi], dx=dx, dy=dy, distance=dist)


def track_positions(table: TrackTable, track_id: int, frames: ArrayLike) -> np.ndarray:
    """Position of one track at each of ``frames``.

    Parameters
    ----------
    table : TrackTable
    track_id : int
    frames : (T,) array_like of int

    Returns
    -------
    (T, 2) float64, metres
        NaN rows where the track has no row in that frame.
    """
    frames = np.asarray(frames, dtype=np.int64).reshape(-1)
    rows = table.id == track_id
    f, xy = table.frame[rows], table.xy[rows]
    out = np.full((frames.size, 2), np.nan)
    order = np.argsort(f, kind="stable")
    f, xy = f[order], xy[order]
    if f.size == 0:
        return out
    k = np.minimum(np.searchsorted(f, frames), f.size - 1)
    hit = f[k] == frames
    out[hit] = xy[k[hit]]
    return out


class TargetCounts(NamedTuple):
    """Seed 001's frame counts: ``a`` correct, ``b`` someone else reported, ``c`` target missed."""

    a: int
    b: int
    c: int


def target_frame_counts(target_xy: ArrayLike, reported_xy: ArrayLike,
                        gate: float = 0.5) -> TargetCounts:
    """Count frames of following one target (seed 001): A, B and C of Table 3.

    Parameters
    ----------
    target_xy : (T, 2) array_like, metres
        The true target's position in each frame; NaN rows where the target is not present
        (outside the range the follower can see).
    reported_xy : (T, 2) array_like, metres
        The position the follower reported as its target; NaN rows where it reported nothing.
    gate : float, metres
        A report within this distance of the true target is correct.

    Returns
    -------
    TargetCounts
        ``a``: frames reported correctly; ``b``: frames with a report that is not the target
        (someone else, or nobody true: the target is absent or farther than ``gate``);
        ``c``: frames with the target present and nothing reported.
    """
    t = np.asarray(target_xy, dtype=float).reshape(-1, 2)
    r = np.asarray(reported_xy, dtype=float).reshape(-1, 2)
    if t.shape != r.shape:
        raise ValueError(f"target_xy {t.shape} and reported_xy {r.shape} must have the same shape")
    present = np.all(np.isfinite(t), axis=1)
    reported = np.all(np.isfinite(r), axis=1)
    with np.errstate(invalid="ignore"):
        near = np.linalg.norm(r - t, axis=1) <= gate       # False where either is NaN
    a = present & reported & near
    b = reported & ~a
    c = present & ~reported
    return TargetCounts(int(a.sum()), int(b.sum()), int(c.sum()))


def target_precision_recall(target_xy: ArrayLike, reported_xy: ArrayLike,
                            gate: float = 0.5) -> tuple[float, float]:
    """Seed 001's follow-a-target precision ``A/(A+B)`` and recall ``A/(A+C)``.

    Arguments as :func:`target_frame_counts`; build them from track tables with
    :func:`track_positions` (the true target's id in the ground truth, the id the follower
    reports in its output). NaN where a denominator is 0.

    Examples
    --------
    >>> nan = float("nan")
    >>> target = [[0, 0], [0, 0], [0, 0], [nan, nan]]
    >>> reported = [[0.1, 0], [2, 0], [nan, nan], [nan, nan]]
    >>> target_precision_recall(target, reported, gate=0.5)   # A=1, B=1, C=1
    (0.5, 0.5)
    """
    a, b, c = target_frame_counts(target_xy, reported_xy, gate)
    precision = a / (a + b) if a + b else float("nan")   # A / (A + B)
    recall = a / (a + c) if a + c else float("nan")      # A / (A + C)
    return float(precision), float(recall)


def rotation_errors_deg(R_true: ArrayLike, R_est: ArrayLike) -> np.ndarray:
    """Per-frame rotation error ``arccos((tr(R0·Rᵀ) − 1) / 2)`` in degrees (seed 003).

    Parameters
    ----------
    R_true, R_est : (T, 3, 3) array_like

    Returns
    -------
    (T,) float64, degrees
    """
    a, b = np.asarray(R_true, dtype=float), np.asarray(R_est, dtype=float)
    if a.shape != b.shape or a.shape[-2:] != (3, 3):
        raise ValueError(f"R_true {a.shape} and R_est {b.shape} must both be (T, 3, 3)")
    return np.asarray(rotation_angle_deg(a, b), dtype=float)


def limb_angle_errors_deg(axis_true: ArrayLike, axis_est: ArrayLike) -> np.ndarray:
    """Per-frame angle between the true and estimated limb axes in degrees (seed 003).

    Parameters
    ----------
    axis_true, axis_est : (T, 3) array_like
        Limb direction vectors (e.g. joint to joint); need not be unit length.

    Returns
    -------
    (T,) float64, degrees in [0, 180]
        NaN where an axis has zero length.
    """
    a, b = np.asarray(axis_true, dtype=float), np.asarray(axis_est, dtype=float)
    if a.shape != b.shape or a.shape[-1] != 3:
        raise ValueError(f"axis_true {a.shape} and axis_est {b.shape} must both be (T, 3)")
    # θ = atan2(‖a × b‖, a · b): accurate at small angles, where arccos of the cosine is not.
    cross = np.linalg.norm(np.cross(a, b), axis=-1)
    dot = np.sum(a * b, axis=-1)
    deg = np.degrees(np.arctan2(cross, dot))
    zero = (np.linalg.norm(a, axis=-1) == 0) | (np.linalg.norm(b, axis=-1) == 0)
    return np.where(zero, np.nan, deg)


class RmseSplit(NamedTuple):
    """Trajectory RMSE (metres) where a camera saw the person and where none did."""

    observed_m: float
    unobserved_m: float
    num_observed: int
    num_unobserved: int


def trajectory_rmse_split(true_xyz: ArrayLike, est_xyz: ArrayLike, observed: ArrayLike) -> RmseSplit:
    """RMSE of an estimated trajectory inside vs outside the cameras' views (seed 002).

    ``RMSE = sqrt(mean_t ‖x̂_t − x_t‖²)`` over the frames of each group.

    Parameters
    ----------
    true_xyz, est_xyz : (T, 3) array_like, metres
    observed : (T,) array_like of bool
        True where at least one camera saw the person.

    Returns
    -------
    RmseSplit
        NaN for a group without frames.
    """
    t, e = np.asarray(true_xyz, dtype=float), np.asarray(est_xyz, dtype=float)
    obs = np.asarray(observed, dtype=bool).reshape(-1)
    if t.shape != e.shape or t.ndim != 2 or obs.shape[0] != t.shape[0]:
        raise ValueError(f"true_xyz {t.shape}, est_xyz {e.shape} must be (T, 3) and observed "
                         f"{obs.shape} (T,)")
    sq = np.sum((e - t) ** 2, axis=1)                  # ‖x̂_t − x_t‖²

    def rmse(mask: np.ndarray) -> float:
        return float(np.sqrt(np.mean(sq[mask]))) if np.any(mask) else float("nan")

    return RmseSplit(rmse(obs), rmse(~obs), int(obs.sum()), int((~obs).sum()))
