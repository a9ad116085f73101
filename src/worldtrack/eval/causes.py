"""Why a tracker's MOTA is what it is: false positives and misses sorted by cause.

MOTA counts every unmatched track and person the same; what to fix depends on why they are
unmatched. With the matched pairs of :func:`worldtrack.eval.evaluate_detailed`, each frame's

* false positive (a track matched to nobody) is a ``ghost`` when no person is within ``near``
  metres, a ``duplicate`` when the nearest person is matched to another track, and ``displaced``
  when the nearest person is matched to no track (the same error is also counted as a miss);
* miss (a person matched to no track) is ``no track`` when no track is within ``near`` metres,
  ``shared`` when the nearest track is matched to somebody else (two people close together under
  one track), and ``displaced`` otherwise.
"""

from __future__ import annotations

from collections import Counter

import numpy as np

from worldtrack.io.tracks import TrackTable

#: The causes, in the order tables list them.
CAUSES = ("fp ghost", "fp duplicate", "fp displaced", "miss no track", "miss shared", "miss displaced")


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
    pred_matched = set(zip(np.asarray(pairs["frame"]).tolist(), np.asarray(pairs["pred_id"]).tolist()))
    gt_matched = set(zip(np.asarray(pairs["frame"]).tolist(), np.asarray(pairs["gt_id"]).tolist()))
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
