"""The papers' numbers: position errors, follow-a-target precision/recall, angles, RMSE split."""

import numpy as np
import pytest

from worldtrack.eval.tables import (limb_angle_errors_deg, position_errors, rotation_errors_deg,
                                    target_frame_counts, target_precision_recall, track_positions,
                                    trajectory_rmse_split)
from worldtrack.geometry.rotation import euler_zyx, rot_x, rot_z
from worldtrack.io.tracks import TrackTable


def test_position_errors_hand_numbers_and_signs():
    # Frame 0: GT 1 (0, 0) <- P 7 (0.3, -0.4): |d| = 0.5 (on the gate, kept), dx 0.3, dy -0.4.
    #          GT 2 (3, 0) <- P 8 (3.1, 0): |d| = 0.1.
    # Frame 1: GT 1 (0, 0), P 7 (2, 0) is 2 m away: not matched. GT 2 has no prediction.
    gt = TrackTable.from_arrays([0, 0, 1, 1], [1, 2, 1, 2], [0, 3, 0, 3], [0, 0, 0, 0])
    pr = TrackTable.from_arrays([0, 0, 1], [7, 8, 7], [0.3, 3.1, 2.0], [-0.4, 0.0, 0.0])
    e = position_errors(gt, pr, gate=0.5)
    assert e.num_pairs == 2
    assert e.gt_id.tolist() == [1, 2] and e.pred_id.tolist() == [7, 8]
    assert e.dx.tolist() == pytest.approx([0.3, 0.1]) and e.dy.tolist() == pytest.approx([-0.4, 0])
    assert e.mean_m == pytest.approx((0.5 + 0.1) / 2)          # 0.3
    assert e.mean_abs_dx_m == pytest.approx((0.3 + 0.1) / 2)   # 0.2
    assert e.mean_abs_dy_m == pytest.approx((0.4 + 0.0) / 2)   # 0.2


def test_position_errors_maximise_pairs_before_nearest():
    # Gate 0.6 m. GT A (0, 0), B (1, 0); P (0.45, 0): A 0.45, B 0.55; Q (-0.5, 0): A 0.5 only.
    # Greedy smallest-first pairs A-P (0.45) and strands B; the assignment must pair both:
    # A-Q 0.5 and B-P 0.55, mean 0.525.
    gt = TrackTable.from_arrays([0, 0], [1, 2], [0.0, 1.0], [0.0, 0.0])
    pr = TrackTable.from_arrays([0, 0], [5, 6], [0.45, -0.5], [0.0, 0.0])
    e = position_errors(gt, pr, gate=0.6)
    assert dict(zip(e.gt_id.tolist(), e.pred_id.tolist())) == {1: 6, 2: 5}
    assert e.mean_m == pytest.approx(0.525)


@pytest.mark.parametrize("two_candidates", ["person", "prediction"])
def test_position_errors_one_pair_when_one_side_has_two_candidates(two_candidates):
    # Frame 0: one person and two predictions within the gate (or the reverse): one pair, the
    # nearer (0.1 m), not both. Frame 1: disjoint pairs 0.2 and 0.3 m (the shortcut path).
    one, two = ([0.0], [0.1, 0.2]) if two_candidates == "person" else ([0.1, 0.2], [0.0])
    gt = TrackTable.from_arrays([0] * len(one) + [1, 1], list(range(1, len(one) + 1)) + [1, 2],
                                one + [0.0, 5.0], [0.0] * (len(one) + 2))
    pr = TrackTable.from_arrays([0] * len(two) + [1, 1], list(range(7, 7 + len(two))) + [7, 8],
                                two + [0.2, 5.3], [0.0] * (len(two) + 2))
    e = position_errors(gt, pr, gate=0.5)
    assert e.frame.tolist() == [0, 1, 1]
    assert e.distance.tolist() == pytest.approx([0.1, 0.2, 0.3])


def test_position_errors_without_pairs_are_nan():
    gt = TrackTable.from_arrays([0], [1], [0.0], [0.0])
    pr = TrackTable.from_arrays([1], [1], [0.0], [0.0])         # a different frame
    e = position_errors(gt, pr)
    assert e.num_pairs == 0 and np.isnan(e.mean_m) and np.isnan(e.mean_abs_dx_m)


def test_target_precision_recall_counts_a_b_c():
    nan = np.nan
    target = np.array([[0, 0], [0, 0], [0, 0], [0, 0], [nan, nan], [nan, nan], [1, 1]], float)
    reported = np.array([[0.1, 0], [0, 0.2], [2, 2], [nan, nan], [5, 5], [nan, nan], [1, 1.4]])
    # frame: 0 A, 1 A, 2 B (someone 2.8 m away), 3 C (present, nothing), 4 B (target absent,
    # something reported), 5 nothing at all (not counted), 6 A (0.4 m <= 0.5 m gate)
    assert target_frame_counts(target, reported, gate=0.5) == (3, 2, 1)
    p, r = target_precision_recall(target, reported, gate=0.5)
    assert p == pytest.approx(3 / 5) and r == pytest.approx(3 / 4)   # A/(A+B), A/(A+C)
    # A tighter gate turns frame 6 into B: A = 2, B = 3, C = 1.
    assert target_precision_recall(target, reported, gate=0.3) == pytest.approx((2 / 5, 2 / 3))
    p, r = target_precision_recall([[nan, nan]], [[nan, nan]])
    assert np.isnan(p) and np.isnan(r)


def test_track_positions_fill_nan_where_absent():
    t = TrackTable.from_arrays([3, 1, 1], [4, 4, 5], [3.0, 1.0, 9.0], [0.3, 0.1, 9.0])
    xy = track_positions(t, 4, [0, 1, 2, 3, 4])
    assert np.isnan(xy[[0, 2, 4]]).all()
    assert xy[1].tolist() == [1.0, 0.1] and xy[3].tolist() == [3.0, 0.3]
    assert np.isnan(track_positions(t, 99, [1])).all()


def test_rotation_errors_match_known_angles():
    R_true = np.stack([np.eye(3), rot_z(np.radians(10)), euler_zyx(0.3, -0.2, 0.1)])
    R_est = np.stack([rot_x(np.radians(2.5)), np.eye(3), euler_zyx(0.3, -0.2, 0.1)])
    err = rotation_errors_deg(R_true, R_est)
    assert err.shape == (3,)
    assert err == pytest.approx([2.5, 10.0, 0.0], abs=1e-6)
    with pytest.raises(ValueError):
        rotation_errors_deg(np.eye(3)[None], np.eye(3)[None, :2])


def test_limb_angle_errors_degrees_including_small_angles():
    small = 1e-7  # radians; arccos of the cosine would lose this completely
    a = np.array([[1, 0, 0], [0, 0, 2], [1, 0, 0], [1, 0, 0], [0, 0, 0]], float)
    b = np.array([[0, 1, 0], [0, 0, 5], [-3, 0, 0], [1, small, 0], [1, 0, 0]], float)
    deg = limb_angle_errors_deg(a, b)
    assert deg[:3] == pytest.approx([90.0, 0.0, 180.0])
    assert deg[3] == pytest.approx(np.degrees(small), rel=1e-6)
    assert np.isnan(deg[4])


def test_trajectory_rmse_split_inside_and_outside_views():
    true = np.zeros((5, 3))
    est = np.array([[0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.3], [0.4, 0, 0], [0, 0.3, 0]])
    seen = np.array([True, True, False, False, False])
    s = trajectory_rmse_split(true, est, seen)
    assert s.observed_m == pytest.approx(0.1)                               # sqrt((.01+.01)/2)
    assert s.unobserved_m == pytest.approx(np.sqrt((0.09 + 0.16 + 0.09) / 3))
    assert (s.num_observed, s.num_unobserved) == (2, 3)
    assert np.isnan(trajectory_rmse_split(true, est, np.ones(5, bool)).unobserved_m)
