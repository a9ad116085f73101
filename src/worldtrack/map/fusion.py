"""Merging observations of the same person from different workers: one map state per time bucket.

This is the answer worldtrack gives to the question paper 000 leaves open (§5–6: several systems,
each with its own cameras, share one person map — who updates a person two of them see?):

* **Every worker that sees a person updates them, on its own map, from its own cameras**, and
  publishes its estimate. A worker never moves a person its cameras do not show: those it takes
  from the shared map as they are (:mod:`worldtrack.map.worker`). With ``map.share_rule``
  ``information`` (the default), every worker that sees a person starts each frame from the
  map's estimate (the common prior, at the time of its previous step: its tracker predicts it on
  itself) and refines it with its own images; the map then adds their measurements in
  information form, so no view is thrown away. (Before issue 39e only the worker whose estimate
  weighed most, the ``lead``, continued from its own estimate and the others restarted from the
  map's each frame: a better view corrected the lead by one frame's evidence only, and on
  two-rooms two people in line in one camera pulled the map between them —
  ``share_rule=support-lead`` keeps that rule. Letting every worker keep its own estimate
  instead lost up to 0.74 MOTA, ids swapping in one worker: issue 39d.)
* **The shared map weighs each worker's estimate by support and by geometry** — the
  support is the share of the person's own pixels that are foreground in that worker's views (the
  evidence the estimate rests on; else the match score; at least 0.05) — with ``weigh_own``
  (opt-in: it lost on held-out seeds 24-33, issue-39h) times the share of the body no other person
  that worker holds covers — and the geometry is how finely the
  worker's cameras resolve the floor where the person stands: the information matrix ``I_k`` of
  a one-pixel error of the body points they show (:func:`~worldtrack.map.evidence.floor_information`; a camera 8 m away
  resolves depth ~6× worse than one 3 m away, and only along its line of sight; points hidden by
  the scene's obstacles or behind another person the worker holds add nothing, so the view in
  which a person stands in front tells their depth). Within a time bucket the map position is
  ``x = (Σ w_k I_k)⁻¹ Σ w_k I_k x_k`` over the workers ``k`` that saw the person (each
  ``x_k`` is the fit of that worker's images from the common prior, its own measurement: the
  prior only starts the search and is not added again). ``weigh_by=tracker`` uses the inverse
  of each tracker's measured covariance instead (the ellipsoid tracker's σ, from the curvature of
  its score): on two-rooms its σ along the line of sight sits at its 0.29 m cap in a third of the
  estimates and does not tell the occluded view from the clear one (MOTA 0.83 / 0.90 against 1.00
  / 1.00 on seeds 1 and 3). Estimates of a person a worker holds without evidence (hidden behind a
  desk in its view) count only when no worker saw them.
* **Ids are the map's.** A worker's tracker takes new ids from the map (each worker from its slot's
  counter in Redis: the scene index of its first camera decides which ids it gives, so a batch run
  gives the same ids whichever worker asks first) and, for a person walking in from a
  neighbour's view, finds them already on its map under their id.
  If two workers still start the same person (both saw them first in the same frame), the two
  ids are close, and no worker sees both: the younger id is folded into the elder (``aliases``)
  after ``merge_after_s``, at once when both ids are that young, and the workers rename their
  copy. Two ids one worker sees at the same time are two people it tells apart (two people
  crossing in its view, while another worker sees only one of them), never merged.
* **The map does not wait for the slowest worker.** Until a bucket is complete, the live map is
  :func:`provisional_state`: each person reported so far in the bucket where those reports put
  them (weighed as above; a later worker's report of the same bucket refines the estimate), and
  everybody else as the last complete bucket had them. So a worker that is late delays only the
  people it reports; nobody is marked lost, merged or forgotten until the bucket is complete
  (:func:`fuse_bucket`, which writes the record).
* A person no worker reports is ``lost`` (kept, not moved) and leaves the map after
  ``forget_after_s``, or at once when the workers that saw them last say their tracker ended them
  (walked out of the door).

Everything here is pure (no Redis): :func:`fuse_bucket` turns a bucket's observations and the
previous :class:`FusionState` into a :class:`~worldtrack.map.messages.MapState`.

>>> from worldtrack.map.messages import Estimate, Observation
>>> cfg = MapConfig()
>>> a = Observation("cam1", 5.02, "w1", 50, 5.03, (Estimate(7, 1.0, 2.0, 1.7, 0.45, 0, 0, 0.8, 0.9, True),))
>>> b = Observation("cam2", 5.04, "w2", 50, 5.05, (Estimate(7, 1.2, 2.0, 1.7, 0.45, 0, 0, 0.8, 0.3, True),))
>>> state = FusionState()
>>> p, = fuse_bucket(state, 50, [a, b], cfg).people
>>> round(p.x, 3), p.workers           # (0.9·1.0 + 0.3·1.2) / 1.2
(1.05, 2)
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, fields, replace
from typing import Iterable, Mapping

import numpy as np

from worldtrack.map.config import MapConfig
from worldtrack.map.evidence import (LEAD_SHARE, floor_information, in_views, people_boxes, visible_share,  # noqa: F401
                                     with_ray_error)
from worldtrack.map.messages import REFUTED, Estimate, MapPerson, MapState, Observation
from worldtrack.map.merges import MIN_WEIGHT, merge_duplicates
from worldtrack.map.rays import RAY_HEIGHTS, ViewRay, map_height, ray_height
from worldtrack.map.refute import refute
from worldtrack.map.same_blob import fold_same_blobs


@dataclass
class FusedPerson:
    """A person on the fused map, with what the fusion needs to continue them."""

    id: int
    x: float
    y: float
    height: float
    width: float
    vx: float = 0.0
    vy: float = 0.0
    score: float = 0.0
    support: float = float("nan")
    last_seen: float = 0.0
    born: float = 0.0
    mode: str = "tracking"
    workers: int = 0
    lead: str = ""
    #: Buckets running in which another worker's clear view showed this person's place empty
    #: while only views showing less than LEAD_SHARE of them reported them.
    doubt: int = 0
    #: Buckets running in which only one worker reported them, covered by other people there.
    hidden: int = 0
    #: ``map.head_rays``: their last heights (m) from two workers' head rays, oldest first.
    ray_heights: list = field(default_factory=list)

    def public(self) -> MapPerson:
        return MapPerson(self.id, self.x, self.y, self.height, self.width, self.vx, self.vy, self.score,
                         self.support, self.mode, self.last_seen, self.born, self.workers, self.lead)


_PERSON_FIELDS = [f.name for f in fields(FusedPerson)]


@dataclass
class FusionState:
    """What the fusion role carries from bucket to bucket (and hands over on failover as JSON)."""

    people: dict[int, FusedPerson] = field(default_factory=dict)
    #: Pairs of ids (a < b) from different workers close to each other: since when (s).
    close_since: dict[tuple[int, int], float] = field(default_factory=dict)
    #: Merged ids: younger → elder, with the time of the merge (kept for ``forget_after_s``).
    aliases: dict[int, tuple[int, float]] = field(default_factory=dict)
    last_bucket: int | None = None
    #: ``map.crossing_s``: pairs of ids (a < b) one worker saw at the same time, when last (s).
    together: dict[tuple[int, int], float] = field(default_factory=dict)

    def to_json(self) -> str:
        # Without map.head_rays's heights (the last field), map.crossing_s's pairs: as before (older roles read it).
        n = len(_PERSON_FIELDS) - (not any(p.ray_heights for p in self.people.values()))
        together = {"together": [[a, b, t] for (a, b), t in self.together.items()]} if self.together else {}
        return json.dumps({"fields": _PERSON_FIELDS[:n],
                           "people": [list(vars(p).values())[:n] for p in self.people.values()],
                           "close_since": [[a, b, t] for (a, b), t in self.close_since.items()],
                           "aliases": [[y, e, t] for y, (e, t) in self.aliases.items()],
                           "last_bucket": self.last_bucket} | together, allow_nan=True)

    @classmethod
    def from_json(cls, text: str) -> "FusionState":
        d = json.loads(text)
        people = [FusedPerson(**dict(zip(d["fields"], p))) for p in d["people"]]
        return cls({p.id: p for p in people},
                   {(int(a), int(b)): float(t) for a, b, t in d["close_since"]},
                   {int(y): (int(e), float(t)) for y, e, t in d["aliases"]}, d["last_bucket"],
                   {(int(a), int(b)): float(t) for a, b, t in d.get("together", [])})

    def copy(self) -> "FusionState":
        """An independent copy (a bucket is fused on a copy until its write has succeeded)."""
        return FusionState({i: replace(p) for i, p in self.people.items()}, dict(self.close_since),
                           dict(self.aliases), self.last_bucket, dict(self.together))

    @classmethod
    def from_record(cls, state: MapState, bucket: int) -> "FusionState":
        """The state to continue after ``bucket`` from its entry in the record (the map stream),
        when the state written beside it is missing (the current-map hash deleted or older).
        Pairs of close ids start afresh; the bucket's own merges are kept."""
        people = {p.id: FusedPerson(**p._asdict()) for p in state.people}
        return cls(people, {}, {y: (e, state.t) for y, e in state.aliases.items()}, bucket)

    def resolve(self, pid: int) -> int:
        """The id ``pid`` is known by now (following merges)."""
        seen = set()
        while pid in self.aliases and pid not in seen:
            seen.add(pid)
            pid = self.aliases[pid][0]
        return pid


def estimate_weight(e: Estimate) -> float:
    """How much an estimate counts: its support, else its score, at least :data:`MIN_WEIGHT`."""
    for v in (e.support, e.score):
        if v is not None and math.isfinite(v) and v > 0:
            return max(MIN_WEIGHT, float(v))
    return MIN_WEIGHT


def own_weight(e: Estimate, weigh_own: bool = True) -> float:
    """:func:`estimate_weight` × the share of the body the worker's views show as this person's own
    (``Estimate.own``: not covered by other people it holds; at least :data:`MIN_WEIGHT`): a worker
    that sees a person behind somebody else measures the one in front as much as them."""
    own = e.own if weigh_own and math.isfinite(e.own) else 1.0
    return estimate_weight(e) * max(MIN_WEIGHT, min(1.0, own))


def _information(e: Estimate) -> np.ndarray:
    m = np.array([[e.ixx, e.ixy], [e.ixy, e.iyy]], float)
    return m if np.isfinite(m).all() and np.linalg.det(m) > 0 else np.eye(2)


def measured_information(e: Estimate) -> np.ndarray | None:
    """The information (2, 2) 1/m² of an estimate as its worker's tracker measured it (the inverse
    of its covariance ``cxx, cxy, cyy``); None when the tracker gave none (or a degenerate one)."""
    c = np.array([[e.cxx, e.cxy], [e.cxy, e.cyy]], float)
    if not np.isfinite(c).all() or c[0, 0] <= 0 or np.linalg.det(c) <= 0:
        return None
    return np.linalg.inv(c)


def _weights(estimates: list[Estimate], weigh_by: str, weigh_own: bool = True,
             ray_error_m: float = 0.0) -> tuple[list[np.ndarray], bool]:
    """Each estimate's weight matrix, and whether they are the trackers' measured information
    (``weigh_by="tracker"`` and every estimate has one) rather than support (× own share, see
    :func:`own_weight`) × floor geometry (with ``ray_error_m`` > 0 plus that model error along the
    worker's line of sight, :func:`~worldtrack.map.evidence.with_ray_error`)."""
    measured = [measured_information(e) for e in estimates] if weigh_by == "tracker" else [None]
    if all(m is not None for m in measured):
        return measured, True
    w = [own_weight(e, weigh_own) for e in estimates]
    infos = [with_ray_error(wi * _information(e), ray_error_m) for wi, e in zip(w, estimates)]
    scale = np.mean([np.trace(m) for m in infos])
    return [m / scale for m in infos], False         # relative weights: keeps the solve well scaled


def _weighted(estimates: list[Estimate], weigh_by: str = "geometry", weigh_own: bool = True,
              ray_error_m: float = 0.0, height_by_view: bool = False) -> tuple[float, ...]:
    if len(estimates) == 1:           # most people, most of the time: one worker sees them
        e = estimates[0]
        return e.x, e.y, e.height, e.width, e.vx, e.vy, e.score, e.support
    w = [estimate_weight(e) for e in estimates]
    total = sum(w)
    infos, _ = _weights(estimates, weigh_by, weigh_own, ray_error_m)
    total_info = sum(infos)
    xy = np.linalg.solve(total_info, sum(m @ np.array([e.x, e.y]) for m, e in zip(infos, estimates)))
    v_ok = [(m, e) for m, e in zip(infos, estimates) if math.isfinite(e.vx) and math.isfinite(e.vy)]
    vxy = (np.linalg.solve(sum(m for m, _ in v_ok), sum(m @ np.array([e.vx, e.vy]) for m, e in v_ok))
           if v_ok else np.array([0.0, 0.0]))

    def mean(attr: str, by_view: bool = False) -> float:
        # by_view: × the share of the body the worker's views show as its own (Estimate.own): a
        # worker that shows neither feet nor head of a person (behind somebody) measures no height.
        vals = [(wi * (max(MIN_WEIGHT, min(1.0, e.own)) if by_view and math.isfinite(e.own) else 1.0), getattr(e, attr))
                for wi, e in zip(w, estimates) if math.isfinite(getattr(e, attr))]
        s = sum(wi for wi, _ in vals)
        return sum(wi * v for wi, v in vals) / s if s > 0 else float("nan")

    supports = [e.support for e in estimates if math.isfinite(e.support)]
    return (float(xy[0]), float(xy[1]), mean("height", height_by_view), mean("width"), float(vxy[0]), float(vxy[1]),
            sum(wi * e.score for wi, e in zip(w, estimates)) / total, max(supports) if supports else float("nan"))


def _lead(by_worker: Mapping[str, Estimate], use: list[Estimate], weigh_by: str, weigh_own: bool = True) -> str:
    """The worker whose estimate of a person weighs most: with the trackers' covariances
    (``weigh_by="tracker"``) the smallest (trace); else a worker showing at least
    :data:`LEAD_SHARE` of the body (with ``weigh_own``: as their own, not covered by other people),
    then the largest support (× own share) × trace of floor information."""
    if len(by_worker) == 1:
        return next(iter(by_worker))
    if _weights(use, weigh_by)[1]:
        return min((e.cxx + e.cyy, k) for k, e in by_worker.items() if e in use)[1]
    return max(((min(e.visible, e.own if weigh_own else 1.0) >= LEAD_SHARE,
                 own_weight(e, weigh_own) * np.trace(_information(e)), k)
                for k, e in by_worker.items() if e in use), default=(False, 0.0, ""))[2]


def _per_worker(state: FusionState, observations: Iterable[Observation]) -> dict[int, dict[str, Estimate]]:
    """Each person's estimates, one per worker (a worker's cameras share its tracker's estimate;
    the one seen, else the latest, is kept)."""
    out: dict[int, dict[str, Estimate]] = {}
    # In an order that does not depend on arrival (worker names hold a pid): the sums of the
    # weighted estimates, the people's order in the state and ties of the lead repeat run to run.
    for o in sorted(observations, key=lambda o: (o.t, o.camera, o.frame)):
        for e in o.people:
            pid = state.resolve(e.id)
            if pid == REFUTED:                  # dropped on negative evidence: not brought back
                continue
            mine = out.setdefault(pid, {})
            old = mine.get(o.worker)
            if old is None or e.seen or not old.seen:
                mine[o.worker] = e._replace(id=pid)
    return out


def _rays_of(state: FusionState, observations: Iterable[Observation]) -> dict[int, dict[tuple[str, str], ViewRay]]:
    """Each person's view rays (``map.head_rays``), one per worker and camera (the latest)."""
    out: dict[int, dict[tuple[str, str], ViewRay]] = {}
    for o in sorted(observations, key=lambda o: (o.t, o.camera, o.frame)):
        for r in o.rays:
            pid = state.resolve(r.id)
            if pid != REFUTED:
                out.setdefault(pid, {})[o.worker, o.camera] = r._replace(id=pid)
    return out


def fuse_bucket(state: FusionState, bucket: int, observations: list[Observation], cfg: MapConfig,
                written: float = 0.0) -> MapState:
    """Merge a bucket's observations into ``state`` and return the map state of the bucket.

    Parameters
    ----------
    state : FusionState — updated in place
    bucket : int — the bucket's index (its start is ``bucket · cfg.bucket_s`` seconds)
    observations : the observations whose capture times fall in the bucket
    cfg : MapConfig
    written : wall-clock time (s) recorded as the state's ``written``
    """
    t = bucket * cfg.bucket_s
    observations = sorted(observations, key=lambda o: (o.t, o.camera, o.frame))
    estimates = _per_worker(state, observations)
    workers_of = _update_people(state.people, estimates, t, cfg.weigh_by, weigh_own=cfg.weigh_own,
                                ray_error_m=cfg.ray_error_m, height_by_view=cfg.height_by_view,
                                rays=_rays_of(state, observations) if cfg.head_rays else None,
                                height_deadband_m=cfg.ray_height_deadband_m)
    ended = {state.resolve(i) for o in observations for i in o.ended}
    for pid in list(state.people):
        p = state.people[pid]
        if pid in estimates:
            continue
        p.mode = "lost"
        if pid in ended or t - p.last_seen > cfg.forget_after_s:
            del state.people[pid]
    aliases = merge_duplicates(state, workers_of, t, cfg, estimates)
    aliases.update(fold_same_blobs(state, observations, t, cfg.same_blob_s) if cfg.same_blob_iou > 0 else {})
    if cfg.negative_evidence:
        aliases.update(refute(state, estimates, observations, t, cfg))
    state.aliases = {y: (e, ts) for y, (e, ts) in state.aliases.items() if t - ts <= cfg.forget_after_s}
    state.last_bucket = bucket
    reports = tuple((o.camera, o.t, o.sent) for o in observations)
    people = tuple(p.public() for p in sorted(state.people.values(), key=lambda p: p.id))
    return MapState(t, people, reports, aliases, written)


def _update_people(people: dict[int, FusedPerson], estimates: dict[int, dict[str, Estimate]], t: float,
                   weigh_by: str = "geometry", copy: bool = False, weigh_own: bool = True,
                   ray_error_m: float = 0.0, height_by_view: bool = False,
                   rays: Mapping[int, Mapping[tuple[str, str], ViewRay]] | None = None,
                   height_deadband_m: float = 0.0) -> dict[int, set[str]]:
    """Set each reported person of ``people`` to the weighted estimate of the workers that report
    them at bucket time ``t`` (s); ``copy``: replace the person by an updated copy (the people of a
    committed state stay as they are). ``rays``: per person the view rays of each worker and camera
    (:func:`_rays_of`); the height of a person two workers that see them publish head rays of is
    the median of their last :data:`RAY_HEIGHTS` heights from those rays
    (:func:`~worldtrack.map.rays.ray_height`), once three are in. Returns, per person, the workers
    that see them."""
    workers_of: dict[int, set[str]] = {}
    for pid, by_worker in estimates.items():
        seen = [e for e in by_worker.values() if e.seen]
        use = seen or list(by_worker.values())
        x, y, h, w, vx, vy, score, support = _weighted(use, weigh_by, weigh_own, ray_error_m, height_by_view)
        mine = {key: r for key, r in (rays or {}).get(pid, {}).items()
                if key[0] in by_worker and by_worker[key[0]].seen}
        measured = ray_height(list(mine.values()), np.array([x, y, h if math.isfinite(h) else 1.7])) \
            if len({k for k, _ in mine}) >= 2 else None
        p = people.get(pid)
        if p is None:
            p = people[pid] = FusedPerson(pid, x, y, h, w, born=t)
        elif copy:
            p = people[pid] = replace(p)
        p.x, p.y, p.vx, p.vy, p.score, p.support = x, y, vx, vy, score, support
        if measured is not None:     # a new list: a copy (copy=True) must not change the committed person's
            p.ray_heights = [*p.ray_heights[1 - RAY_HEIGHTS:], measured]
        if len(p.ray_heights) >= 3:       # held while within height_deadband_m (map_height)
            h = map_height(p.ray_heights, p.height, height_deadband_m)
        p.height = h if math.isfinite(h) else p.height
        p.width = w if math.isfinite(w) else p.width
        p.mode, p.last_seen, p.workers = "tracking", t, len(use)
        p.lead = _lead(by_worker, use, weigh_by, weigh_own)
        workers_of[pid] = {k for k, e in by_worker.items() if e.seen}
    return workers_of


def provisional_state(state: FusionState, buckets: Mapping[int, list[Observation]], cfg: MapConfig,
                      written: float = 0.0) -> MapState:
    """The live map before the open ``buckets`` are complete: ``state`` (the last complete bucket,
    left unchanged) refined by every observation that has come for the buckets after it.

    A person reported in an open bucket is where the reports so far put them (weighed as in
    :func:`fuse_bucket`; a later worker's report refines it); anybody else keeps their last
    estimate and mode — a worker that has not reported yet delays only its own people, and nobody
    is marked lost, merged or forgotten before the bucket is complete. The state's ``t`` is the
    newest open bucket's start, its ``reports`` those of all open buckets.

    >>> from worldtrack.map.messages import Estimate, Observation
    >>> cfg, state = MapConfig(), FusionState()
    >>> a = Observation("cam1", 5.02, "w1", 50, 5.03, (Estimate(7, 1.0, 2.0, 1.7, 0.45, 0, 0, 0.8, 0.9, True),))
    >>> p, = provisional_state(state, {50: [a]}, cfg).people
    >>> p.id, p.x, len(state.people)         # the committed state is not touched
    (7, 1.0, 0)
    """
    people = dict(state.people)
    for b in sorted(buckets):
        _update_people(people, _per_worker(state, buckets[b]), b * cfg.bucket_s, cfg.weigh_by, copy=True,
                       weigh_own=cfg.weigh_own, ray_error_m=cfg.ray_error_m, height_by_view=cfg.height_by_view,
                       rays=_rays_of(state, buckets[b]) if cfg.head_rays else None,
                       height_deadband_m=cfg.ray_height_deadband_m)
    t = max(buckets, default=state.last_bucket or 0) * cfg.bucket_s
    reports = tuple((o.camera, o.t, o.sent) for b in sorted(buckets) for o in buckets[b])
    public = tuple(p.public() for p in sorted(people.values(), key=lambda p: p.id))
    aliases = {young: elder for young, (elder, _) in state.aliases.items()}   # recent merges, again
    return MapState(t, public, reports, aliases, written)


__all__ = ["FusedPerson", "FusionState", "MIN_WEIGHT", "estimate_weight", "floor_information", "fuse_bucket",
           "in_views", "measured_information", "people_boxes", "provisional_state", "visible_share"]
