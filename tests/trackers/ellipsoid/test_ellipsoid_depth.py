"""Depth along one camera's line of sight from every cue, weighed by σ (``ellipsoid.depth``)."""

import numpy as np
import pytest
from _line_of_sight import line_of_sight_frame, misplaced

from worldtrack.trackers.ellipsoid.config import DepthConfig, FeetConfig, HeightConfig
from worldtrack.trackers.ellipsoid.depth import DepthFusion, fuse_along
from worldtrack.trackers.ellipsoid.height_sigma import height_estimate, height_sigma, median_sigma
from worldtrack.trackers.people import Person


@pytest.fixture(scope="module")
def seen():
    return line_of_sight_frame()


def _legs_unsure(labels, instance, truth, shoes_px=0):
    """The labels with the person's lower half turned shadow-like (legs the floor's colour), but
    for the lowest ``shoes_px`` rows (the shoes)."""
    body = instance == truth["id"]
    rows = np.nonzero(body.any(axis=1))[0]
    v = np.arange(labels.shape[0])[:, None]
    legs = body & (v > (rows.min() + rows.max()) / 2) & (v <= rows.max() - shoes_px)
    cut = labels.copy()
    cut[legs & (cut == 1)] = 2
    return cut


def _fusion(**depth):
    return DepthFusion(DepthConfig(fuse=True, **depth), FeetConfig(), HeightConfig())


def test_the_feet_of_a_whole_silhouette_pull_a_track_back_and_nothing_moves_with_fusion_off(seen):
    tracker, labels, _, truth = seen
    p, xy = misplaced(tracker, truth, 0.6)
    assert _fusion().apply([p], tracker.views, {"cam": labels}, tracker.walkable, 0.1) == 1
    # Feet σ 0.1 m against the clear ellipse's 0.3 m: 90 % of the 0.6 m back.
    assert np.hypot(p.x - xy[0], p.y - xy[1]) < 0.15
    q, _ = misplaced(tracker, truth, 0.6)
    off = DepthFusion(DepthConfig(), FeetConfig(), HeightConfig())
    off.remember_prediction([q])
    assert off.apply([q], tracker.views, {"cam": labels}, tracker.walkable, 0.1) == 0
    assert np.hypot(q.x - xy[0], q.y - xy[1]) > 0.59


@pytest.mark.parametrize("shoes_px", [0, 3])
def test_where_the_legs_are_not_foreground_the_prediction_carries_the_depth(seen, shoes_px):
    tracker, labels, instance, truth = seen
    # The silhouette ends at the waist, or at shoes below unsure trousers: the feet are not trusted.
    cut = _legs_unsure(labels, instance, truth, shoes_px)
    # The prediction said the truth; the match put the person 0.6 m beyond it.
    p, xy = misplaced(tracker, truth, 0.0)
    fusion = _fusion()
    fusion.remember_prediction([p])
    start = xy + 0.6 * (xy - tracker.scene.cameras["cam"].centre[:2]) / np.hypot(
        *(xy - tracker.scene.cameras["cam"].centre[:2]))
    p.x, p.y = float(start[0]), float(start[1])
    fusion.apply([p], tracker.views, {"cam": cut}, tracker.walkable, 0.1)
    # Legs unsure: the feet are not used and the ellipse is weak (σ 0.6 m); the prediction (σ 0.15 m)
    # and the head (height unmeasured: σ ~0.6 m) bring it nearly all the way back.
    assert np.hypot(p.x - xy[0], p.y - xy[1]) < 0.1
    # Without the prediction, the head alone against the weak ellipse: part of the way.
    q, _ = misplaced(tracker, truth, 0.6)
    _fusion().apply([q], tracker.views, {"cam": cut}, tracker.walkable, 0.1)
    assert 0.1 < np.hypot(q.x - xy[0], q.y - xy[1]) < 0.45
    # Once the height is measured (σ 3 cm, ~0.2 m along the ray here), the head counts for more.
    r, _ = misplaced(tracker, truth, 0.6)
    r.height_samples.extend([truth["height"]] * 3)
    _fusion().apply([r], tracker.views, {"cam": cut}, tracker.walkable, 0.1)
    assert np.hypot(r.x - xy[0], r.y - xy[1]) < np.hypot(q.x - xy[0], q.y - xy[1]) - 0.1


def test_the_prediction_weighs_less_the_longer_the_feet_are_not_seen(seen):
    tracker, labels, instance, truth = seen
    cut = _legs_unsure(labels, instance, truth)
    p, xy = misplaced(tracker, truth, 0.0)
    cam = tracker.scene.cameras["cam"]
    beyond = xy + 0.6 * (xy - cam.centre[:2]) / np.hypot(*(xy - cam.centre[:2]))
    fusion = _fusion()
    left = []
    for _ in range(9):      # each frame: predicted at the truth, matched 0.6 m beyond it
        p.x, p.y = float(xy[0]), float(xy[1])
        fusion.remember_prediction([p])
        p.x, p.y = float(beyond[0]), float(beyond[1])
        fusion.apply([p], tracker.views, {"cam": cut}, tracker.walkable, 0.1)
        left.append(np.hypot(p.x - xy[0], p.y - xy[1]))
    # σ of the prediction 0.15 m, then 0.15 · √10 m after 9 frames without the feet: the other cues
    # (the weak ellipse, the head) get a say.
    assert left[0] < 0.1 and left[-1] > left[0] + 0.1


def test_a_person_covered_by_others_has_the_height_measured_afresh_once_clear():
    p = Person(1, 0.0, 0.0, height=1.9, height_samples=[1.9] * 10, height_tries=12)
    keep = _fusion()
    keep.note_encounter(p, True)
    keep.note_encounter(p, False)
    assert len(p.height_samples) == 10        # option off: carried through
    again = _fusion(remeasure_after_encounter=True)
    again.note_encounter(p, False)
    assert len(p.height_samples) == 10        # never covered: kept
    again.note_encounter(p, True)
    assert len(p.height_samples) == 10        # still covered: kept until clear
    again.note_encounter(p, False)
    assert p.height_samples == [] and p.height_tries == 0
    again.note_encounter(p, False)            # once only


def test_the_height_has_its_own_uncertainty_and_replaces_the_default_beyond_it():
    samples = [1.70, 1.72, 1.74, 1.76, 1.78, 1.72, 1.74, 1.76, 1.73]
    # median 1.74, MAD 0.02 m: σ of the median 1.2533 · 1.4826 · 0.02 / 3 ≈ 1.2 cm.
    assert median_sigma(samples) == pytest.approx(1.2533 * 1.4826 * 0.02 / 3)
    assert height_estimate(samples, 1.70, HeightConfig()) == 1.70     # within the fixed 5 cm deadband
    # With the default as a prior (σ 0.1 m): nearly all the way to the median (1.74).
    w = 0.01 / (0.01 + median_sigma(samples) ** 2)
    assert height_estimate(samples, 1.70, HeightConfig(prior_sigma_m=0.1)) == pytest.approx(1.70 + w * 0.04)
    assert 1.735 < 1.70 + w * 0.04 < 1.74
    tight = [1.73] * 9
    assert median_sigma(tight) == 0.005                                 # at least 5 mm
    scattered = [1.60, 1.73, 1.86]                                      # three far apart: the prior counts more
    assert 1.70 < height_estimate(scattered, 1.70, HeightConfig(prior_sigma_m=0.1)) < 1.72
    assert height_sigma(Person(1, 0.0, 0.0, height_samples=tight), 0.1) == 0.01         # here at least 1 cm
    assert height_sigma(Person(2, 0.0, 0.0, height_samples=[1.7, 1.8]), 0.1) == 0.1     # unmeasured
    assert fuse_along([(0.0, 0.3), (0.6, 0.1)]) == pytest.approx(0.54)
    assert fuse_along([]) == 0.0
