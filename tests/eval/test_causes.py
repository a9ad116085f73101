"""Sorting false positives and misses by cause."""

from worldtrack.eval import CAUSES, error_causes, evaluate_detailed
from worldtrack.io.tracks import TrackTable


def test_each_kind_of_error_is_named():
    gt = TrackTable.from_arrays(
        frame=[0, 0, 1, 1, 2], id=[1, 2, 3, 4, 5],
        x=[0.0, 5.0, 0.0, 0.6, 0.0], y=[0.0] * 5)
    pred = TrackTable.from_arrays(
        frame=[0, 0, 0, 1, 2], id=[1, 2, 3, 4, 5],
        x=[0.1, 0.3, 9.0, 0.2, 0.8], y=[0.0, 0.0, 9.0, 0.0, 0.0])
    pairs = evaluate_detailed(gt, pred, gate=0.5).pairs
    counts = error_causes(gt, pred, pairs, near=1.0)
    assert counts == {
        "fp duplicate": 1,      # frame 0: track 2 beside person 1, whom track 1 has
        "fp ghost": 1,          # frame 0: track 3, 12 m from everybody
        "miss no track": 1,     # frame 0: person 2, no track within 1 m
        "miss shared": 1,       # frame 1: person 4, 0.4 m from track 4, which is person 3's
        "fp displaced": 1,      # frame 2: track 5, 0.8 m from person 5 - outside the 0.5 m gate
        "miss displaced": 1,    # ... and person 5 with it
    }
    assert set(counts) == set(CAUSES)


def test_a_perfect_tracker_has_no_errors_to_sort():
    gt = TrackTable.from_arrays(frame=[0, 1], id=[1, 1], x=[0.0, 0.1], y=[0.0, 0.0])
    counts = error_causes(gt, gt, evaluate_detailed(gt, gt, gate=0.5).pairs)
    assert sum(counts.values()) == 0
