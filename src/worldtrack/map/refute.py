"""The evidence against a person on the shared map: what makes the fusion drop somebody no worker
shows well (:func:`refute`). Pure, called by :func:`worldtrack.map.fusion.fuse_bucket`."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from worldtrack.map.config import MapConfig
from worldtrack.map.evidence import LEAD_SHARE
from worldtrack.map.messages import REFUTED, Estimate, Observation

if TYPE_CHECKING:
    from worldtrack.map.fusion import FusionState

#: Less than this share of a person's body their own (not covered by other people) in a view:
#: that view may be showing somebody else (the ellipsoid tracker's ``min_own_share``).
MIN_OWN_SHARE = 0.25


def refute(state: "FusionState", estimates: dict[int, dict[str, Estimate]], observations: list[Observation],
            t: float, cfg: MapConfig) -> dict[int, int]:
    """Drop a person no worker shows well, on the evidence against them (``{id: REFUTED}``):

    * *negative*: only views showing less than :data:`LEAD_SHARE` of them report them (through a
      door, behind somebody) while another worker's camera shows their place clearly and empty
      (``Observation.absent``), ``cfg.refute_after`` buckets running; also when they are shown
      well but younger than ``cfg.confirm_birth_s`` (a birth the other view does not confirm);
    * *hidden*: one worker reports them, covered by other people it holds (less than
      :data:`MIN_OWN_SHARE` of the body its own: a copy of somebody behind them on its line of
      sight), while other workers are on the map, for ``cfg.hidden_after_s`` — the one-process
      tracker's rule for a person at most one of several cameras shows inside somebody else's
      silhouette. A person any worker shows well is kept."""
    against: dict[int, set[str]] = {}
    for o in observations:
        for i in o.absent:
            against.setdefault(state.resolve(i), set()).add(o.worker)
    several = len({o.worker for o in observations}) > 1
    hidden_after = round(cfg.hidden_after_s / cfg.bucket_s) if cfg.hidden_after_s > 0 else math.inf
    refuted: dict[int, int] = {}
    for pid, by_worker in estimates.items():
        p = state.people.get(pid)
        if p is None:
            continue
        well_seen = any(e.seen and e.visible >= LEAD_SHARE for e in by_worker.values())
        seen_by = {k for k, e in by_worker.items() if e.seen}
        young = t - p.born < cfg.confirm_birth_s           # a birth another worker's view does not confirm
        p.doubt = p.doubt + 1 if against.get(pid, set()) - seen_by and (young or not well_seen) else 0
        covered = len(by_worker) == 1 and several and all(e.own < MIN_OWN_SHARE for e in by_worker.values())
        p.hidden = p.hidden + 1 if covered else 0
        if p.doubt >= cfg.refute_after or p.hidden >= hidden_after:
            del state.people[pid]
            state.aliases[pid] = (REFUTED, t)
            refuted[pid] = REFUTED
    return refuted


__all__ = ["MIN_OWN_SHARE", "refute"]
