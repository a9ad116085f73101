"""The feet anchor's head cue only where the silhouette's top is this person's head (``feet.head_clear``)."""

import numpy as np
import pytest
from _line_of_sight import line_of_sight_frame, misplaced

from worldtrack.trackers.ellipsoid.config import FeetConfig, HeightConfig
from worldtrack.trackers.ellipsoid import feet
from worldtrack.trackers.ellipsoid.feet import anchor_to_feet
from worldtrack.trackers.ellipsoid.head_clear import head_is_clear

BOX = np.array([10, 40, 20, 80])          # u0, u1, v0, v1 (px): 60 rows, 2 px of clearance
DOWN = np.array([0.0, 1.0])


def _look(top_row: int, owner_rows: slice | None = None):
    labels = np.zeros((100, 60), np.uint8)
    labels[top_row:75, 20:29] = 1          # one silhouette, 9 px wide, down to row 75
    owner = np.full((60, 30), -1, np.int32)
    owner[:, 8:20] = 0                     # this person's ellipse
    if owner_rows is not None:
        owner[owner_rows, 8:20] = 1        # somebody else's, over the top of it
    return labels, (np.ones((60, 30), bool), owner, BOX, DOWN)


def test_a_top_inside_the_region_and_clear_of_others_is_the_head():
    labels, look = _look(30)
    assert head_is_clear(None, labels, look, 0)


def test_a_silhouette_going_on_above_the_region_has_no_head_in_it():
    labels, look = _look(5)                # runs on above the region's top row (20)
    assert not head_is_clear(None, labels, look, 0)
    labels[:20] = 0                        # ends exactly at the region's edge: nothing above, a head
    assert head_is_clear(None, labels, look, 0)


def test_a_top_against_another_persons_ellipse_is_not_trusted():
    labels, look = _look(30, slice(0, 9))  # the other's ellipse ends 1 px above the top (row 29)
    assert not head_is_clear(None, labels, look, 0)
    labels, look = _look(30, slice(0, 5))  # ... or 5 px above it: clear
    assert head_is_clear(None, labels, look, 0)


@pytest.fixture(scope="module")
def seen():
    return line_of_sight_frame()


def test_the_anchor_asks_the_head_only_when_it_is_clear(seen, monkeypatch):
    tracker, labels, instance, truth = seen
    body = instance == truth["id"]
    rows = np.nonzero(body.any(axis=1))[0]
    cut = labels.copy()   # legs the floor's colour: the feet are not trusted, the head is asked
    cut[body & (np.arange(labels.shape[0])[:, None] > (rows.min() + rows.max()) / 2) & (cut == 1)] = 2

    def moves(head_clear: bool) -> int:
        q, _ = misplaced(tracker, truth, 0.6)
        q.height_samples.extend([truth["height"]] * 3)
        return anchor_to_feet([q], tracker.views, {"cam": cut}, tracker.walkable,
                              FeetConfig(anchor=True, head_clear=head_clear), HeightConfig())

    assert moves(True) == 1 and moves(False) == 1       # this head is clear: asked either way
    monkeypatch.setattr(feet, "head_is_clear", lambda *a: False)
    assert moves(True) == 0 and moves(False) == 1       # a head not clear is asked only without head_clear
