"""Why a tracker's MOTA is what it is: false positives and misses sorted by cause.

MOTA counts every unmatched track and person the same; what to fix depends on why they are
unmatched. With the matched pairs of :func:`worldtrack.eval.evaluate_detailed`, each frame's

* false positive (a track matched to nobody) is a ``ghost`` when no person is within ``near``
  metres, a ``duplicate`` when the nearest person is matched to another track, and ``displaced``
  when the nearest person is matched to no track (the same error is also counted as a miss);
* miss (a person matched to no track) is ``no track`` when no track is within ``near`` metres,
  ``shared`` when the nearest track is matched to somebody else (two people close together under
  one track), and ``displaced`` otherwise.

:func:`errors_by_views` sorts the same errors by how many cameras see the place: with one camera a
person's distance along its line of sight rests on their height alone.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable

import numpy as np

from worldtrack.geometry.camera import Camera
from worldtrack.io.tracks import TrackTable

#: The causes, in the order tables list them.
CAUSES = ("fp ghost", "fp duplicate", "fp displaced", "miss no track", "miss shared", "miss displaced")


def _matched(pairs: dict, column: str) -> set[tuple[int, int]]:
    """The (frame, id) keys of ``column`` ("gt_id" or "pred_id") in the matched ``pairs``."""
    return set(zip(np.asarray(pairs["frame"]).tolist(), np.asarray(pairs[column]).tolist()))


def error_causes(gt: TrackTable, pred: TrackTable, pairs: dict, near: float = 1.0) -> Counter:
    """Count false positives and misses by cause (see the module notes).

    Parameters
    ----------
    gt, pred : the scored ground truth and predictions
    pairs : ``evaluate_detailed(...).pairs`` — matched ``frame``, ``gt_id``, ``pred_id`` columns
    near : metres — a track farther than this from every person is a ghost, and vice versa

    Returns
    -------
    Counter keyed by :data:`CAUSES`
    """
    pred_matched, gt_matched = _matched(pairs, "pred_id"), _matched(pairs, "gt_id")
    out: Counter = Counter({c: 0 for c in CAUSES})
    for frame in np.unique(np.concatenate([gt.frame, pred.frame])).tolist():
        g, p = gt.frame == frame, pred.frame == frame
        gid, pid = gt.id[g].tolist(), pred.id[p].tolist()
        gxy = np.column_stack([gt.x[g], gt.y[g]])
        pxy = np.column_stack([pred.x[p], pred.y[p]])
        # (G, P) distances, metres.
        d = np.linalg.norm(gxy[:, None] - pxy[None], axis=2) if gid and pid else np.zeros((len(gid), len(pid)))
        for j, track in enumerate(pid):
            if (frame, track) in pred_matched:
                continue
            i = int(np.argmin(d[:, j])) if gid else -1
            if i < 0 or d[i, j] > near:
                out["fp ghost"] += 1
            else:
                out["fp duplicate" if (frame, gid[i]) in gt_matched else "fp displaced"] += 1
        for i, person in enumerate(gid):
            if (frame, person) in gt_matched:
                continue
            j = int(np.argmin(d[i])) if pid else -1
            if j < 0 or d[i, j] > near:
                out["miss no track"] += 1
            else:
                out["miss shared" if (frame, pid[j]) in pred_matched else "miss displaced"] += 1
    return out


def views_of(x: np.ndarray, y: np.ndarray, cameras: Iterable[Camera], head_z: float = 1.6) -> np.ndarray:
    """How many of ``cameras`` see a person standing at each floor point, feet and head.

    Parameters
    ----------
    x, y : (N,) metres — floor points
    cameras : the cameras
    head_z : metres — a camera sees the person when both ``(x, y, 0)`` and ``(x, y, head_z)`` are in
        front of it and project inside its image

    Returns
    -------
    (N,) int — the number of cameras
    """
    xy = np.column_stack([np.asarray(x, float).reshape(-1), np.asarray(y, float).reshape(-1)])
    count = np.zeros(len(xy), dtype=int)
    for cam in cameras:
        count += cam.sees_standing(xy, head_z)
    return count


def errors_by_views(gt: TrackTable, pred: TrackTable, pairs: dict, cameras: Iterable[Camera],
                    head_z: float = 1.6) -> dict[int, dict[str, int]]:
    """People, misses, tracks and false positives by how many cameras see the place (:func:`views_of`).

    Parameters
    ----------
    gt, pred, pairs : as :func:`error_causes`
    cameras : the scene's cameras
    head_z : metres

    Returns
    -------
    {views: {"people": …, "misses": …, "tracks": …, "false positives": …}} — person rows and their
    misses by the views of the person's true place, track rows and their false positives by the
    views of the track's place; one key per number of views that occurs
    """
    cameras = list(cameras)
    out: dict[int, dict[str, int]] = {}
    for table, matched, total, wrong in ((gt, _matched(pairs, "gt_id"), "people", "misses"),
                                         (pred, _matched(pairs, "pred_id"), "tracks", "false positives")):
        views = views_of(table.x, table.y, cameras, head_z)
        hit = np.array([key in matched for key in zip(table.frame.tolist(), table.id.tolist())], dtype=bool)
        for v in np.unique(views).tolist():
            row = out.setdefault(int(v), {"people": 0, "misses": 0, "tracks": 0, "false positives": 0})
            row[total] += int((views == v).sum())
            row[wrong] += int(((views == v) & ~hit).sum())
    return dict(sorted(out.items()))
