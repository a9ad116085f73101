"""HOTA on the floor (TrackEval's metric, similarity 1 − d / gate): perfect tracks, hand arithmetic,
an identity swap that costs association but not detection, and MOTA/IDF1 left as they were."""

import sys

import numpy as np
import pytest

from worldtrack.eval import evaluate, evaluate_hota
from worldtrack.eval.hota import sequence_data
from worldtrack.io.tracks import TrackTable


def walking_pair(n_frames: int = 20) -> TrackTable:
    """Two people 3 m apart walking along +X at 1 m/s, 10 fps; ids 1 and 2."""
    f = np.repeat(np.arange(n_frames), 2)
    ids = np.tile([1, 2], n_frames)
    return TrackTable.from_arrays(f, ids, f * 0.1, np.where(ids == 1, 0.0, 3.0), time=f * 0.1)


def test_perfect_tracks_score_one_whatever_their_ids():
    gt = walking_pair()
    pred = TrackTable.from_arrays(gt.frame, gt.id + 100, gt.x, gt.y)     # other numbers, same people
    h = evaluate_hota(gt, pred, gate=0.5)
    assert h.hota == pytest.approx(1.0) and h.deta == pytest.approx(1.0)
    assert h.assa == pytest.approx(1.0) and h.loca == pytest.approx(1.0)


def test_small_case_matches_hand_arithmetic():
    # One person at (0, 0) in frame 0 and (1, 0) in frame 1. Track 1 is 0.42 m off in frame 0
    # (similarity 1 − 0.42 = 0.58 at a 1 m gate) and exact in frame 1; track 2 is a false
    # positive far away in frame 1.
    gt = TrackTable.from_arrays([0, 1], [1, 1], [0.0, 1.0], [0.0, 0.0])
    pred = TrackTable.from_arrays([0, 1, 1], [1, 1, 2], [0.42, 1.0, 5.0], [0.0, 0.0, 5.0])
    h = evaluate_hota(gt, pred, gate=1.0)
    # α ≤ 0.55 (11 of the 19 thresholds): TP 2, FN 0, FP 1 → DetA 2/3; the one pair of ids
    # matched in both of its 2 + 2 rows → AssA 1.
    # α ≥ 0.60 (8 thresholds): only frame 1 matches: TP 1, FN 1, FP 2 → DetA 1/4;
    # AssA = 1 / (2 + 2 − 1) = 1/3.
    expected = (11 * np.sqrt(2 / 3 * 1) + 8 * np.sqrt(1 / 4 * 1 / 3)) / 19
    assert h.hota == pytest.approx(expected, abs=1e-12)
    assert h.deta == pytest.approx((11 * 2 / 3 + 8 / 4) / 19, abs=1e-12)
    assert h.assa == pytest.approx((11 * 1 + 8 / 3) / 19, abs=1e-12)
    # LocA: mean similarity of the matched pairs, (0.58 + 1) / 2 below α = 0.6, 1 above.
    assert h.loca == pytest.approx((11 * 0.79 + 8 * 1.0) / 19, abs=1e-12)


def test_id_swap_lowers_association_not_detection():
    gt = walking_pair(20)
    # 2 cm off: similarity 0.96, a match at all 19 thresholds (up to 0.95).
    same = TrackTable.from_arrays(gt.frame, gt.id, gt.x + 0.02, gt.y)
    swapped = TrackTable.from_arrays(gt.frame, np.where(gt.frame >= 10, 3 - gt.id, gt.id), gt.x + 0.02, gt.y)
    a, b = evaluate_hota(gt, same, gate=0.5), evaluate_hota(gt, swapped, gate=0.5)
    assert b.deta == pytest.approx(a.deta) and b.loca == pytest.approx(a.loca)
    assert a.assa == pytest.approx(1.0)
    # Each person is half with one track, half with the other: AssA = 10 / (20 + 20 − 10) = 1/3.
    assert b.assa == pytest.approx(1 / 3)
    assert b.hota == pytest.approx(np.sqrt(a.deta / 3))


def test_evaluate_reports_hota_beside_unchanged_mota_and_idf1():
    gt = walking_pair(20)
    swapped = TrackTable.from_arrays(gt.frame, np.where(gt.frame >= 10, 3 - gt.id, gt.id), gt.x, gt.y)
    m = evaluate(gt, swapped, gate=0.5)
    assert m["mota"] == pytest.approx(0.95) and m["idf1"] == pytest.approx(0.5)   # as in test_mot.py
    assert m["hota_deta"] == pytest.approx(1.0) and m["hota_assa"] == pytest.approx(1 / 3)
    assert m["hota"] == pytest.approx(np.sqrt(1 / 3))


def test_similarity_is_one_minus_distance_over_gate_and_zero_beyond():
    gt = TrackTable.from_arrays([0, 0], [5, 9], [0.0, 4.0], [0.0, 0.0])
    pred = TrackTable.from_arrays([0, 0], [7, 8], [0.3, 0.0], [0.4, 0.0])
    data = sequence_data(gt, pred, np.array([0]), gate=1.0)
    np.testing.assert_allclose(data["similarity_scores"][0], [[0.5, 1.0], [0.0, 0.0]])
    assert [ids.tolist() for ids in data["gt_ids"]] == [[0, 1]]           # TrackEval's dense ids
    assert data["num_gt_dets"] == 2 and data["num_tracker_ids"] == 2


def test_without_trackeval_hota_is_none_and_the_table_says_how_to_install_it(monkeypatch):
    hota_module = sys.modules["worldtrack.eval.hota"]
    from worldtrack.cli.eval import format_table

    monkeypatch.setattr(hota_module, "_hota_metric", lambda: None)
    gt = walking_pair(5)
    m = evaluate(gt, gt, gate=0.5)
    assert m["hota"] is None and m["hota_assa"] is None and m["mota"] == 1.0
    m.update(mean_error_m=0.0, mean_abs_dx_m=0.0, mean_abs_dy_m=0.0)
    assert "pip install --no-deps trackeval==1.3.0" in format_table(m)


def test_evaluate_passes_hota_the_same_numbers_it_would_compute_itself():
    # evaluate() hands HOTA its gated distance matrices (NaN beyond the gate); the result must
    # equal evaluate_hota() computing them afresh, to the last bit, with noise and far pairs.
    rng = np.random.default_rng(5)
    gt = walking_pair(40)
    keep = rng.random(len(gt)) > 0.1
    pred = TrackTable.from_arrays(gt.frame[keep], gt.id[keep] + 10,
                                  gt.x[keep] + rng.normal(0, 0.3, keep.sum()), gt.y[keep])
    h = evaluate_hota(gt, pred, gate=0.5, frames=np.unique(gt.frame))
    m = evaluate(gt, pred, gate=0.5)
    assert (m["hota"], m["hota_deta"], m["hota_assa"], m["hota_loca"]) == (h.hota, h.deta, h.assa, h.loca)
    assert 0.0 < h.hota < 1.0
