"""MOT metrics on the floor: parity with motmetrics, hand arithmetic, gate in metres, area, frames."""

from pathlib import Path

import motmetrics as mm
import numpy as np
import pytest

from worldtrack.errors import InputError
from worldtrack.eval.mot import (accumulate, drop_ignored, evaluate, evaluate_detailed, evaluated_frames,
                                 floor_distances, summarize)
from worldtrack.io.tracks import TrackTable, read_tracks

DATA = Path(__file__).resolve().parent / "data"


def walking_pair(n_frames: int = 20) -> TrackTable:
    """Two people 3 m apart walking along +X at 1 m/s, 10 fps; ids 1 and 2."""
    f = np.repeat(np.arange(n_frames), 2)
    ids = np.tile([1, 2], n_frames)
    x = f * 0.1
    y = np.where(ids == 1, 0.0, 3.0)
    return TrackTable.from_arrays(f, ids, x, y, time=f * 0.1, source="walking")


def test_ground_truth_against_itself_is_perfect():
    gt = read_tracks(DATA / "gt_small.csv")
    m = evaluate(gt, gt)
    assert m["mota"] == 1.0 and m["motp_m"] == 0.0 and m["idf1"] == 1.0
    assert m["num_switches"] == 0 and m["num_false_positives"] == 0 and m["num_misses"] == 0
    assert m["num_objects"] == 10 and m["num_frames"] == 5 and m["mostly_tracked"] == 2
    assert m["hota"] == pytest.approx(1.0) and m["hota_deta"] == pytest.approx(1.0)


def test_two_ids_swapped_from_mid_way_give_exactly_two_switches():
    gt = walking_pair(20)
    swapped_id = np.where(gt.frame >= 10, 3 - gt.id, gt.id)      # 1 <-> 2 from frame 10 on
    pred = TrackTable.from_arrays(gt.frame, swapped_id, gt.x, gt.y)
    m = evaluate(gt, pred)
    # CLEAR-MOT counts a switch per ground-truth object whose matched hypothesis changes: at
    # frame 10 person 1 goes from hypothesis 1 to 2 and person 2 from 2 to 1 -> 2 switches.
    assert m["num_switches"] == 2
    # MOTA = 1 - (FN + FP + IDSW) / GT = 1 - (0 + 0 + 2) / 40 = 0.95
    assert m["mota"] == pytest.approx(0.95)
    # IDF1: the best one-to-one id pairing keeps half of each track: IDTP = 10 + 10 = 20,
    # IDFP = IDFN = 40 - 20 = 20 -> IDF1 = 2·20 / (2·20 + 20 + 20) = 0.5
    assert m["idf1"] == pytest.approx(0.5)
    assert m["motp_m"] == 0.0 and m["num_fragmentations"] == 0


def test_hand_made_fixture_matches_hand_arithmetic_and_motmetrics_directly():
    # tests/eval/data: GT 1 stands at (0, 0), GT 2 at (5, 0), frames 0-4 (10 GT rows).
    # Predictions: 11 at (0.3, 0) in all frames (0.3 m from GT 1); 12 at (5, 0.4) in frames
    # 0-1 (0.4 m from GT 2); nothing near GT 2 in frame 2; 13 at (5, 0.1) in frames 3-4;
    # 14 at (10, 10) in frame 4 (false positive). 10 predicted rows.
    gt = read_tracks(DATA / "gt_small.csv")
    pred = read_tracks(DATA / "pred_small.csv")
    m = evaluate(gt, pred, gate=0.5)

    # Hand arithmetic.
    # matches = 5 (GT 1) + 4 (GT 2, frames 0, 1, 3, 4) = 9; misses = 1 (GT 2, frame 2);
    # FP = 1 (14); switches = 1 (GT 2: 12 -> 13 at frame 3); fragmentations = 1 (GT 2 lost
    # at frame 2 and found again).
    # MOTA = 1 - (1 + 1 + 1) / 10 = 0.7
    # MOTP = (5·0.3 + 2·0.4 + 2·0.1) / 9 = 2.5 / 9 m
    # IDF1: pair 1<->11 (5 frames) and 2<->12 or 2<->13 (2 frames): IDTP = 7,
    # IDFN = 10 - 7 = 3, IDFP = 10 - 7 = 3 -> IDF1 = 14 / 20 = 0.7, IDP = IDR = 0.7
    # precision = 9 / (9 + 1) = 0.9, recall = 9 / 10 = 0.9; GT 2 tracked 4/5 = 80 % -> MT = 2
    hand = dict(mota=0.7, motp_m=2.5 / 9, idf1=0.7, idp=0.7, idr=0.7, precision=0.9, recall=0.9,
                num_switches=1, num_fragmentations=1, num_false_positives=1, num_misses=1,
                num_matches=9, num_objects=10, num_predictions=10, num_frames=5,
                mostly_tracked=2, partially_tracked=0, mostly_lost=0)
    for k, v in hand.items():
        assert m[k] == pytest.approx(v, abs=1e-12), k

    # motmetrics' own API on distances computed independently of our code.
    acc = mm.MOTAccumulator(auto_id=False)
    for f in range(5):
        g, p = gt.select(gt.frame == f), pred.select(pred.frame == f)
        d = np.hypot(g.x[:, None] - p.x[None, :], g.y[:, None] - p.y[None, :])
        acc.update(g.id, p.id, np.where(d <= 0.5, d, np.nan), frameid=f)
    ref = mm.metrics.create().compute(
        acc, metrics=["mota", "motp", "idf1", "num_switches", "num_fragmentations"],
        return_dataframe=False)
    assert m["mota"] == pytest.approx(ref["mota"])
    assert m["motp_m"] == pytest.approx(ref["motp"])
    assert m["idf1"] == pytest.approx(ref["idf1"])
    assert m["num_switches"] == ref["num_switches"] == 1
    assert m["num_fragmentations"] == ref["num_fragmentations"]


def test_gate_is_in_metres_not_squared_metres():
    gt = TrackTable.from_arrays([0, 1], [1, 1], [0.0, 0.0], [0.0, 0.0])
    pred = TrackTable.from_arrays([0, 1], [1, 1], [0.4, 0.4], [0.0, 0.0])   # 0.4 m off
    inside = evaluate(gt, pred, gate=0.5)
    assert inside["num_matches"] == 2 and inside["num_misses"] == 0
    assert inside["motp_m"] == pytest.approx(0.4)            # metres, not 0.16 m²
    outside = evaluate(gt, pred, gate=0.3)                   # 0.4² = 0.16 < 0.3 would match
    assert outside["num_matches"] == 0
    assert outside["num_misses"] == 2 and outside["num_false_positives"] == 2
    assert np.isnan(outside["motp_m"])
    d = floor_distances([[0, 0]], [[0.3, 0.4], [0.6, 0.8]], gate=0.5)
    assert d[0, 0] == pytest.approx(0.5) and np.isnan(d[0, 1])


def test_area_drops_ground_truth_and_predictions_outside():
    # Two people; only the one at x = 1 is inside the 2 m square. A false positive outside.
    gt = TrackTable.from_arrays([0, 0, 1, 1], [1, 2, 1, 2], [1.0, 5.0, 1.0, 5.0], [1.0] * 4)
    pred = TrackTable.from_arrays([0, 1, 1], [7, 7, 8], [1.1, 1.1, 8.0], [1.0, 1.0, 8.0])
    square = [[0, 0], [2, 0], [2, 2], [0, 2]]
    everywhere = evaluate(gt, pred)
    assert everywhere["num_objects"] == 4 and everywhere["num_misses"] == 2
    assert everywhere["num_false_positives"] == 1
    inside = evaluate(gt, pred, area=square)
    assert inside["num_objects"] == 2 and inside["num_predictions"] == 2
    assert inside["num_misses"] == 0 and inside["num_false_positives"] == 0
    assert inside["mota"] == 1.0 and inside["num_frames"] == 2
    res = evaluate_detailed(gt, pred, area=square)
    assert res.gt.id.tolist() == [1, 1] and res.pred.id.tolist() == [7, 7]
    with pytest.raises(InputError, match="area"):
        evaluate(gt, pred, area=[[0, 0], [1, 1]])


def test_frames_policy_false_positives_inside_gt_range_only():
    # GT on frames 0 and 3 (nobody on 1-2), predictions on 1 (inside the range) and 9 (after).
    gt = TrackTable.from_arrays([0, 3], [1, 1], [0.0, 0.0], [0.0, 0.0])
    pred = TrackTable.from_arrays([0, 1, 9], [1, 1, 1], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    assert evaluated_frames(gt, pred).tolist() == [0, 1, 3]
    res = evaluate_detailed(gt, pred)
    m = res.metrics
    assert m["num_frames"] == 3
    assert m["num_false_positives"] == 1            # frame 1; frame 9 is ignored
    assert m["num_misses"] == 1                     # frame 3: GT, no prediction
    assert m["num_predictions"] == 2
    pf = res.per_frame
    assert pf["frame"].tolist() == [0, 1, 3]
    assert pf["num_gt"].tolist() == [1, 0, 1] and pf["num_pred"].tolist() == [1, 1, 0]
    assert pf["matches"].tolist() == [1, 0, 0] and pf["false_positives"].tolist() == [0, 1, 0]
    assert pf["misses"].tolist() == [0, 0, 1]
    assert pf["mean_error_m"][0] == 0.0 and np.isnan(pf["mean_error_m"][1])


def test_per_frame_switches_and_pairs_agree_with_totals():
    gt = walking_pair(20)
    pred = TrackTable.from_arrays(gt.frame, np.where(gt.frame >= 10, 3 - gt.id, gt.id),
                                  gt.x + 0.1, gt.y)
    res = evaluate_detailed(gt, pred)
    assert res.per_frame["switches"].tolist() == [0] * 10 + [2] + [0] * 9
    assert res.pairs["frame"].size == res.metrics["num_matches"] == 40
    assert res.pairs["switch"].sum() == 2
    assert np.allclose(res.pairs["distance"], 0.1)
    assert np.allclose(res.per_frame["mean_error_m"], 0.1)


def test_bad_gate_and_empty_ground_truth_are_input_errors():
    gt = walking_pair(3)
    with pytest.raises(InputError, match="gate"):
        evaluate(gt, gt, gate=0.0)
    empty = TrackTable.from_arrays([], [], [], [], source="gt.csv")
    with pytest.raises(InputError, match="gt.csv: no rows"):
        evaluate(empty, gt)


# --- motmetrics' own published numbers ---------------------------------------------------------

def _iou_distance(a: np.ndarray, b: np.ndarray, max_d: float = 0.5) -> np.ndarray:
    """1 − IoU of (x, y, w, h) boxes, NaN above ``max_d``: motmetrics' ``iou_matrix``, which
    1.4.0 cannot run under NumPy 2 (it calls the removed ``np.asfarray``)."""
    a0, a1 = a[:, None, :2], a[:, None, :2] + a[:, None, 2:]
    b0, b1 = b[None, :, :2], b[None, :, :2] + b[None, :, 2:]
    inter = np.prod(np.clip(np.minimum(a1, b1) - np.maximum(a0, b0), 0, None), axis=-1)
    union = np.prod(a[:, None, 2:], axis=-1) + np.prod(b[None, :, 2:], axis=-1) - inter
    d = 1.0 - np.where(inter > 0, inter / union, 0.0)
    return np.where(d > max_d, np.nan, d)


def _tud_frames(folder: Path):
    gt = np.loadtxt(folder / "gt.txt", delimiter=",", ndmin=2)
    dt = np.loadtxt(folder / "test.txt", delimiter=",", ndmin=2)
    for f in np.union1d(gt[:, 0], dt[:, 0]):           # as motmetrics.utils.compare_to_groundtruth
        g, d = gt[gt[:, 0] == f], dt[dt[:, 0] == f]
        dist = _iou_distance(g[:, 2:6], d[:, 2:6]) if len(g) and len(d) else np.empty((len(g), len(d)))
        yield int(f), g[:, 1].astype(int), d[:, 1].astype(int), dist


# Expected values from motmetrics 1.4.0 tests/test_metrics.py::test_motchallenge_files.
TUD_EXPECTED = {
    "TUD-Campus": dict(idf1=0.557659, idp=0.729730, idr=0.451253, recall=0.582173,
                       precision=0.941441, num_unique_objects=8, mostly_tracked=1,
                       partially_tracked=6, mostly_lost=1, num_false_positives=13,
                       num_misses=150, num_switches=7, num_fragmentations=7, mota=0.526462,
                       motp=0.277201),
    "TUD-Stadtmitte": dict(idf1=0.644619, idp=0.819760, idr=0.531142, recall=0.608997,
                           precision=0.939920, num_unique_objects=10, mostly_tracked=5,
                           partially_tracked=4, mostly_lost=1, num_false_positives=45,
                           num_misses=452, num_switches=7, num_fragmentations=6, mota=0.564014,
                           motp=0.345904),
}


@pytest.mark.parametrize("name", sorted(TUD_EXPECTED))
def test_accumulator_path_reproduces_motmetrics_published_tud_numbers(name):
    # Image boxes and IoU distance here, so this checks the accumulate -> summarize path that
    # evaluate() uses (and motmetrics under our NumPy/pandas), not our Euclidean matrix.
    folder = Path(mm.__file__).parent / "data" / name
    if not folder.exists():
        pytest.skip("motmetrics wheel without its TUD test data")
    got = summarize(accumulate(_tud_frames(folder)))
    for k, v in TUD_EXPECTED[name].items():
        assert got[k] == pytest.approx(v, abs=1e-3), k


def test_drop_ignored_removes_ignored_people_and_the_predictions_that_found_them():
    # Frame 0: person 1 (ignored) and person 2 (scored), a prediction near each.
    # Frame 1: the ignored person has no prediction; person 2's and a far false positive stay.
    # Frame 2: one prediction between them, nearer the scored person: it matches person 2 and stays.
    gt = TrackTable.from_arrays([0, 0, 1, 1, 2, 2], [1, 2, 1, 2, 1, 2],
                                [0.0, 3.0, 0.1, 3.1, 0.2, 0.6], [0.0] * 6)
    ignore = gt.id == 1
    pred = TrackTable.from_arrays([0, 0, 1, 1, 2], [10, 20, 20, 30, 20],
                                  [0.1, 3.1, 3.2, 6.0, 0.45], [0.0] * 5)
    gt_kept, pred_kept = drop_ignored(gt, pred, ignore, gate=0.5)
    assert list(zip(gt_kept.frame.tolist(), gt_kept.id.tolist())) == [(0, 2), (1, 2), (2, 2)]
    assert list(zip(pred_kept.frame.tolist(), pred_kept.id.tolist())) == [(0, 20), (1, 20), (1, 30), (2, 20)]
    np.testing.assert_allclose(pred_kept.x, [3.1, 3.2, 6.0, 0.45])
    with pytest.raises(ValueError, match="ignore"):
        drop_ignored(gt, pred, ignore[:-1])
