"""Seed 001's measures of following one target, frame by frame, and the issue's extra ones.

Every frame gets one label (the paper's Table 3 counts them):

* ``A`` — the follower reported a position and the true target is the person nearest to it,
  within ``gate`` metres;
* ``B`` — it reported a position that is not the target's (someone else, or nobody);
* ``C`` — it reported nothing although the target was *visible* (at least ``vis_min`` of it in
  view, the rest of frames the paper's "present");
* ``N`` — it reported nothing and the target was not visible: correct silence.

precision = A / (A + B), recall = A / (A + C). A report of a half-hidden target is A, not B.

Beyond the paper: **swaps** (runs of B frames of at least ``min_s`` seconds — the follower locked
on to someone else), **re-acquisition delays** after each occlusion (seconds from the first frame the
target is visible again to the first A frame), and the dissimilarity D of the true target and of
every other person, matched to the candidates by position (Tables 1–2).

>>> import numpy as np
>>> nan = np.nan
>>> target = np.array([[0, 0], [0, 0], [0, 0], [0, 0]], float)
>>> visible = np.array([True, True, True, False])
>>> reported = np.array([[0.1, 0], [2, 0], [nan, nan], [nan, nan]])
>>> others = [np.zeros((0, 2))] * 4
>>> follow_labels(target, visible, reported, others).tolist()
['A', 'B', 'C', 'N']
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy.optimize import linear_sum_assignment


def follow_labels(target_xy: np.ndarray, visible: np.ndarray, reported_xy: np.ndarray, others_xy: list,
                  gate: float = 0.5) -> np.ndarray:
    """(T,) labels 'A', 'B', 'C', 'N' (see the module docstring).

    Parameters
    ----------
    target_xy : (T, 2) metres, NaN where the target is not in the scene
    visible : (T,) bool — the target is visible enough to be expected (for C)
    reported_xy : (T, 2) metres, NaN where nothing was reported
    others_xy : list of T arrays (K_t, 2) — the other people's positions in each frame
    """
    t = np.asarray(target_xy, float).reshape(-1, 2)
    r = np.asarray(reported_xy, float).reshape(-1, 2)
    reported = np.all(np.isfinite(r), axis=1)
    with np.errstate(invalid="ignore"):
        d_target = np.hypot(*(r - t).T)
    near_other = np.array([np.hypot(*(o - rr).T).min() if len(o) and ok else np.inf
                           for o, rr, ok in zip(others_xy, r, reported)])
    a = reported & (d_target <= gate) & (d_target <= near_other)
    labels = np.full(len(t), "N", dtype="<U1")
    labels[reported & ~a] = "B"
    labels[a] = "A"
    labels[~reported & np.asarray(visible, bool)] = "C"
    return labels


class Counts(NamedTuple):
    """Frames of each label and the two ratios (NaN without a denominator)."""

    a: int
    b: int
    c: int
    precision: float
    recall: float


def counts(labels: np.ndarray) -> Counts:
    """A, B, C, precision = A/(A+B), recall = A/(A+C)."""
    a, b, c = (int(np.sum(labels == x)) for x in "ABC")
    return Counts(a, b, c, a / (a + b) if a + b else float("nan"), a / (a + c) if a + c else float("nan"))


def counts_by(labels: np.ndarray, groups: np.ndarray) -> dict:
    """:func:`counts` for each value of ``groups`` (T,), e.g. the lighting segment."""
    return {g: counts(labels[groups == g]) for g in dict.fromkeys(groups.tolist())}


def runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """(start, stop) index pairs of the runs of True in ``mask``."""
    m = np.concatenate([[False], np.asarray(mask, bool), [False]])
    edges = np.flatnonzero(np.diff(m.astype(np.int8)))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist()))


def swaps(labels: np.ndarray, times: np.ndarray, min_s: float = 0.3) -> list[tuple[float, float]]:
    """(start time, duration s) of each run of B frames lasting at least ``min_s`` seconds."""
    out = []
    dt = float(np.median(np.diff(times))) if len(times) > 1 else 0.0
    for s, e in runs(labels == "B"):
        dur = times[e - 1] - times[s] + dt
        if dur >= min_s - 1e-9:
            out.append((float(times[s]), float(dur)))
    return out


class Occlusion(NamedTuple):
    """The target was not visible from ``start`` to ``stop`` (indices; ``stop`` visible again)."""

    start: int
    stop: int
    duration: float
    delay: float


def reacquisitions(labels: np.ndarray, visible: np.ndarray, in_scene: np.ndarray, times: np.ndarray) -> list:
    """Every occlusion (a run of frames with the target in the scene but not visible, between
    visible frames) and the delay (s) from its end to the first A frame (inf: never)."""
    out = []
    dt = float(np.median(np.diff(times))) if len(times) > 1 else 0.0
    hidden = np.asarray(in_scene, bool) & ~np.asarray(visible, bool)
    for s, e in runs(hidden):
        if s == 0 or e >= len(labels) or not visible[s - 1] or not visible[e]:
            continue
        hits = np.flatnonzero(labels[e:] == "A")
        delay = float(times[e + hits[0]] - times[e]) if len(hits) else float("inf")
        out.append(Occlusion(s, e, float(times[e - 1] - times[s] + dt), delay))
    return out


def match_candidates(candidates_xy: np.ndarray, people_xy: np.ndarray, gate: float = 0.5) -> np.ndarray:
    """(P,) index of the candidate matched to each person (one-to-one, nearest, within ``gate``), −1 if none."""
    out = np.full(len(people_xy), -1, dtype=np.int64)
    if len(candidates_xy) == 0 or len(people_xy) == 0:
        return out
    d = np.hypot(*(people_xy[:, None, :] - candidates_xy[None, :, :]).transpose(2, 0, 1))
    rows, cols = linear_sum_assignment(np.where(d <= gate, d, 1e6))
    ok = d[rows, cols] <= gate
    out[rows[ok]] = cols[ok]
    return out


def dissimilarity_table(values: dict) -> dict:
    """person id → (mean, sd, frames) of the D values collected for them (Tables 1–2)."""
    return {pid: (float(np.mean(v)), float(np.std(v)), len(v)) for pid, v in values.items() if len(v)}
