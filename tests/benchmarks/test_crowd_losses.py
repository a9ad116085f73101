"""crowd50's account of how each person's own track was first lost (benchmarks/crowd_losses.py)."""

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from crowd_losses import first_losses  # noqa: E402

from worldtrack.io.tracks import TrackTable  # noqa: E402


def test_each_way_of_losing_a_track_is_told_apart():
    # Camera at the origin; people on the x axis (their ray is x), 2 m apart; 3 frames.
    people = {1: 2.0, 2: 4.0, 3: 6.0, 4: 8.0, 5: 10.0, 6: 12.0, 7: 14.0, 8: 16.0}
    frames, ids, xs = zip(*[(f, i, x) for f in range(3) for i, x in people.items()])
    vis = np.ones(len(ids))
    vis[[k for k, (f, i) in enumerate(zip(frames, ids)) if f == 2 and i == 1]] = 0.1   # 1 out of sight at frame 2
    gt = TrackTable.from_arrays(frames, ids, xs, np.zeros(len(ids)), extra={"vis_c": vis})
    rows = [(f, i, x, 0.0) for f in range(2) for i, x in people.items()]
    rows += [(2, 3, 4.1, 0.0),      # 3's track on person 2
             (2, 4, 9.0, 0.0),      # 4's track 1 m beyond them on the ray
             (2, 5, 10.0, 0.8),     # 5's track 0.8 m across
             (2, 6, 12.2, 0.1),     # 6 still held
             (2, 7, 13.1, 0.0)]     # 7's track 0.9 m nearer the camera; 1, 2 and 8: no track (1 out of sight)
    pred = TrackTable.from_arrays(*(np.array(c) for c in zip(*rows)))
    got = first_losses(gt, pred, np.array([0.0, 0.0]))
    assert got == {"ended out of sight": 1, "ended in view": 2, "onto a neighbour": 1, "along the ray": 2,
                   "across the ray": 1}


def test_a_person_never_held_is_not_counted_as_lost():
    gt = TrackTable.from_arrays([0, 1], [1, 1], [2.0, 2.0], [0.0, 0.0], extra={"vis_c": np.ones(2)})
    pred = TrackTable.from_arrays([0, 1], [1, 1], [3.0, 3.0], [0.0, 0.0])
    assert not first_losses(gt, pred, np.array([0.0, 0.0]))


def test_coverage_tells_what_is_near_each_person_without_a_track_of_their_own():
    from crowd_losses import coverage
    # Camera at the origin. One frame: 1 and 2 one behind the other on the x axis, so are 8 and 9
    # (9 within the gate of 8's track, which is nearer 8), 3 beside 4, 5 alone with a track 0.8 m
    # off, 6 with nothing near, 7 not visible enough to count.
    xy = {1: (4.0, 0.0), 2: (4.7, 0.0), 3: (0.0, 6.0), 4: (0.7, 6.0), 5: (-6.0, 0.0), 6: (0.0, -9.0), 7: (9.0, 9.0),
          8: (-3.0, 3.0), 9: (-3.3, 3.3)}
    ids = list(xy)
    vis = np.array([1.0, 0.6, 1.0, 1.0, 1.0, 1.0, 0.1, 1.0, 0.5])
    gt = TrackTable.from_arrays([0] * 9, ids, [xy[i][0] for i in ids], [xy[i][1] for i in ids], extra={"vis_c": vis})
    pred = TrackTable.from_arrays([0] * 4, [10, 11, 12, 13], [4.05, 0.0, -6.8, -3.0], [0.0, 6.05, 0.0, 3.05])
    got = coverage(gt, pred, np.array([0.0, 0.0]))
    assert got == {"own track": 3, "under a neighbour's track on the same ray": 2, "under a neighbour's track beside": 1,
                   "a track between": 1, "no track within 1 m": 1}
