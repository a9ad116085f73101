"""What travels through Redis: observations (worker → fusion) and map states (fusion → everyone).

Stream entries are flat maps of strings; people are JSON lists in a fixed column order, so a
message stays small (256 cameras × 5 people at 10 Hz is ~13,000 people a second).

* An :class:`Observation` is one camera's frame as a worker saw it: the camera, the capture time
  (wall clock, s), the worker, the frame number, when it was sent, and every person the worker's
  tracker holds in that camera's view (:class:`Estimate`), plus the ids its tracker ended there.
* A :class:`MapState` is the fused map for one time bucket: every person with where they are, how
  sure the map is, and since when they have not been seen (``mode`` ``"lost"``).

Entry ids are capture times in ms (``<ms>-<seq>``), so streams can be read and trimmed by time
(``XRANGE``, ``MINID``) and a map bucket is written once: a second ``XADD`` of the same id fails.

>>> e = Estimate(3, 1.5, 2.0, 1.7, 0.45, 0.2, 0.0, 0.8, 0.6, True, cxx=0.04, cxy=0.0, cyy=0.0025)
>>> o = Observation("cam1", 12.3, "w1", 123, 12.35, (e,), ended=(2,), absent=(5,),
...                 candidates=((4.0, 1.0, 1.7, 0.45),), affirms=(("w2", 9.5, 2.0),), same=((4, 1),))
>>> decode_observation(encode_observation(o)) == o
True
>>> r = ViewRay(3, 0.3, 2.5, 3.0, 0.9, 0.0, -0.3, 0.8, 0.0, -0.6)    # a worker's own head and feet rays
>>> fields = encode_observation(replace(o, rays=(r,)))
>>> fields["rays"][:3], decode_observation(fields).rays == (r,)
('[1,', True)
>>> bucket_index(12.34, 0.1), stream_id_ms(12.3)
(123, 12300)
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, replace  # noqa: F401 (doctest)
from typing import Mapping, NamedTuple

from worldtrack.map.rays import ViewRay

FORMAT_VERSION = "2"
#: The version of an observation's optional ``rays`` field (:class:`~worldtrack.map.rays.ViewRay`
#: rows): a field of its own, so readers of format 2 that predate it read the rest as before.
RAYS_VERSION = 1


class Estimate(NamedTuple):
    """One worker's estimate of one person at one capture time (metres, m/s).

    ``support`` is the share of the person's own pixels that are foreground (NaN if the tracker
    does not say); ``seen`` is False for a person the worker holds in its view without evidence in
    this frame (hidden behind something), True when its cameras show them. ``ixx, ixy, iyy``
    (1/m²): how finely the worker's cameras resolve the floor there, the information matrix of a
    one-pixel error of the person's feet and head (:func:`worldtrack.map.evidence.floor_information`);
    ``visible``: the share of the person's body the worker's best camera shows
    (:func:`worldtrack.map.evidence.visible_share`). ``cxx, cxy, cyy`` (m²): the covariance of the
    estimate as the worker's tracker measured it this frame (the ellipsoid tracker's, from the
    curvature of its score: it knows what other people hide), NaN when the tracker gives none.
    ``own``: the share of the person's body its best camera shows that no other person it holds
    covers (the map's counterpart of the tracker's own share; 1 from older workers).
    """

    id: int
    x: float
    y: float
    height: float
    width: float
    vx: float
    vy: float
    score: float
    support: float
    seen: bool
    ixx: float = 1.0
    ixy: float = 0.0
    iyy: float = 1.0
    visible: float = 1.0
    cxx: float = float("nan")
    cxy: float = float("nan")
    cyy: float = float("nan")
    own: float = 1.0


#: An alias to this id means the map dropped the person on other workers' negative evidence
#: (their cameras show the place clearly, and nobody there): no elder, the id is gone.
REFUTED = 0


@dataclass(frozen=True)
class Observation:
    """One camera's frame as a worker saw it. ``ended``: ids its tracker ended; ``absent``: ids of
    the map's people this camera shows the place of, clearly, with nobody there (negative evidence,
    :func:`worldtrack.map.evidence.looks_empty`). ``candidates``: the people its tracker proposes
    there but has not confirmed, ``(x, y, height, width)`` m; ``affirms``: other workers'
    candidates this camera shows somebody at, ``(their worker, x, y)`` (:mod:`worldtrack.map.affirm`);
    ``same``: ``(its id, another worker's id)``, two newborns its camera shows as one blob
    (:mod:`worldtrack.map.same_blob`). ``rays``: per person its camera's own head and feet rays
    (``map.head_rays``, :mod:`worldtrack.map.rays`)."""

    camera: str
    t: float
    worker: str
    frame: int
    sent: float
    people: tuple[Estimate, ...] = ()
    ended: tuple[int, ...] = ()
    absent: tuple[int, ...] = ()
    candidates: tuple[tuple[float, float, float, float], ...] = ()
    affirms: tuple[tuple[str, float, float], ...] = ()
    same: tuple[tuple[int, int], ...] = ()
    rays: tuple[ViewRay, ...] = ()


class MapPerson(NamedTuple):
    """A person on the fused map (metres, m/s, seconds).

    ``mode``: ``"tracking"`` (some worker reported them in this bucket) or ``"lost"`` (none did;
    kept until ``forget_after_s``). ``workers``: how many workers' estimates were merged;
    ``lead``: the worker whose estimate weighed most (support × floor information), "" if none.
    """

    id: int
    x: float
    y: float
    height: float
    width: float
    vx: float
    vy: float
    score: float
    support: float
    mode: str
    last_seen: float
    born: float
    workers: int
    lead: str = ""


@dataclass(frozen=True)
class MapState:
    """The fused map for the bucket starting at ``t`` (s).

    ``reports``: ``(camera, capture time, sent time)`` of every observation merged (for lag and
    latency); ``aliases``: ``{younger id: elder id}`` merged in this bucket (elder :data:`REFUTED`:
    dropped on negative evidence); ``written``: when the
    fusion wrote it (wall clock, s); ``late``: observations that came after their bucket was written.
    """

    t: float
    people: tuple[MapPerson, ...]
    reports: tuple[tuple[str, float, float], ...] = ()
    aliases: Mapping[int, int] = field(default_factory=dict)
    written: float = 0.0
    late: int = 0

    @property
    def captured(self) -> float:
        """The latest capture time merged into this state (s); the bucket's middle if none."""
        return max((t for _, t, _ in self.reports), default=self.t)

    def present(self) -> list[MapPerson]:
        """The people some worker reported in this bucket (what ``tracks.csv`` lists)."""
        return [p for p in self.people if p.mode == "tracking"]


def _num(v: float, digits: int = 4) -> float | None:
    return None if v is None or not math.isfinite(v) else round(float(v), digits)


def _sig(v: float) -> float:
    """Four significant digits (information matrices span orders of magnitude); NaN stays NaN."""
    return float(f"{float(v):.4g}")


def _float(v) -> float:
    return float("nan") if v is None else float(v)


def encode_observation(o: Observation) -> dict[str, str]:
    """The stream fields of an observation: ``v``, ``t`` (capture time) and ``o``, one JSON list
    ``[camera, worker, frame, sent, people, ended, absent, candidates, affirms, same]`` (one field to parse, not
    ten: the fusion reads thousands a second). NaN stays NaN (Python's JSON)."""
    people = [[int(e.id), round(e.x, 4), round(e.y, 4), round(e.height, 3), round(e.width, 3), round(e.vx, 3),
               round(e.vy, 3), round(float(e.score), 3), round(float(e.support), 3), int(bool(e.seen)), _sig(e.ixx),
               _sig(e.ixy), _sig(e.iyy), round(float(e.visible), 2), _sig(e.cxx), _sig(e.cxy), _sig(e.cyy),
               round(float(e.own), 2)]
              for e in o.people]
    body = [o.camera, o.worker, int(o.frame), float(o.sent), people, [int(i) for i in o.ended],
            [int(i) for i in o.absent], [[round(float(v), 4) for v in c] for c in o.candidates],
            [[str(w), round(float(x), 4), round(float(y), 4)] for w, x, y in o.affirms],
            [[int(a), int(b)] for a, b in o.same]]
    out = {"v": FORMAT_VERSION, "t": repr(float(o.t)), "o": json.dumps(body, separators=(",", ":"))}
    if o.rays:      # ``rays``: [RAYS_VERSION, rows]; a field older readers do not look at
        rows = [[int(r.id), *(round(float(v), 5) for v in r[1:])] for r in o.rays]
        out["rays"] = json.dumps([RAYS_VERSION, rows], separators=(",", ":"))
    return out


def decode_observation(fields: Mapping[str, str]) -> Observation:
    """An observation from its stream fields; :class:`ValueError` naming what is wrong otherwise."""
    try:
        if fields.get("v") != FORMAT_VERSION:
            raise ValueError(f"format version {fields.get('v')!r}, expected {FORMAT_VERSION}")
        # 6 elements: before absent; 7: before candidates and affirms; 9: before same
        camera, worker, frame, sent, people, ended, *rest = json.loads(fields["o"])
        for p in people:
            p[9] = p[9] == 1
        absent, candidates, affirms, same = (rest + [[], [], [], []])[:4]
        return Observation(str(camera), float(fields["t"]), str(worker), int(frame), float(sent),
                           tuple(Estimate(*p) for p in people), tuple(ended), tuple(absent),
                           tuple(tuple(float(v) for v in c[:4]) for c in candidates),
                           tuple((str(w), float(x), float(y)) for w, x, y in affirms),
                           tuple((int(a), int(b)) for a, b in same), _rays(fields.get("rays")))
    except (KeyError, IndexError, TypeError, ValueError, json.JSONDecodeError) as e:
        if isinstance(e, ValueError) and str(e).startswith("format version"):
            raise
        raise ValueError(f"malformed observation ({type(e).__name__}: {e})") from None


def _rays(text: str | None) -> tuple[ViewRay, ...]:
    """The ``rays`` field of an observation; () when absent, or of a later version this reader
    does not know (the rest of the observation is read as ever)."""
    if not text:
        return ()
    version, rows = json.loads(text)
    if version != RAYS_VERSION:
        return ()
    return tuple(ViewRay(int(r[0]), *(_float(v) for v in r[1:10])) for r in rows)


def encode_map_state(s: MapState) -> dict[str, str]:
    """The stream fields of a map state."""
    people = [[p.id, _num(p.x), _num(p.y), _num(p.height, 3), _num(p.width, 3), _num(p.vx, 3), _num(p.vy, 3),
               _num(p.score, 3), _num(p.support, 3), p.mode, _num(p.last_seen, 3), _num(p.born, 3), p.workers, p.lead]
              for p in s.people]
    reports = [[c, _num(t, 4), _num(sent, 4)] for c, t, sent in s.reports]
    return {"v": FORMAT_VERSION, "t": repr(float(s.t)), "written": repr(float(s.written)), "late": str(int(s.late)),
            "people": json.dumps(people, separators=(",", ":")),
            "reports": json.dumps(reports, separators=(",", ":")),
            "aliases": json.dumps({str(k): int(v) for k, v in s.aliases.items()}, separators=(",", ":"))}


def decode_map_state(fields: Mapping[str, str]) -> MapState:
    """A map state from its stream fields; :class:`ValueError` naming what is wrong otherwise."""
    try:
        if fields.get("v") != FORMAT_VERSION:
            raise ValueError(f"format version {fields.get('v')!r}, expected {FORMAT_VERSION}")
        people = tuple(MapPerson(int(p[0]), *(_float(v) for v in p[1:9]), str(p[9]), _float(p[10]), _float(p[11]),
                                 int(p[12]), str(p[13]) if len(p) > 13 else "") for p in json.loads(fields["people"]))
        reports = tuple((str(c), _float(t), _float(s)) for c, t, s in json.loads(fields.get("reports", "[]")))
        aliases = {int(k): int(v) for k, v in json.loads(fields.get("aliases", "{}")).items()}
        return MapState(float(fields["t"]), people, reports, aliases, float(fields.get("written", 0.0)),
                        int(fields.get("late", 0)))
    except (KeyError, IndexError, TypeError, json.JSONDecodeError) as e:
        raise ValueError(f"malformed map state ({type(e).__name__}: {e})") from None


def bucket_index(t: float, bucket_s: float) -> int:
    """The time bucket of capture time ``t`` (s): ``floor(t / bucket_s)``, robust to rounding."""
    return int(math.floor(t / bucket_s + 1e-9))


def stream_id_ms(t: float) -> int:
    """The ms part of the stream entry id of time ``t`` (s)."""
    return int(math.floor(t * 1000.0 + 1e-6))


def time_of_id(entry_id: str) -> float:
    """The time (s) of a stream entry id ``<ms>-<seq>``."""
    return int(str(entry_id).split("-", 1)[0]) / 1000.0


__all__ = ["Estimate", "FORMAT_VERSION", "RAYS_VERSION", "MapPerson", "MapState", "Observation", "REFUTED",
           "bucket_index", "decode_map_state", "decode_observation", "encode_map_state", "encode_observation", "stream_id_ms",
           "time_of_id"]
