"""The entry benchmark's figures count what they say: pairs split on entry, and where the error is."""

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from types import SimpleNamespace  # noqa: E402

from particle_entry import _pairs_split_on_entry, error_breakdown  # noqa: E402

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


def _table(rows: list[tuple[int, int, float, float]]) -> TrackTable:
    a = np.array(rows, dtype=float)
    return TrackTable.from_arrays(a[:, 0].astype(int), a[:, 1].astype(int), a[:, 2], a[:, 3])


def test_error_breakdown_splits_the_error_along_and_across_the_line_of_sight_and_by_situation():
    # Camera at the origin. Person 1 walks along +x at 1 m/s (10 frames/s), alone; person 2 stands
    # at (0, 4) with person 3 0.5 m beside it.
    seq = SimpleNamespace(scenario=SimpleNamespace(fps=10.0, scene=SimpleNamespace(
        cameras={"cam": SimpleNamespace(centre=np.array([0.0, 0.0, 3.0]))})))
    gt = _table([(f, 1, 3.0 + 0.1 * f, 0.0) for f in range(3)] + [(f, 2, 0.0, 4.0) for f in range(3)]
                + [(f, 3, 0.5, 4.0) for f in range(3)])
    # Track of 1 at frame 1: 0.3 m too far along its line of sight (+x), 0.4 m across (+y).
    # Track of 2 at frame 1: 0.1 m across its line of sight (−x).
    pred = _table([(1, 7, 3.1 + 0.3, 0.4), (1, 8, -0.1, 4.0)])
    q = np.array([1, 4])          # gt rows: person 1 and person 2 at frame 1
    j = np.array([0, 1])
    out = error_breakdown(seq, gt, gt, pred, j, q)
    assert np.isclose(out["err_along_m"], 0.15)              # (0.3 + 0) / 2
    assert np.isclose(out["err_across_m"], 0.25)             # (0.4 + 0.1) / 2
    assert np.isclose(out["err_alone_m"], 0.5)               # person 1 only: hypot(0.3, 0.4)
    assert np.isclose(out["err_near_m"], 0.1)                # person 2, 0.5 m from person 3
    assert np.isclose(out["near_pct"], 50.0)
    assert np.isclose(out["err_walking_m"], 0.5)             # 1 m/s
    assert np.isclose(out["err_standing_m"], 0.1)


def test_error_breakdown_counts_only_neighbours_in_the_same_frame():
    seq = SimpleNamespace(scenario=SimpleNamespace(fps=10.0, scene=SimpleNamespace(
        cameras={"cam": SimpleNamespace(centre=np.array([0.0, 0.0, 3.0]))})))
    # Person 2 stands at (0, 4) in frames 0-2; person 3 stands beside it only in frame 2.
    gt = _table([(f, 2, 0.0, 4.0) for f in range(3)] + [(2, 3, 0.5, 4.0)])
    pred = _table([(1, 8, -0.1, 4.0), (2, 8, -0.2, 4.0)])
    out = error_breakdown(seq, gt, gt, pred, np.array([0, 1]), np.array([1, 2]))
    assert np.isclose(out["err_alone_m"], 0.1)               # frame 1: nobody else there
    assert np.isclose(out["err_near_m"], 0.2)                # frame 2: person 3 0.5 m away
    assert np.isclose(out["err_standing_m"], 0.15)
