"""Births in a crowd one camera sees: a person in front of a farther track, shown by the legs below it.

Seen from one corner, a person standing in front of somebody already tracked farther along the
same line of sight is drawn over by that track's ellipse from the head down to the track's feet:
the binary foreground holds no evidence for them above that row (issue 37, crowd 50 dev seed 109:
60 % of the untracked people at least half visible had their head top inside a known ellipse, 88 %
of these of a person farther than them). What does show is the foreground going on *below* the
farther track's feet, in its columns: the nearer person's legs. The births' residual
(:mod:`.births`) cuts those into slivers under other ellipses, mostly under its smallest blob.

With ``crowd.births_in_front`` every confirmed person's feet are looked below
(:func:`legs_below`): where the foreground in a strip down from their feet pixel (across ±
:data:`STRIP_SHARE` of their length in the image) goes on for at least ``min_extra`` of that length,
a person is proposed with the feet at the foreground's lowest row on that strip
(:func:`in_front_proposals`), at the default height, unless

* the strip reaches the image border (the feet may be beyond it),
* somebody already known covers the feet point (their ellipse reaches down to there: the legs
  are theirs), or stands within ``min_separation`` m of it,
* a person of the default size standing there would not be mostly foreground
  (:data:`MIN_FOREGROUND`).

>>> import numpy as np
>>> mask = np.zeros((60, 20), np.uint8); mask[5:50, 6:14] = 1             # foreground down to row 49
>>> legs_below(mask, np.array([10.0, 30.0]), np.array([0.0, 1.0]), half=3.0, reach=25)
19
>>> legs_below(mask, np.array([10.0, 49.0]), np.array([0.0, 1.0]), half=3.0, reach=25)
0
"""

from __future__ import annotations

import numpy as np

from worldtrack.trackers.ellipsoid.args import People
from worldtrack.trackers.ellipsoid.cameras import CameraView
from worldtrack.trackers.ellipsoid.forms import ellipse_crop
from worldtrack.trackers.ellipsoid.people_edges import covered_share

#: Half the strip looked down (px) from a person's feet, as a share of their length in the image.
STRIP_SHARE = 0.08
#: Rows of less than half foreground that end the legs (a gap shorter than this is a hole in the mask).
GAP_ROWS = 3
#: A proposed person's ellipse (default size) holds at least this share of foreground.
MIN_FOREGROUND = 0.8


def legs_below(mask: np.ndarray, feet: np.ndarray, down: np.ndarray, half: float, reach: int) -> int:
    """How far (px) the foreground goes on below ``feet`` (2,) px along ``down`` (2,), unit.

    A row (9 points across ±``half`` px) counts as foreground when at least half its points are;
    the legs end before :data:`GAP_ROWS` rows in a row that do not. Rows 1 … ``reach`` below the
    feet are looked at; returns the last foreground row's distance (0: none), ``reach`` when they
    go on to the end (or ``-1`` when they reach the image border first: the feet may be beyond).
    """
    down = np.asarray(down, float)
    across = np.array([-down[1], down[0]])
    steps = np.arange(1, reach + 1, dtype=float)
    pts = (np.asarray(feet, float)[None, None] + steps[:, None, None] * down
           + np.linspace(-half, half, 9)[None, :, None] * across)            # (reach, 9, 2)
    q = np.rint(pts).astype(int)
    inside = (q[..., 0] >= 0) & (q[..., 0] < mask.shape[1]) & (q[..., 1] >= 0) & (q[..., 1] < mask.shape[0])
    hit = np.zeros(inside.shape, bool)
    hit[inside] = mask[q[inside][:, 1], q[inside][:, 0]] != 0
    row = hit.mean(axis=1) >= 0.5
    gone = ~row
    # The first run of GAP_ROWS rows without foreground ends the legs.
    run = np.convolve(gone.astype(int), np.ones(GAP_ROWS, int), mode="valid") >= GAP_ROWS
    end = int(np.argmax(run)) if run.any() else reach
    last = np.nonzero(row[:end])[0]
    if not len(last):
        return 0
    extent = int(last[-1]) + 1
    if not inside[:min(extent + GAP_ROWS, reach)].all():
        return -1
    return extent


def in_front_proposals(view: CameraView, mask: np.ndarray, people: People, confirmed: np.ndarray,
                       explained: np.ndarray, height: float, width: float, min_extra: float,
                       min_separation: float) -> list[np.ndarray]:
    """Floor places (2,) m of people in front of confirmed ones, shown by their legs below them.

    Parameters
    ----------
    view : CameraView — the camera
    mask : (H, W) uint8 — its foreground (nonzero)
    people : People — everybody known (confirmed or not)
    confirmed : (N,) bool — which of ``people`` are confirmed (only those are looked below)
    explained : (H, W) uint8 — nonzero inside the known people's (dilated) ellipses
    height, width : float — the default person's size, m
    min_extra : float — the legs below go on for at least this share of the person's length, px/px
    min_separation : float — no proposal within this distance (m) of a known person or another one
    """
    cam = view.camera
    xy = np.asarray(people.xy, float).reshape(-1, 2)
    out: list[np.ndarray] = []
    for k in np.nonzero(np.asarray(confirmed, bool))[0]:
        x, y = xy[k]
        ends = cam.project(np.array([[x, y, 0.0], [x, y, float(people.heights[k])]]))
        if not np.isfinite(ends).all():
            continue
        feet, length = ends[0], float(np.hypot(*(ends[0] - ends[1])))
        down = view.down_direction(feet)
        if down is None or length < 10 or not (0 <= feet[0] < mask.shape[1] and 0 <= feet[1] < mask.shape[0]):
            continue
        extent = legs_below(mask, feet, down, max(1.0, STRIP_SHARE * length), int(1.5 * length))
        if extent < min_extra * length:
            continue   # none, too short, or at the border (-1)
        foot = feet + extent * down
        across = np.array([-down[1], down[0]])
        if covered_share(explained, foot - 3 * down + np.linspace(-2, 2, 5)[:, None] * across) >= 0.5:
            continue   # somebody known reaches down to there: the legs are theirs
        p = cam.backproject(foot[None], 0.0)[0][:2]
        if not np.isfinite(p).all():
            continue
        near = np.vstack([xy] + out) if out else xy
        if len(near) and np.min(np.hypot(*(near - p).T)) < min_separation:
            continue
        if foreground_share(view, mask, p, height, width) < MIN_FOREGROUND:
            continue
        out.append(p)
    return out


def foreground_share(view: CameraView, mask: np.ndarray, xy: np.ndarray, height: float, width: float) -> float:
    """Share of the pixels of a person's ellipse at floor point ``xy`` (2,) m, of ``height`` ×
    ``width`` m, in the image and in front of obstacles, that are foreground in ``mask`` (0: none)."""
    inner, _, box, valid, dist = view.forms(np.asarray(xy, float)[None], np.array([height]), np.array([width]))
    u0, u1, v0, v1 = box[0]
    if not valid[0] or u0 >= u1 or v0 >= v1:
        return 0.0
    inside = ellipse_crop(inner[0], box[0], view.grid, view.args.has_dist) & (view.occ[v0:v1, u0:u1] >= dist[0])
    n = int(inside.sum())
    return float((mask[v0:v1, u0:u1][inside] != 0).sum() / n) if n else 0.0


__all__ = ["GAP_ROWS", "MIN_FOREGROUND", "STRIP_SHARE", "foreground_share", "in_front_proposals", "legs_below"]
