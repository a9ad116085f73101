"""Ids the shared map finds to be one person (:func:`merge_duplicates`): two workers that started
the same person, or one worker's first estimate of somebody it sees from afar. Pure, called by
:func:`worldtrack.map.fusion.fuse_bucket`."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Iterable, Mapping

import numpy as np

from worldtrack.map.config import MapConfig
from worldtrack.map.messages import Estimate

if TYPE_CHECKING:
    from worldtrack.map.fusion import FusionState

#: The least weight an estimate has (support 0 still says "a worker sees somebody here").
MIN_WEIGHT = 0.05


def merge_duplicates(state: "FusionState", workers_of: dict[int, set[str]], t: float,
                      cfg: MapConfig, estimates: Mapping[int, Mapping[str, Estimate]] | None = None) -> dict[int, int]:
    """Fold the younger of two ids that stay within ``merge_distance_m`` for ``merge_after_s`` into
    the elder, unless a worker sees both (then they are two people that worker tells apart: two
    people crossing in one worker's view while another worker sees only one of them are not
    merged; with ``crossing_s`` neither when a worker saw both that recently: each camera now shows
    only the one in front). Two ids both younger than ``merge_after_s`` (two workers starting the same person in
    the same frames: no history could tell them apart) are merged at once — also farther apart than
    ``merge_distance_m`` when the workers' tracker covariances (``estimates``) put them within
    ``newborn_gate`` (a far view's first estimate through a door is off by more than 0.5 m in depth,
    and says so). Returns ``{younger: elder}``."""
    from scipy.spatial import cKDTree
    ids = sorted(workers_of)
    close_now = set()
    if cfg.crossing_s > 0:
        remember_together(state, workers_of, t, cfg.crossing_s, _held_xy(estimates or {}), cfg.crossing_apart_m)
    if len(ids) >= 2:
        xy = np.array([[state.people[i].x, state.people[i].y] for i in ids])
        for i, j in cKDTree(xy).query_pairs(cfg.merge_distance_m):
            a, b = min(ids[i], ids[j]), max(ids[i], ids[j])
            if workers_of[a] & workers_of[b] or not workers_of[a] or not workers_of[b]:
                continue      # a worker that sees both holds them apart: two people
            if t - state.together.get((a, b), -math.inf) <= cfg.crossing_s:
                continue      # and did so moments ago: one is behind the other in each view now
            close_now.add((a, b))
        close_now |= _newborns_within_gate(state, workers_of, t, cfg, estimates or {}, xy, ids)
    state.close_since = {pair: state.close_since.get(pair, t) for pair in close_now}
    merged: dict[int, int] = {}
    for (a, b), since in sorted(state.close_since.items()):
        pa, pb = state.people[a], state.people[b]
        newborn = t - min(pa.born, pb.born) < cfg.merge_after_s    # both just started: nothing to wait for
        if (t - since < cfg.merge_after_s and not newborn) or a in merged or b in merged:
            continue
        elder, younger = (pa, pb) if (pa.born, pa.id) <= (pb.born, pb.id) else (pb, pa)
        wa, wb = max(MIN_WEIGHT, _finite(elder.support)), max(MIN_WEIGHT, _finite(younger.support))
        elder.x = (wa * elder.x + wb * younger.x) / (wa + wb)
        elder.y = (wa * elder.y + wb * younger.y) / (wa + wb)
        elder.workers += younger.workers
        del state.people[younger.id]
        state.aliases[younger.id] = (elder.id, t)
        merged[younger.id] = elder.id
    state.close_since = {k: v for k, v in state.close_since.items() if k[0] not in merged and k[1] not in merged}
    return merged


def remember_together(state: "FusionState", workers_of: Mapping[int, set[str]], t: float, memory_s: float,
                      held_xy: Mapping[str, Mapping[int, tuple[float, float]]] | None = None,
                      apart_m: float = 0.0) -> None:
    """Note in ``state.together`` every pair of ids ``(a, b)``, ``a < b``, some worker sees at ``t``
    (s) at least ``apart_m`` (m) apart where that worker holds them (``held_xy``: per worker, id →
    (x, y) m; an id missing there counts as apart); forget pairs older than ``memory_s`` (s) or with
    a person gone from the map."""
    by_worker: dict[str, list[int]] = {}
    for pid in sorted(workers_of):
        for w in sorted(workers_of[pid]):
            by_worker.setdefault(w, []).append(pid)
    for w, held in by_worker.items():
        state.together = held_together(state.together, held, t, memory_s, (held_xy or {}).get(w), apart_m)
    state.together = {k: s for k, s in state.together.items() if k[0] in state.people and k[1] in state.people}


def held_together(together: Mapping[tuple[int, int], float], ids: Iterable[int], t: float, memory_s: float,
                  xy: Mapping[int, tuple[float, float]] | None = None,
                  apart_m: float = 0.0) -> dict[tuple[int, int], float]:
    """``together`` (pairs of ids ``(a, b)``, ``a < b``: when last held at the same time, s) with
    every pair of ``ids`` held at ``t`` (s), pairs older than ``memory_s`` (s) left out (``memory_s``
    0: none noted, ``{}``).

    With ``apart_m`` > 0 only pairs held at least that far apart (``xy``: id → (x, y), m; an id
    without a position counts as apart) are noted: two people crossing were apart before one hid
    the other, while a tracker's duplicate is born on top of its twin and is no second person.

    >>> held_together({(1, 9): 0.0}, [3, 1, 2], 5.0, 2.0)
    {(1, 2): 5.0, (1, 3): 5.0, (2, 3): 5.0}
    >>> held_together({}, [1, 2, 3], 5.0, 2.0, {1: (0.0, 0.0), 2: (0.1, 0.0), 3: (2.0, 0.0)}, 0.5)
    {(1, 3): 5.0, (2, 3): 5.0}
    """
    if memory_s <= 0:
        return {}
    ids = sorted(set(ids))
    out = {k: s for k, s in together.items() if t - s <= memory_s}
    pairs = [(a, b) for k, a in enumerate(ids) for b in ids[k + 1:]]
    if apart_m > 0 and xy:
        pairs = [(a, b) for a, b in pairs if a not in xy or b not in xy or
                 math.hypot(xy[a][0] - xy[b][0], xy[a][1] - xy[b][1]) >= apart_m]
    out.update({pair: t for pair in pairs})
    return dict(sorted(out.items()))


def _held_xy(estimates: Mapping[int, Mapping[str, Estimate]]) -> dict[str, dict[int, tuple[float, float]]]:
    """Per worker, where it holds each id it reports: id → (x, y), m."""
    out: dict[str, dict[int, tuple[float, float]]] = {}
    for pid, by_worker in estimates.items():
        for w, e in by_worker.items():
            out.setdefault(w, {})[pid] = (e.x, e.y)
    return out


def _newborns_within_gate(state: "FusionState", workers_of: dict[int, set[str]], t: float, cfg: MapConfig,
                          estimates: Mapping[int, Mapping[str, Estimate]], xy: np.ndarray,
                          ids: list[int]) -> set[tuple[int, int]]:
    """Pairs of ids both younger than ``merge_after_s``, from different workers, at most
    ``2 · merge_distance_m`` apart, whose squared Mahalanobis distance under the sum of their
    estimates' covariances is below ``newborn_gate``."""
    from scipy.spatial import cKDTree
    if cfg.newborn_gate <= 0:
        return set()
    out = set()
    for i, j in cKDTree(xy).query_pairs(2 * cfg.merge_distance_m):
        a, b = min(ids[i], ids[j]), max(ids[i], ids[j])
        pa, pb = state.people[a], state.people[b]
        if not workers_of[a] or not workers_of[b] or workers_of[a] & workers_of[b] or \
                t - min(pa.born, pb.born) >= cfg.merge_after_s:
            continue
        ca, cb = _covariance(estimates.get(a, {})), _covariance(estimates.get(b, {}))
        if ca is None or cb is None:
            continue
        d = np.array([pa.x - pb.x, pa.y - pb.y])
        if float(d @ np.linalg.solve(ca + cb, d)) < cfg.newborn_gate:
            out.add((a, b))
    return out


def _covariance(estimates_of: Mapping[str, Estimate]) -> np.ndarray | None:
    """The covariance (m²) of a person's fused position: its workers' seen estimates' tracker
    covariances, their information added; None when one of them has none."""
    infos = []
    for e in estimates_of.values():
        c = np.array([[e.cxx, e.cxy], [e.cxy, e.cyy]])
        if not e.seen:
            continue
        if not np.all(np.isfinite(c)) or np.linalg.det(c) <= 0:
            return None
        infos.append(np.linalg.inv(c))
    return np.linalg.inv(sum(infos)) if infos else None


def _finite(v: float) -> float:
    return v if v is not None and math.isfinite(v) else 0.0


__all__ = ["MIN_WEIGHT", "held_together", "merge_duplicates", "remember_together"]
