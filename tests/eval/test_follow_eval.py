"""Seed 001's frame labels (A, B, C), swaps, re-acquisition delays and candidate matching."""

import numpy as np

from worldtrack.eval.follow import (counts, counts_by, follow_labels, match_candidates, reacquisitions, runs,
                                    swaps)
from worldtrack.eval.tables import target_frame_counts

nan = np.nan


def test_labels_follow_the_paper_and_a_half_hidden_target_reported_is_right():
    target = np.zeros((6, 2))
    visible = np.array([True, True, True, False, False, True])
    reported = np.array([[0.1, 0], [2, 0], [nan, nan], [0.2, 0], [nan, nan], [0.45, 0]])
    others = [np.zeros((0, 2))] * 5 + [np.array([[0.5, 0.0]])]       # frame 5: someone nearer the report
    labels = follow_labels(target, visible, reported, others)
    assert labels.tolist() == ["A", "B", "C", "A", "N", "B"]
    c = counts(labels)
    assert (c.a, c.b, c.c) == (2, 2, 1) and c.precision == 0.5 and c.recall == 2 / 3
    by = counts_by(labels, np.array(list("xxxyyy")))
    assert by["x"].a == 1 and by["y"].b == 1


def test_labels_agree_with_table_3_counts_when_the_target_is_always_visible():
    rng = np.random.default_rng(0)
    target = rng.uniform(0, 5, (50, 2))
    reported = target + rng.normal(0, 0.4, (50, 2))
    reported[rng.random(50) < 0.2] = nan
    labels = follow_labels(target, np.ones(50, bool), reported, [np.zeros((0, 2))] * 50)
    a, b, c = target_frame_counts(target, reported, gate=0.5)
    assert (counts(labels).a, counts(labels).b, counts(labels).c) == (a, b, c)


def test_swaps_and_reacquisitions():
    times = np.arange(12) / 10
    labels = np.array(list("AABBBAANNCAA"))
    assert runs(labels == "B") == [(2, 5)]
    (start, duration), = swaps(labels, times)
    assert abs(start - 0.2) < 1e-9 and abs(duration - 0.3) < 1e-9
    assert swaps(labels, times, min_s=0.5) == []
    visible = np.array([1, 1, 1, 1, 1, 1, 1, 0, 0, 1, 1, 1], bool)
    occ = reacquisitions(labels, visible, np.ones(12, bool), times)
    assert len(occ) == 1 and occ[0].start == 7 and occ[0].stop == 9
    assert abs(occ[0].duration - 0.2) < 1e-9 and abs(occ[0].delay - 0.1) < 1e-9


def test_candidates_are_matched_one_to_one_within_the_gate():
    cands = np.array([[0.0, 0.0], [1.0, 0.0], [5.0, 5.0]])
    people = np.array([[0.9, 0.1], [0.1, 0.0], [3.0, 3.0]])
    assert match_candidates(cands, people).tolist() == [1, 0, -1]
