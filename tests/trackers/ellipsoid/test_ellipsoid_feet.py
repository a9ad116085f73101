"""Depth from the feet (and the head's top where the feet are not to be trusted) along the line of sight."""

import numpy as np
import pytest
from _line_of_sight import line_of_sight_frame, misplaced

from worldtrack.trackers.ellipsoid.config import FeetConfig, HeightConfig
from worldtrack.trackers.ellipsoid.feet import anchor_to_feet, feet_weight


@pytest.fixture(scope="module")
def seen():
    return line_of_sight_frame()


def test_the_feet_pull_a_track_that_sits_too_far_along_the_line_of_sight_back_to_the_person(seen):
    tracker, labels, instance, truth = seen
    p, xy = misplaced(tracker, truth, 0.6)
    moved = anchor_to_feet([p], tracker.views, {"cam": labels}, tracker.walkable, FeetConfig(anchor=True), HeightConfig())
    assert moved == 1
    # 0.6 m off before; the feet are 0.1 m uncertain, the ellipse 0.3 m: 90 % of the way back.
    assert np.hypot(p.x - xy[0], p.y - xy[1]) < 0.2
    q, _ = misplaced(tracker, truth, 0.6)
    assert anchor_to_feet([q], tracker.views, {"cam": labels}, tracker.walkable, FeetConfig(anchor=False),
                          HeightConfig()) == 0
    r, _ = misplaced(tracker, truth, 0.0)   # in the right place: stays there
    anchor_to_feet([r], tracker.views, {"cam": labels}, tracker.walkable, FeetConfig(anchor=True), HeightConfig())
    assert np.hypot(r.x - xy[0], r.y - xy[1]) < 0.15


def _legs_as_shadow(labels, instance, truth):
    """``labels`` with legs the floor's colour: the person's foreground pixels below the body's
    middle read as shadow-like ("unsure", 2)."""
    body = instance == truth["id"]
    rows = np.nonzero(body.any(axis=1))[0]
    legs = body & (np.arange(labels.shape[0])[:, None] > (rows.min() + rows.max()) / 2)
    cut = labels.copy()
    cut[legs & (cut == 1)] = 2
    return cut


def test_without_legs_in_the_foreground_the_head_places_the_person_not_the_waist(seen):
    tracker, labels, instance, truth = seen
    cut = _legs_as_shadow(labels, instance, truth)
    p, xy = misplaced(tracker, truth, 0.6)
    moved = anchor_to_feet([p], tracker.views, {"cam": cut}, tracker.walkable, FeetConfig(anchor=True), HeightConfig())
    assert moved == 1
    # The head at an unmeasured height (σ 0.1 m, ~0.6 m along the ray at this distance) is weak
    # evidence: a small step back (the waist, taken for the feet, would have pulled it farther).
    assert 0.3 < np.hypot(p.x - xy[0], p.y - xy[1]) < 0.57
    # Once the height is measured (σ 0.03 m) the head pins the depth nearly as well as the feet.
    q, _ = misplaced(tracker, truth, 0.6)
    q.height_samples.extend([truth["height"]] * 3)
    anchor_to_feet([q], tracker.views, {"cam": cut}, tracker.walkable, FeetConfig(anchor=True), HeightConfig())
    assert np.hypot(q.x - xy[0], q.y - xy[1]) < 0.3
    assert feet_weight(0.3, 0.1) > 0.85


def test_without_the_head_fallback_only_trusted_feet_move_a_person(seen):
    tracker, labels, instance, truth = seen
    cut = _legs_as_shadow(labels, instance, truth)
    config = FeetConfig(anchor=True, head_fallback=False)
    q, xy = misplaced(tracker, truth, 0.6)
    q.height_samples.extend([truth["height"]] * 3)
    # Legs not foreground: the feet are not trusted, and the head is not asked; the person stays put.
    assert anchor_to_feet([q], tracker.views, {"cam": cut}, tracker.walkable, config, HeightConfig()) == 0
    assert np.hypot(q.x - xy[0], q.y - xy[1]) == pytest.approx(0.6, abs=1e-9)
    # Whole legs: the feet still pull the person back.
    p, _ = misplaced(tracker, truth, 0.6)
    assert anchor_to_feet([p], tracker.views, {"cam": labels}, tracker.walkable, config, HeightConfig()) == 1
    assert np.hypot(p.x - xy[0], p.y - xy[1]) < 0.2
