"""Merging observations of the same person from different workers: one map state per time bucket.

This is the answer worldtrack gives to the question paper 000 leaves open (§5–6: several systems,
each with its own cameras, share one person map — who updates a person two of them see?):

* **Every worker that sees a person updates them, on its own map, from its own cameras**, and
  publishes its estimate. A worker never moves a person its cameras do not show: those it takes
  from the shared map as they are (:mod:`worldtrack.map.worker`). Of the workers that see a person,
  the one whose estimate weighs most (``lead``) continues from its own estimate; the others start
  each frame from the map's and move the person by their own cameras' evidence, so a worker that
  sees somebody poorly (far, through a door) contributes without drifting away on its own.
* **The shared map keeps each worker's estimate and weighs them by support and by geometry** —
  the support is the share of the person's own pixels that are foreground in that worker's views
  (the evidence the estimate rests on; else the match score; at least 0.05), and the geometry is
  how finely the worker's cameras resolve the floor where the person stands: the information
  matrix ``I_k`` of a one-pixel error of their feet and head (:func:`floor_information`; a camera
  8 m away resolves depth ~6× worse than one 3 m away, and only along its line of sight). Within
  a time bucket the map position is the information-weighted mean
  ``x = (Σ w_k I_k)⁻¹ Σ w_k I_k x_k`` over the workers ``k`` that saw the person. Estimates of a
  person a worker holds without evidence (hidden behind a desk in its view) count only when no
  worker saw them.
* **Ids are the map's.** A worker's tracker takes new ids from the map (one counter in Redis) and,
  for a person walking in from a neighbour's view, finds them already on its map under their id.
  If two workers still start the same person at once (both saw them first in the same frame), the
  two ids are close for ``merge_after_s`` with estimates from different sets of workers: the
  younger id is folded into the elder (``aliases``), and the workers rename their copy.
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
from dataclasses import dataclass, field, fields
from typing import Iterable, Sequence

import numpy as np

from worldtrack.geometry.camera import Camera
from worldtrack.map.config import MapConfig
from worldtrack.map.messages import Estimate, MapPerson, MapState, Observation

#: The least weight an estimate has (support 0 still says "a worker sees somebody here").
MIN_WEIGHT = 0.05
#: The lead of a person is a worker whose cameras show at least this share of their body, if any
#: does (a tracker fitting a head at the image's edge is no lead, however near the camera).
LEAD_SHARE = 0.6


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

    def to_json(self) -> str:
        return json.dumps({"fields": _PERSON_FIELDS, "people": [list(vars(p).values()) for p in self.people.values()],
                           "close_since": [[a, b, t] for (a, b), t in self.close_since.items()],
                           "aliases": [[y, e, t] for y, (e, t) in self.aliases.items()],
                           "last_bucket": self.last_bucket}, allow_nan=True)

    @classmethod
    def from_json(cls, text: str) -> "FusionState":
        d = json.loads(text)
        people = [FusedPerson(**dict(zip(d["fields"], p))) for p in d["people"]]
        return cls({p.id: p for p in people},
                   {(int(a), int(b)): float(t) for a, b, t in d["close_since"]},
                   {int(y): (int(e), float(t)) for y, e, t in d["aliases"]}, d["last_bucket"])

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


def _body_points(cam: Camera, xy: np.ndarray, height: float, occlusion: np.ndarray | None,
                 step_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Five points on a person's axis (feet to head) and four neighbours of each a step away on
    the floor, in ``cam``'s image: (5, 5, 2) pixels, and which of the five show (inside the image,
    not behind an obstacle), (5,) bool."""
    offsets = np.array([[0.0, 0.0], [step_m, 0.0], [-step_m, 0.0], [0.0, step_m], [0.0, -step_m]])
    heights = np.linspace(0.0, height, 5)
    pts = np.concatenate([np.column_stack([xy[None, :] + offsets, np.full(5, z)]) for z in heights])
    uv = cam.project(pts).reshape(len(heights), 5, 2)
    seen = cam.in_image(uv[:, 0]) & np.isfinite(uv).all(axis=(1, 2))
    if occlusion is not None and seen.any():
        px = np.clip(np.nan_to_num(np.round(uv[:, 0])).astype(int), 0, [cam.width - 1, cam.height - 1])
        mine = float(cam.floor_distance(np.append(xy, 0.0)[None, :])[0])
        seen &= occlusion[px[:, 1], px[:, 0]] > mine - 0.3
    return uv, seen


def visible_share(cameras: Sequence[Camera], xy: np.ndarray, height: float,
                  occlusion: Sequence[np.ndarray | None] | None = None) -> float:
    """The largest share, over ``cameras``, of a person's five axis points (feet to head) that the
    camera shows: 1 in full view, 0.2 when one camera sees only their head through a door."""
    shares = [_body_points(cam, xy, height, occlusion[k] if occlusion else None, 0.05)[1].mean()
              for k, cam in enumerate(cameras)]
    return float(max(shares, default=0.0))


def floor_information(cameras: Sequence[Camera], xy: np.ndarray, height: float, sigma_px: float = 1.0,
                      step_m: float = 0.05, occlusion: Sequence[np.ndarray | None] | None = None
                      ) -> tuple[float, float, float]:
    """How finely ``cameras`` resolve a person standing at floor point ``xy`` (metres): the
    information matrix ``Σ Jᵀ J / σ²`` (1/m², as ``ixx, ixy, iyy``) of five points on the person's
    axis (feet to head), ``J`` the pixels a point moves per metre on the floor, ``σ = sigma_px``.
    Points outside a camera's image, or hidden there by a structure (``occlusion``: per camera the
    scene's floor-distance map of obstacles, (H, W) metres), add nothing; so a person seen only
    through a door counts for less. No visible point gives ``(nan, nan, nan)``.

    >>> from worldtrack.geometry.camera import Camera
    >>> cam = Camera.look_at("c", 320, 240, [0.0, 0.0, 3.0], [4.0, 0.0, 0.0], hfov_deg=60)
    >>> near, far = (floor_information([cam], np.array([x, 0.0]), 1.7) for x in (2.0, 6.0))
    >>> near[0] > 4 * far[0]                      # depth resolves worse far away
    True
    """
    info = np.zeros((2, 2))
    for k, cam in enumerate(cameras):
        uv, seen = _body_points(cam, xy, height, occlusion[k] if occlusion is not None else None, step_m)
        for i in np.flatnonzero(seen):
            J = np.column_stack([(uv[i, 1] - uv[i, 2]) / (2 * step_m), (uv[i, 3] - uv[i, 4]) / (2 * step_m)])
            info += J.T @ J / sigma_px ** 2
    if not info.any():
        return float("nan"), float("nan"), float("nan")
    return float(info[0, 0]), float(info[0, 1]), float(info[1, 1])


def _information(e: Estimate) -> np.ndarray:
    m = np.array([[e.ixx, e.ixy], [e.ixy, e.iyy]], float)
    return m if np.isfinite(m).all() and np.linalg.det(m) > 0 else np.eye(2)


def _weighted(estimates: list[Estimate]) -> tuple[float, ...]:
    if len(estimates) == 1:           # most people, most of the time: one worker sees them
        e = estimates[0]
        return e.x, e.y, e.height, e.width, e.vx, e.vy, e.score, e.support
    w = [estimate_weight(e) for e in estimates]
    total = sum(w)
    infos = [wi * _information(e) for wi, e in zip(w, estimates)]
    scale = np.mean([np.trace(m) for m in infos])
    infos = [m / scale for m in infos]            # relative weights: keeps the solve well scaled
    total_info = sum(infos)
    xy = np.linalg.solve(total_info, sum(m @ np.array([e.x, e.y]) for m, e in zip(infos, estimates)))
    v_ok = [(m, e) for m, e in zip(infos, estimates) if math.isfinite(e.vx) and math.isfinite(e.vy)]
    vxy = (np.linalg.solve(sum(m for m, _ in v_ok), sum(m @ np.array([e.vx, e.vy]) for m, e in v_ok))
           if v_ok else np.array([0.0, 0.0]))

    def mean(attr: str) -> float:
        vals = [(wi, getattr(e, attr)) for wi, e in zip(w, estimates) if math.isfinite(getattr(e, attr))]
        s = sum(wi for wi, _ in vals)
        return sum(wi * v for wi, v in vals) / s if s > 0 else float("nan")

    supports = [e.support for e in estimates if math.isfinite(e.support)]
    return (float(xy[0]), float(xy[1]), mean("height"), mean("width"), float(vxy[0]), float(vxy[1]),
            sum(wi * e.score for wi, e in zip(w, estimates)) / total, max(supports) if supports else float("nan"))


def _per_worker(state: FusionState, observations: Iterable[Observation]) -> dict[int, dict[str, Estimate]]:
    """Each person's estimates, one per worker (a worker's cameras share its tracker's estimate;
    the one seen, else the latest, is kept)."""
    out: dict[int, dict[str, Estimate]] = {}
    for o in sorted(observations, key=lambda o: o.t):
        for e in o.people:
            pid = state.resolve(e.id)
            mine = out.setdefault(pid, {})
            old = mine.get(o.worker)
            if old is None or e.seen or not old.seen:
                mine[o.worker] = e._replace(id=pid)
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
    estimates = _per_worker(state, observations)
    workers_of: dict[int, set[str]] = {}
    for pid, by_worker in estimates.items():
        seen = [e for e in by_worker.values() if e.seen]
        use = seen or list(by_worker.values())
        x, y, h, w, vx, vy, score, support = _weighted(use)
        p = state.people.get(pid)
        if p is None:
            p = state.people[pid] = FusedPerson(pid, x, y, h, w, born=t)
        p.x, p.y, p.vx, p.vy, p.score, p.support = x, y, vx, vy, score, support
        p.height = h if math.isfinite(h) else p.height
        p.width = w if math.isfinite(w) else p.width
        p.mode, p.last_seen, p.workers = "tracking", t, len(use)
        p.lead = next(iter(by_worker)) if len(by_worker) == 1 else \
            max(((e.visible >= LEAD_SHARE, estimate_weight(e) * np.trace(_information(e)), k)
                 for k, e in by_worker.items() if e in use), default=(False, 0.0, ""))[2]
        workers_of[pid] = {k for k, e in by_worker.items() if e.seen}
    ended = {state.resolve(i) for o in observations for i in o.ended}
    for pid in list(state.people):
        p = state.people[pid]
        if pid in estimates:
            continue
        p.mode = "lost"
        if pid in ended or t - p.last_seen > cfg.forget_after_s:
            del state.people[pid]
    aliases = _merge_duplicates(state, workers_of, t, cfg)
    state.aliases = {y: (e, ts) for y, (e, ts) in state.aliases.items() if t - ts <= cfg.forget_after_s}
    state.last_bucket = bucket
    reports = tuple((o.camera, o.t, o.sent) for o in observations)
    people = tuple(p.public() for p in sorted(state.people.values(), key=lambda p: p.id))
    return MapState(t, people, reports, aliases, written)


def _merge_duplicates(state: FusionState, workers_of: dict[int, set[str]], t: float,
                      cfg: MapConfig) -> dict[int, int]:
    """Fold the younger of two ids that stay within ``merge_distance_m`` for ``merge_after_s`` into
    the elder, unless the very same workers see both (then they are two people those workers tell
    apart). Returns ``{younger: elder}``."""
    from scipy.spatial import cKDTree
    ids = sorted(workers_of)
    close_now = set()
    if len(ids) >= 2:
        xy = np.array([[state.people[i].x, state.people[i].y] for i in ids])
        for i, j in cKDTree(xy).query_pairs(cfg.merge_distance_m):
            a, b = min(ids[i], ids[j]), max(ids[i], ids[j])
            if workers_of[a] == workers_of[b] or not workers_of[a] or not workers_of[b]:
                continue      # the same workers hold both apart: two people
            close_now.add((a, b))
    state.close_since = {pair: state.close_since.get(pair, t) for pair in close_now}
    merged: dict[int, int] = {}
    for (a, b), since in sorted(state.close_since.items()):
        if t - since < cfg.merge_after_s or a in merged or b in merged:
            continue
        pa, pb = state.people[a], state.people[b]
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


def _finite(v: float) -> float:
    return v if v is not None and math.isfinite(v) else 0.0


__all__ = ["FusedPerson", "FusionState", "MIN_WEIGHT", "estimate_weight", "floor_information", "fuse_bucket",
           "visible_share"]
