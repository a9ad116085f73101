"""How each person's own track is first lost, for a run started on everyone's true place.

Started from the truth (``init_from_gt``), track ids are the people's ids, so for every person
one can follow *their own* track and say when and how it first stops being within the gate of
them (after having been). :func:`first_losses` sorts those first losses into:

* **ended out of sight** — the track is gone, the person was < 20 % visible then (walked out of
  the image, or behind a pillar or others);
* **ended in view** — the track is gone although the person shows;
* **onto a neighbour** — the track is within the gate of somebody else (pulled onto them: two
  tracks on one person, and this one uncovered);
* **along the ray** / **across the ray** — the track is off by more than the gate, mostly along
  the camera's line of sight through the person (depth) or across it.

Each loss also carries the person's visible share at that frame.

:func:`coverage` asks the question "held" rests on, for any run (cold start too): in each frame, is
each scored person (at least 20 % visible) covered by a track of their own — the nearest track
within the gate, of which they are the nearest person? If not, what is near them:

* **under a neighbour's track on the same ray** — the nearest track (within 1 m) is within the gate of
  somebody else who stands within 5° of the same line of sight: one track for two people, one
  behind the other (one camera cannot tell them apart by the silhouette's outline);
* **under a neighbour's track beside** — the same, the other person off that ray;
* **a track between** — the nearest track is within 1 m of them and within the gate of nobody;
* **no track within 1 m** — nobody proposed them, or their track ended.

>>> from worldtrack.io.tracks import TrackTable
>>> gt = TrackTable.from_arrays([0, 1, 0, 1], [1, 1, 2, 2], [2.0, 2.0, 4.0, 4.0], [0.0, 0.0, 0.0, 0.0],
...                             extra={"vis_c": np.ones(4)})
>>> pred = TrackTable.from_arrays([0, 1, 0, 1], [1, 1, 2, 2], [2.0, 3.0, 4.0, 4.0], [0.0, 0.0, 0.0, 0.3])
>>> first_losses(gt, pred, np.array([0.0, 0.0]))
Counter({'along the ray': 1})
"""

from __future__ import annotations

from collections import Counter

import numpy as np

LOSSES = ("ended out of sight", "ended in view", "onto a neighbour", "along the ray", "across the ray")
#: What is near a scored person in a frame (:func:`coverage`).
COVERAGE = ("own track", "under a neighbour's track on the same ray", "under a neighbour's track beside",
            "a track between", "no track within 1 m")
#: Two people within this angle (degrees) of one line of sight stand "on the same ray".
SAME_RAY_DEG = 5.0


def _visibility(gt) -> np.ndarray:
    vis = [gt.column(c) for c in gt.columns if c.startswith("vis_")]
    return np.max(np.vstack(vis), axis=0) if vis else np.ones(len(gt))


def first_losses(gt, pred, camera_xy: np.ndarray, gate: float = 0.5, min_visibility: float = 0.2) -> Counter:
    """Counter of :data:`LOSSES`: how each person's own track (same id) was first lost.

    Parameters
    ----------
    gt, pred : TrackTable — every ground-truth row and every reported track row (ids shared)
    camera_xy : (2,) — the camera's foot point on the floor, m
    gate : float — within this a track holds its person, m
    min_visibility : float — below this visible share a person is out of sight
    """
    vis = _visibility(gt)
    out: Counter = Counter()
    by_frame = {f: np.flatnonzero(gt.frame == f) for f in np.unique(gt.frame)}
    for pid in np.unique(gt.id):
        rows = np.flatnonzero(gt.id == pid)
        held = False
        for r in rows[np.argsort(gt.frame[rows])]:
            f, p = gt.frame[r], np.array([gt.x[r], gt.y[r]])
            own = np.flatnonzero((pred.frame == f) & (pred.id == pid))
            if len(own) and np.hypot(pred.x[own[0]] - p[0], pred.y[own[0]] - p[1]) < gate:
                held = True
                continue
            if not held:
                continue
            if not len(own):
                out["ended out of sight" if vis[r] < min_visibility else "ended in view"] += 1
                break
            t = np.array([pred.x[own[0]], pred.y[own[0]]])
            others = by_frame[f][gt.id[by_frame[f]] != pid]
            if len(others) and np.hypot(gt.x[others] - t[0], gt.y[others] - t[1]).min() < gate:
                out["onto a neighbour"] += 1
                break
            ray = (p - camera_xy) / max(np.linalg.norm(p - camera_xy), 1e-9)
            off = t - p
            out["along the ray" if abs(off @ ray) >= abs(off[0] * ray[1] - off[1] * ray[0]) else "across the ray"] += 1
            break
    return out


def coverage(gt, pred, camera_xy: np.ndarray, gate: float = 0.5, min_visibility: float = 0.2,
             near: float = 1.0) -> Counter:
    """Counter of :data:`COVERAGE` over the person-frames at least ``min_visibility`` visible.

    Parameters
    ----------
    gt, pred : TrackTable — every ground-truth row and every reported track row
    camera_xy : (2,) — the camera's foot point on the floor, m
    gate : float — a track within this of a person may be theirs, m
    min_visibility : float — less visible people are not counted
    near : float — farther than this from every track, a person has "no track", m
    """
    vis = _visibility(gt)
    out: Counter = Counter()
    cos_same = np.cos(np.radians(SAME_RAY_DEG))
    for f in np.unique(gt.frame):
        g = np.flatnonzero(gt.frame == f)
        p = np.flatnonzero(pred.frame == f)
        shown = vis[g] >= min_visibility
        if not len(p):
            out["no track within 1 m"] += int(shown.sum())
            continue
        gxy = np.column_stack([gt.x[g], gt.y[g]])
        d = np.hypot(gxy[:, None, 0] - pred.x[p][None], gxy[:, None, 1] - pred.y[p][None])   # (G, P), m
        nearest_person = d.argmin(axis=0)                                                    # (P,)
        track_gated = d[nearest_person, np.arange(len(p))] < gate
        ray = gxy - camera_xy
        ray /= np.maximum(np.linalg.norm(ray, axis=1, keepdims=True), 1e-9)
        for k in np.flatnonzero(shown):
            if np.any((nearest_person == k) & track_gated & (d[k] < gate)):
                out["own track"] += 1
                continue
            j = int(d[k].argmin())
            if d[k, j] >= near:
                out["no track within 1 m"] += 1
            elif not track_gated[j]:
                out["a track between"] += 1
            else:
                same = ray[k] @ ray[nearest_person[j]] >= cos_same
                out["under a neighbour's track on the same ray" if same else "under a neighbour's track beside"] += 1
    return out


__all__ = ["COVERAGE", "LOSSES", "coverage", "first_losses"]
