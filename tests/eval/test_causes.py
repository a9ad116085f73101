"""Sorting false positives and misses by cause."""

from worldtrack.eval import CAUSES, error_causes, errors_by_views, evaluate_detailed, views_of
from worldtrack.geometry.camera import Camera
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


def _overhead_pair():
    """Two cameras 5 m up looking straight down, 4 m apart, 90° across: a camera sees feet up to 5 m
    and a 1.6 m head up to 3.4 m to either side of it along x."""
    return [Camera.look_at(c, 640, 480, [x, 0.0, 5.0], [x, 0.0, 0.0], hfov_deg=90.0) for c, x in (("a", 0.0), ("b", 4.0))]


def test_a_camera_sees_a_place_only_when_it_sees_both_feet_and_head():
    # x = 3.3: head 3.3 m from camera a's axis (inside its 3.4 m); x = 3.5: feet in view, head not.
    views = views_of([2.0, 3.3, 3.5, -2.0, 20.0], [0.0] * 5, _overhead_pair())
    assert views.tolist() == [2, 2, 1, 1, 0]


def test_errors_are_sorted_by_the_views_of_the_place():
    gt = TrackTable.from_arrays(frame=[0, 0, 0], id=[1, 2, 3], x=[2.0, -2.0, 20.0], y=[0.0, 0.0, 0.0])
    # Track 1 on person 1 (both cameras see them); track 2 2 m beside person 2 (camera a only); person 3
    # is out of every view and has no track.
    pred = TrackTable.from_arrays(frame=[0, 0], id=[1, 2], x=[2.1, -2.0], y=[0.0, 2.0])
    pairs = evaluate_detailed(gt, pred, gate=0.5).pairs
    assert errors_by_views(gt, pred, pairs, _overhead_pair()) == {
        0: {"people": 1, "misses": 1, "tracks": 0, "false positives": 0},
        1: {"people": 1, "misses": 1, "tracks": 1, "false positives": 1},
        2: {"people": 1, "misses": 0, "tracks": 1, "false positives": 0},
    }
