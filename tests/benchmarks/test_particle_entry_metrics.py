"""The entry benchmark's side-by-side figure counts what the issue asks: pairs split on entry."""

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from particle_entry import _pairs_split_on_entry  # noqa: E402

from worldtrack.io.tracks import TrackTable  # noqa: E402


def _walk(frames: int, people: dict[int, tuple[float, float]]) -> TrackTable:
    """Ground truth: each person standing at (x, y) for ``frames`` frames."""
    rows = [(f, i, x, y) for f in range(frames) for i, (x, y) in people.items()]
    a = np.array(rows, dtype=float)
    return TrackTable.from_arrays(a[:, 0].astype(int), a[:, 1].astype(int), a[:, 2], a[:, 3])


def _pairs(matches: list[tuple[int, int, int]]) -> dict:
    f, g, p = (np.array(c, dtype=int) for c in zip(*matches))
    return {"frame": f, "gt_id": g, "pred_id": p}


def test_a_pair_entering_together_counts_as_split_only_with_two_tracks_within_five_frames():
    gt = _walk(20, {1: (0.0, 0.0), 2: (0.5, 0.0), 3: (3.0, 0.0)})
    full = {1: 2, 2: 4, 3: 4}   # 1 and 2 enter together (0.5 m apart); 3 is far from both
    shared = _pairs([(f, g, 7) for f in range(4, 12) for g in (1, 2)])
    assert _pairs_split_on_entry(gt, shared, full, within=10) == (0, 1)
    late = _pairs([(f, 1, 7) for f in range(4, 20)] + [(f, 2, 8) for f in range(10, 20)])
    assert _pairs_split_on_entry(gt, late, full, within=10) == (0, 1)     # frame 10 > 4 + 5
    early = _pairs([(f, 1, 7) for f in range(4, 20)] + [(f, 2, 8) for f in range(9, 20)])
    assert _pairs_split_on_entry(gt, early, full, within=10) == (1, 1)    # frame 9 = 4 + 5


def test_people_entering_apart_in_place_or_time_are_not_a_pair():
    gt = _walk(40, {1: (0.0, 0.0), 2: (0.9, 0.0), 3: (0.0, 0.5)})
    pairs = _pairs([(f, g, g) for f in range(40) for g in (1, 2, 3)])
    assert _pairs_split_on_entry(gt, pairs, {1: 0, 2: 0}, within=10) == (0, 0)    # 0.9 m apart
    assert _pairs_split_on_entry(gt, pairs, {1: 0, 3: 11}, within=10) == (0, 0)   # 1.1 s apart
    assert _pairs_split_on_entry(gt, pairs, {1: 0, 3: 10}, within=10) == (1, 1)
