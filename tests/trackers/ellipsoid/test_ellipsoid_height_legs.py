"""A height is measured in one view only where the feet are evidenced (``height.legs_min_share``)."""

import numpy as np
import pytest
from _line_of_sight import line_of_sight_frame, misplaced

from worldtrack.trackers.ellipsoid.config import HeightConfig
from worldtrack.trackers.ellipsoid.height import update_heights


@pytest.fixture(scope="module")
def seen():
    return line_of_sight_frame()


def _legs_unsure(labels, instance, truth):
    """The labels with the lowest fifth of the person shadow-like (shins and shoes the floor's
    colour): the foreground ends at mid-shin."""
    body = instance == truth["id"]
    rows = np.nonzero(body.any(axis=1))[0]
    v = np.arange(labels.shape[0])[:, None]
    cut = labels.copy()
    cut[body & (v > rows.min() + 0.8 * (rows.max() - rows.min())) & (cut == 1)] = 2
    return cut


def _measured(tracker, truth, labels, legs_min_share):
    p, _ = misplaced(tracker, truth, 0.0)
    update_heights([p], [0], tracker.views, {"cam": labels}, lambda _: 1.7,
                   HeightConfig(legs_min_share=legs_min_share))
    return list(p.height_samples)


def test_no_height_from_a_silhouette_cut_above_the_feet_with_the_test(seen):
    tracker, labels, instance, truth = seen
    # Whole silhouette: measured within 5 cm of the truth, with or without the test.
    for share in (0.0, 0.5):
        whole = _measured(tracker, truth, labels, share)
        assert len(whole) == 1 and abs(whole[0] - truth["height"]) < 0.05
    cut = _legs_unsure(labels, instance, truth)
    # Cut at mid-shin, without the test: the shin is taken for the feet, 15 cm short but plausible;
    # with the test, no sample at all.
    wrong = _measured(tracker, truth, cut, 0.0)
    assert len(wrong) == 1 and 0.1 < truth["height"] - wrong[0] < 0.25
    assert _measured(tracker, truth, cut, 0.5) == []


def test_the_share_must_be_a_fraction():
    with pytest.raises(Exception, match="legs_min_share"):
        HeightConfig(legs_min_share=1.5)
