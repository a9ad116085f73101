"""The feet anchor on one camera: people behind a person do not hide them (``feet.behind_margin_m``)."""

import numpy as np
import pytest
from _line_of_sight import line_of_sight_frame, misplaced

from worldtrack.trackers.ellipsoid.behind import farther, in_front, overlaps_behind
from worldtrack.trackers.ellipsoid.config import FeetConfig, HeightConfig
from worldtrack.trackers.ellipsoid.feet import anchor_to_feet


@pytest.fixture(scope="module")
def seen():
    return line_of_sight_frame()


def _with_somebody_behind(tracker, truth, along_m, behind_m):
    """The seen person tracked ``along_m`` too far, and somebody tracked (with no pixels of their own)
    ``behind_m`` beyond the person on the same line of sight."""
    p, xy = misplaced(tracker, truth, along_m)
    other, _ = misplaced(tracker, truth, behind_m)
    other.height = truth["height"] + 0.1
    return p, other, xy


@pytest.mark.parametrize("along_m", [0.6, 0.9])
def test_a_person_in_front_of_somebody_is_anchored_to_their_feet(seen, along_m):
    tracker, labels, instance, truth = seen
    off = {}
    for margin in (0.0, 0.5):
        p, other, xy = _with_somebody_behind(tracker, truth, along_m, 1.6)
        anchor_to_feet([p, other], tracker.views, {"cam": labels}, tracker.walkable,
                       FeetConfig(anchor=True, behind_margin_m=margin), HeightConfig())
        off[margin] = float(np.hypot(p.x - xy[0], p.y - xy[1]))
    # The one behind covers most of the region drawn at the track: no cue without the option, the feet with it.
    assert off[0.0] > along_m - 0.05
    assert off[0.5] < 0.3


def test_somebody_in_front_still_hides_a_person(seen):
    tracker, labels, instance, truth = seen
    p, xy = misplaced(tracker, truth, 0.9)
    front, _ = misplaced(tracker, truth, 0.3)     # tracked between the camera and p's place
    anchor_to_feet([p, front], tracker.views, {"cam": labels}, tracker.walkable,
                   FeetConfig(anchor=True, behind_margin_m=0.5), HeightConfig())
    assert np.hypot(p.x - xy[0], p.y - xy[1]) > 0.85


def test_who_is_behind_and_who_may_hide(seen):
    xy = np.array([[0.0, 5.0], [0.0, 6.0], [0.0, 5.3], [1.0, 3.0]])
    behind = farther(np.zeros(2), xy, 0, 0.5)
    assert behind.tolist() == [False, True, False, False]       # 5.3 m is within the margin of 5 m
    assert not farther(np.zeros(2), xy, 0, 1.5).any()
    boxes = np.array([[0, 10, 0, 10], [20, 30, 0, 10], [0, 10, 0, 10], [0, 10, 0, 10]])
    assert overlaps_behind(boxes, np.array([25, 40, 5, 20]), behind)
    assert not overlaps_behind(boxes, np.array([30, 40, 5, 20]), behind)   # end exclusive: they only touch
    tracker = seen[0]
    forms = tracker.views["cam"].forms(xy, np.full(4, 1.7), np.full(4, 0.45))
    front = in_front(forms, 0, behind)
    assert front.valid.tolist() == [False, False, True, True] and forms.valid.all()   # k and those behind out
