"""Two workers' newborns that one worker's camera shows as one blob are one person.

At a run's start (or when two workers first see somebody in the same instant) each worker starts
the people its own camera shows. A person in the near room is seen close up by the camera there
and small, through a door, by the camera of the other room: the far worker's estimate is off
mostly in depth, along its camera's ray, sometimes by more than the map's newborn gate
(:func:`~worldtrack.map.merges.merge_duplicates`: two newborns from different workers merge when
their trackers' covariances put them close). Both ids then stay on the map: each worker takes the
other's newborn as a hand-over at its next step, and the map never merges ids one worker reports
together (two people it tells apart) — a duplicate until one of them is lost.

The far worker can tell: the other worker's newborn, drawn in its own camera, covers the same
image box as its own newborn (intersection over union ≥ ``map.same_blob_iou``). Its camera cannot
tell two such places apart along its ray; the other camera can, and saw one person. So it
publishes the pair ``(its id, the other's id)`` with its observation (``Observation.same``,
:func:`same_blob_claims`), and the map folds its id into the other's, keeping the other worker's
place (:func:`fold_same_blobs`); every worker then drops or renames its copy (the map's aliases).

Two people born in the same instant on one ray of the far camera, at nearly the same distance, are
one blob to it as well: the near worker still holds both (its newborns are pairs one to one), so the
far worker's one newborn folds into one of them and the other stays.

>>> from worldtrack.geometry.camera import Camera
>>> far = Camera.look_at("east", 320, 240, [11.7, 2.0, 2.5], [0.0, 2.0, 0.0], hfov_deg=60)
>>> mine = np.array([[4.0, 2.7, 1.6, 1.55, 0.45]])            # id 4, 0.9 m off in depth
>>> theirs = np.array([[1.0, 1.8, 1.5, 1.70, 0.45]])          # id 1, the near worker's
>>> same_blob_pairs([far], mine, theirs, 0.5)
[(4, 1)]
>>> same_blob_pairs([far], mine, theirs + [[0, 0, 1.0, 0, 0]], 0.5)   # a metre aside: two people
[]
"""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from worldtrack.geometry.camera import Camera
from worldtrack.map.evidence import people_boxes


def box_iou(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Intersection over union of every box of ``a`` (n, ≥4) with every box of ``b`` (m, ≥4),
    ``u0, v0, u1, v1`` pixels: (n, m). Empty boxes (u1 ≤ u0) overlap nothing.

    >>> box_iou(np.array([[0, 0, 2, 2]]), np.array([[1, 0, 3, 2], [5, 5, 4, 4]]))
    array([[0.33333333, 0.        ]])
    """
    a, b = np.asarray(a, float)[:, None, :4], np.asarray(b, float)[None, :, :4]
    w = np.clip(np.minimum(a[..., 2], b[..., 2]) - np.maximum(a[..., 0], b[..., 0]), 0, None)
    h = np.clip(np.minimum(a[..., 3], b[..., 3]) - np.maximum(a[..., 1], b[..., 1]), 0, None)
    area = lambda x: np.clip(x[..., 2] - x[..., 0], 0, None) * np.clip(x[..., 3] - x[..., 1], 0, None)  # noqa: E731
    union = area(a) + area(b) - w * h
    return np.where(union > 0, w * h / np.where(union > 0, union, 1.0), 0.0)


def same_blob_pairs(cameras: Sequence[Camera], mine: np.ndarray, theirs: np.ndarray,
                    min_iou: float) -> list[tuple[int, int]]:
    """Pairs ``(my id, their id)`` whose image boxes overlap by at least ``min_iou`` in one of
    ``cameras`` (the best over them), one to one, the best overlap first.

    Parameters
    ----------
    cameras : this worker's cameras
    mine, theirs : (n, 5) and (m, 5) ``id, x, y, height, width`` (m): this worker's newborns and
        another worker's
    min_iou : the least intersection over union of the two people's boxes
        (:func:`~worldtrack.map.evidence.people_boxes`)
    """
    mine, theirs = np.asarray(mine, float).reshape(-1, 5), np.asarray(theirs, float).reshape(-1, 5)
    if not len(mine) or not len(theirs) or not len(cameras):
        return []
    iou = np.max([box_iou(people_boxes(c, mine[:, 1:]), people_boxes(c, theirs[:, 1:])) for c in cameras], axis=0)
    pairs, used_mine, used_theirs = [], set(), set()
    for k in np.argsort(-iou, axis=None, kind="stable"):
        i, j = np.unravel_index(k, iou.shape)
        if iou[i, j] < min_iou:
            break
        if i in used_mine or j in used_theirs:
            continue
        used_mine.add(i)
        used_theirs.add(j)
        pairs.append((int(mine[i, 0]), int(theirs[j, 0])))
    return pairs


def same_blob_claims(cameras: Mapping[str, Camera], tracks: Sequence, state, born_here: set[int], t: float,
                     within_s: float, min_iou: float) -> tuple[tuple[int, int], ...]:
    """What a worker publishes (``Observation.same``): its newborns (``tracks`` whose id it gave,
    ``born_here``, not on the map ``state`` or born there less than ``within_s`` before ``t``) that
    one of its cameras shows as one blob with a newborn of another worker on the map (born less than
    ``within_s`` ago, an id this worker did not give), :func:`same_blob_pairs`."""
    if state is None or min_iou <= 0:
        return ()
    on_map = {p.id: p for p in state.present()}
    young = lambda pid: pid not in on_map or t - on_map[pid].born < within_s      # noqa: E731
    mine = [[tr.id, tr.x, tr.y, tr.height, tr.width] for tr in tracks if tr.id in born_here and young(tr.id)]
    if not mine:
        return ()
    theirs = [[p.id, p.x, p.y, p.height, p.width] for p in on_map.values()
              if p.id not in born_here and t - p.born < within_s and np.isfinite([p.height, p.width]).all()]
    return tuple(same_blob_pairs(list(cameras.values()), np.array(mine), np.array(theirs), min_iou))


def fold_same_blobs(state, observations: Sequence, t: float, within_s: float) -> dict[int, int]:
    """The fusion's side: fold each claimed ``(worker's id, other's id)`` of ``observations`` into
    the other's id (kept where the other worker has them), when both are on the map and born less
    than ``within_s`` before ``t``; records the aliases in ``state`` (a
    :class:`~worldtrack.map.fusion.FusionState`) and returns ``{folded: kept}``."""
    merged: dict[int, int] = {}
    for o in observations:
        for mine, theirs in getattr(o, "same", ()):
            a, b = state.resolve(mine), state.resolve(theirs)
            pa, pb = state.people.get(a), state.people.get(b)
            if a == b or pa is None or pb is None or t - min(pa.born, pb.born) >= within_s:
                continue
            pb.workers = max(pb.workers, 2)
            del state.people[a]
            state.aliases[a] = (b, t)
            merged[a] = b
    if merged:
        state.close_since = {k: v for k, v in state.close_since.items() if k[0] not in merged and k[1] not in merged}
    return merged


__all__ = ["box_iou", "fold_same_blobs", "same_blob_claims", "same_blob_pairs"]
