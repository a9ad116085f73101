"""Candidates two workers confirm together: a person one worker proposes but cannot confirm alone
is confirmed when another worker's camera shows somebody at that place.

One process with both cameras confirms a person at once when two cameras show their foreground
(the ellipsoid tracker's ``confirm.views``): somebody standing right under one camera (only head
and shoulders at the bottom of its image, too little to confirm on) and seen whole but small by a
camera across the room is a person to it. Two workers with one camera each do not have that rule:
the near worker holds a capture candidate it never confirms, the far one proposes nothing, and the
person is missing from the map until they walk into the room. So, through the observation streams:

1. each worker publishes its tracker's candidates with the observation of the camera that
   proposed them (``Observation.candidates``, :func:`candidates_in_views`);
2. every worker reads the other cameras' latest observations (:func:`read_others`; in a batch
   run before its step, those before its frame: the complete previous bucket, so runs repeat);
3. after its step it looks in its own cameras' foreground for somebody within ``merge_distance_m``
   of each candidate of another worker (:func:`somebody_near`; :func:`shows_somebody` is the
   positive counterpart of :func:`~worldtrack.map.evidence.looks_empty`) and publishes the
   candidates its camera shows somebody at whom nobody it tracks explains (``Observation.affirms``,
   :func:`affirmed`);
4. the worker whose candidate it was confirms it at its next step (:func:`confirm_affirmed`),
   with a new id from the map (or the id of a person the map has there), and tracks them on.

The candidate keeps its own worker's position, and the other worker takes the confirmed person
from the map as it takes any hand-over. The cost: one pipelined read of the other cameras' latest
observations per step, and the search only where another worker has candidates.

>>> from worldtrack.trackers.base import PositionMap
>>> near = PositionMap()
>>> _ = near.add(10.8, 2.0, time=0.0, tentative=True)       # right under the east camera
>>> east = Observation("east", 0.0, "w-east", 0, 0.0, candidates=((10.8, 2.0, 1.7, 0.45),))
>>> west = Observation("west", 0.1, "w-west", 1, 0.1, affirms=(("w-east", 10.8, 2.0),))  # it shows somebody
>>> confirm_affirmed(near, [west], "w-east", 0.2, 0.5)
[1]
"""

from __future__ import annotations

import math
from typing import Any, Mapping, Sequence

import cv2
import numpy as np

from worldtrack.geometry.camera import Camera
from worldtrack.map.connection import MapKeys
from worldtrack.map.evidence import LEAD_SHARE, emptiness, in_views, people_boxes
from worldtrack.map.messages import MapState, Observation, decode_observation, stream_id_ms
from worldtrack.trackers.base import PositionMap

#: A place shows somebody when at least this share of the part of a person's box there that
#: nobody else explains is foreground (a person fills about half of their box;
#: :data:`~worldtrack.map.evidence.EMPTY_SHARE` is the empty counterpart).
PRESENT_SHARE = 0.3


def candidates_in_views(local: PositionMap, cameras: Mapping[str, Camera]) -> dict[str, list[tuple]]:
    """Per camera, the tracker's unconfirmed candidates (negative ids), as ``(x, y, height, width)``
    m: under the camera whose foreground proposed them (``Person.birth_camera``), else under each
    camera whose view they are in, else under the first camera (a person right under a camera shows
    neither feet nor head in its image, only shoulders)."""
    out: dict[str, list[tuple]] = {c: [] for c in cameras}
    names = list(cameras)
    for p in local:
        if p.id >= 0 or p.confirmed or not names:
            continue
        under = [p.birth_camera] if p.birth_camera in cameras else \
            [c for c, ok in zip(names, in_views(list(cameras.values()), np.array([p.x, p.y]), p.height)) if ok]
        for c in under or names[:1]:
            out[c].append((p.x, p.y, p.height, p.width))
    return out


def read_others(client: Any, keys: MapKeys, cameras: Sequence[str], before: float | None,
                within_s: float) -> list[Observation]:
    """Each of ``cameras``' latest observation captured before ``before`` (s) and at most
    ``within_s`` earlier (None: the newest; one pipelined ``XREVRANGE`` per camera); malformed
    entries are skipped."""
    hi, lo = ("+", "-") if before is None else (stream_id_ms(before) - 1, max(stream_id_ms(before - within_s), 0))
    if not cameras or (before is not None and hi < lo):
        return []
    pipe = client.pipeline(transaction=False)
    for c in cameras:
        pipe.xrevrange(keys.observations(c), max=str(hi), min=str(lo), count=1)
    out = []
    for entries in pipe.execute():
        for _, fields in entries:
            try:
                out.append(decode_observation(fields))
            except ValueError:
                continue
    return out


def shows_somebody(cam: Camera, mask: np.ndarray | None, xy: np.ndarray, height: float, width: float,
                   occlusion: np.ndarray | None = None, blockers: np.ndarray | None = None) -> bool:
    """Positive evidence: does ``cam`` show somebody at floor point ``xy`` (m) that the people of
    ``blockers`` (:func:`~worldtrack.map.evidence.people_boxes`) do not explain?

    Yes when at least :data:`~worldtrack.map.evidence.LEAD_SHARE` of a person's axis points there
    show (in the image, not behind an obstacle nor behind a blocker), at least 30 % of their box is
    open (not cut by the border, an obstacle or a blocker's box) and at least
    :data:`PRESENT_SHARE` of that open part is foreground in ``mask``. No mask: False.

    >>> cam = Camera.look_at("c", 320, 240, [0.0, 0.0, 3.0], [4.0, 0.0, 0.0], hfov_deg=60)
    >>> from worldtrack.map.evidence import people_boxes
    >>> mask = np.zeros((240, 320), np.uint8)
    >>> u0, v0, u1, v1, _ = people_boxes(cam, np.array([[8.0, 0.0, 1.7, 0.45]]))[0].astype(int)
    >>> mask[max(v0, 0):v1, u0:u1] = 1                              # somebody 8 m away
    >>> shows_somebody(cam, mask, np.array([8.0, 0.0]), 1.7, 0.45)
    True
    >>> shows_somebody(cam, mask, np.array([8.0, 2.0]), 1.7, 0.45)   # two metres aside: nobody
    False
    """
    if mask is None or mask.shape[:2] != (cam.height, cam.width):
        return False
    shown, open_share, foreground = emptiness(cam, mask, xy, height, width, occlusion, blockers)
    return shown >= LEAD_SHARE and open_share >= 0.3 and foreground >= PRESENT_SHARE


def unexplained(mask: np.ndarray, blockers: np.ndarray | None) -> np.ndarray:
    """The integral image (``cv2.integral``, (H+1, W+1)) of the foreground of ``mask`` outside the
    boxes of ``blockers`` (:func:`~worldtrack.map.evidence.people_boxes`)."""
    fg = (mask != 0).astype(np.uint8)
    for b in (blockers if blockers is not None else ()):
        fg[max(0, int(b[1])):max(0, int(np.ceil(b[3]))), max(0, int(b[0])):max(0, int(np.ceil(b[2])))] = 0
    return cv2.integral(fg)


def somebody_near(cam: Camera, mask: np.ndarray | None, xy: np.ndarray, height: float, width: float,
                  occlusion: np.ndarray | None = None, blockers: np.ndarray | None = None,
                  radius_m: float = 0.5, step_m: float = 0.1, summed: np.ndarray | None = None) -> np.ndarray | None:
    """The floor place within ``radius_m`` of ``xy`` (m) whose person box in ``cam`` holds the most
    foreground nobody of ``blockers`` explains (the nearest of equals), if :func:`shows_somebody`
    there; else None. A candidate proposed from a view that shows only part of a person is off by a
    few tenths of a metre; the other view's foreground tells where they are. ``summed``: the
    :func:`unexplained` integral image of ``mask`` and ``blockers`` (computed here if not given).

    >>> cam = Camera.look_at("c", 320, 240, [0.0, 0.0, 3.0], [4.0, 0.0, 0.0], hfov_deg=60)
    >>> from worldtrack.map.evidence import people_boxes
    >>> mask = np.zeros((240, 320), np.uint8)
    >>> u0, v0, u1, v1, _ = people_boxes(cam, np.array([[8.0, 0.4, 1.7, 0.45]]))[0].astype(int)
    >>> mask[max(v0, 0):v1, u0:u1] = 1                              # somebody 0.4 m aside
    >>> shows_somebody(cam, mask, np.array([8.0, 0.0]), 1.7, 0.45)
    False
    >>> round(float(somebody_near(cam, mask, np.array([8.0, 0.0]), 1.7, 0.45)[1]), 1)   # across the view
    0.4
    """
    if mask is None or mask.shape[:2] != (cam.height, cam.width):
        return None
    grid = np.arange(-radius_m, radius_m + 1e-9, step_m)
    offsets = np.stack(np.meshgrid(grid, grid), -1).reshape(-1, 2)
    offsets = offsets[np.hypot(*offsets.T) <= radius_m + 1e-9]
    places = xy[None, :] + offsets
    summed = unexplained(mask, blockers) if summed is None else summed
    box = people_boxes(cam, np.column_stack([places, np.full(len(places), height), np.full(len(places), width)]))
    u0, v0 = (np.clip(np.floor(box[:, k]), 0, lim).astype(int) for k, lim in ((0, cam.width), (1, cam.height)))
    u1, v1 = (np.clip(np.ceil(box[:, k]), 0, lim).astype(int) for k, lim in ((2, cam.width), (3, cam.height)))
    area = np.maximum((box[:, 2] - box[:, 0]) * (box[:, 3] - box[:, 1]), 1.0)
    share = (summed[v1, u1] - summed[v0, u1] - summed[v1, u0] + summed[v0, u0]) / area
    best = places[np.lexsort((np.hypot(*offsets.T), -np.round(share, 3)))[0]]
    return best if shows_somebody(cam, mask, best, height, width, occlusion, blockers) else None


def affirmed(others: Sequence[Observation], name: str, cameras: Mapping[str, Camera],
             masks: Mapping[str, np.ndarray | None], occlusion: Mapping[str, np.ndarray | None],
             boxes: Mapping[str, np.ndarray], held: np.ndarray, near_m: float) -> dict[str, list[tuple]]:
    """Per camera of this worker (``name``), the candidates of other workers' observations
    ``others`` it shows somebody near (:func:`somebody_near`, within ``near_m``), as ``(their
    worker, x, y)``: not within ``near_m`` of a person this worker holds (``held``, (n, 2) m: that
    person is on the map already), the boxes of the people it holds (``boxes``, per camera)
    explaining their own foreground."""
    out: dict[str, list[tuple]] = {c: [] for c in cameras}
    summed: dict[str, np.ndarray] = {}         # per camera, once a candidate needs it
    for o in others:
        if o.worker == name:
            continue
        for x, y, h, w in o.candidates:
            xy = np.array([x, y])
            if len(held) and np.hypot(*(held - xy).T).min() < near_m:
                continue
            for c, cam in cameras.items():
                mask = masks.get(c)
                if mask is None or mask.shape[:2] != (cam.height, cam.width):
                    continue
                if c not in summed:
                    summed[c] = unexplained(mask, boxes.get(c))
                found = somebody_near(cam, mask, xy, h, w, occlusion.get(c), boxes.get(c), near_m, summed=summed[c])
                if found is not None:
                    out[c].append((o.worker, x, y))
    return out


def confirm_affirmed(local: PositionMap, others: Sequence[Observation], name: str, t: float,
                     radius_m: float) -> list[int]:
    """Confirm this worker's (``name``) candidates within ``radius_m`` of a place another worker's
    camera affirmed (``Observation.affirms`` for ``name`` in ``others``); returns their new ids.

    >>> from worldtrack.trackers.base import PositionMap
    >>> m = PositionMap()
    >>> c = m.add(10.8, 2.0, time=0.0, tentative=True)
    >>> o = Observation("west", 0.1, "w1", 1, 0.1, affirms=(("w2", 10.9, 2.1),))
    >>> confirm_affirmed(m, [o], "w2", 0.2, 0.5), m[1].mode, m[1].confirmed
    ([1], 'tracking', True)
    """
    places = [(x, y) for o in others if o.worker != name for w, x, y in o.affirms if w == name]
    if not places:
        return []
    new = []
    for p in local:
        if p.id >= 0 or p.confirmed or p.mode != "capture":
            continue
        if min(math.hypot(p.x - x, p.y - y) for x, y in places) < radius_m:
            pid = local.promote(p.id)
            p.mode, p.confirmed, p.vx, p.vy = "tracking", True, 0.0, 0.0
            p.reset("held", t)
            p.reset("low", t)
            new.append(pid)
    return new


class CandidateExchange:
    """A worker's side of steps 1-4 (module docstring): :meth:`read` the other cameras' latest
    observations (in a batch run before each step, those before its frame: runs repeat; on live
    cameras after publishing, off the capture-to-map path), :meth:`confirm` this worker's affirmed
    candidates before its step, and ``after_step``: what to publish per camera, its own candidates
    and the other workers' it affirms.

    Parameters
    ----------
    client, keys : the map's Redis client and keys
    name : this worker's name
    cameras : {camera_id: Camera} — this worker's cameras
    occlusion : {camera_id: (H, W) floor distance of the scene's obstacles}
    near_m : candidates this close (m) to an affirmed place, or to a person held, are that person
    within_s : how old (s) another camera's latest observation may be
    """

    def __init__(self, client: Any, keys: MapKeys, name: str, cameras: Mapping[str, Camera],
                 occlusion: Mapping[str, np.ndarray | None], near_m: float, within_s: float = 0.5):
        self.client, self.keys, self.name = client, keys, name
        self.cameras, self.occlusion, self.near_m, self.within_s = dict(cameras), dict(occlusion), near_m, within_s
        self.others: list[Observation] = []
        self.confirmed = 0          # candidates confirmed on another worker's view (the worker's last line says)

    def read(self, state: MapState | None, before: float | None = None) -> None:
        """Read the latest observation of each other camera the map state ``state`` has reports of
        (captured before ``before`` s; None: the newest)."""
        mine = set(self.cameras)
        cams = sorted({c for c, _, _ in state.reports} - mine) if state is not None else []
        self.others = read_others(self.client, self.keys, cams, before, self.within_s)

    def before_step(self, local: PositionMap, state: MapState | None, t: float, read: bool) -> list[int]:
        """Before the step at ``t``: with ``read`` (a batch run), :meth:`read` the observations
        before ``t`` of the cameras of ``state`` (the complete previous bucket); then :meth:`confirm`."""
        if read:
            self.read(state, t)
        return self.confirm(local, t)

    def confirm(self, local: PositionMap, t: float) -> list[int]:
        """Confirm this worker's candidates the other cameras' observations read affirm (new ids)."""
        new = confirm_affirmed(local, self.others, self.name, t, self.near_m)
        self.confirmed += len(new)
        return new

    def after_step(self, tracker: Any, tracks: Sequence[Any], boxes: Mapping[str, np.ndarray],
                   cams: Sequence[str]) -> tuple[dict[str, list[tuple]], dict[str, list[tuple]]]:
        """Per camera of ``cams``: this worker's candidates, and the places of the other workers'
        candidates its camera shows somebody at (``boxes``: the people it holds, per camera)."""
        mine = {c: self.cameras[c] for c in cams}
        candidates = candidates_in_views(tracker.position_map, mine)
        overlay = getattr(tracker, "overlay", None)
        masks = {c: getattr(overlay(c), "mask", None) if overlay is not None else None for c in cams}
        held = np.array([[tr.x, tr.y] for tr in tracks], float).reshape(-1, 2)
        return candidates, affirmed(self.others, self.name, mine, masks, self.occlusion, boxes, held, self.near_m)


__all__ = ["PRESENT_SHARE", "CandidateExchange", "affirmed", "candidates_in_views", "confirm_affirmed",
           "read_others", "shows_somebody", "somebody_near", "unexplained"]
