"""The feet anchor on one camera: feet looked for again below a region that cuts them, feet beside
another person's ellipse not trusted, a person near the image's edge whose silhouette is whole."""

import numpy as np
import pytest
from _line_of_sight import line_of_sight_frame, misplaced

from worldtrack.trackers.ellipsoid.config import FeetConfig, HeightConfig
from worldtrack.trackers.ellipsoid.feet import anchor_to_feet, touches_other
from worldtrack.trackers.ellipsoid.border import cut_by_border


@pytest.fixture(scope="module")
def seen():
    return line_of_sight_frame()


@pytest.mark.parametrize("along_m", [1.0, 1.5, 2.0])
def test_a_track_too_far_to_hold_its_own_feet_finds_them_below_its_region(seen, along_m):
    tracker, labels, instance, truth = seen
    # Too far along the ray and 15 cm short: drawn there, the tallest person's region ends above the
    # real feet (the silhouette goes on below it), and the head at the wrong height holds it far.
    p, xy = misplaced(tracker, truth, along_m)
    p.height = truth["height"] - 0.15
    moved = anchor_to_feet([p], tracker.views, {"cam": labels}, tracker.walkable, FeetConfig(anchor=True),
                           HeightConfig())
    assert moved == 1
    # Looked for again nearer, the feet are found: back within 0.15 m (without: 0.9-1.9 m off).
    assert np.hypot(p.x - xy[0], p.y - xy[1]) < 0.15


def test_feet_next_to_another_persons_ellipse_are_not_trusted():
    owner = np.full((40, 20), -1, np.int32)
    owner[:, :8] = 0                      # this person's ellipse
    owner[30:, 14:] = 1                   # somebody else's, low on the right
    box = np.array([100, 120, 50, 90])    # u0, u1, v0, v1: 40 rows, so 2 px of clearance (3 %, at least 2)
    assert not touches_other(owner, box, np.array([104.0, 85.0]), 0)   # own ellipse only
    assert not touches_other(owner, box, np.array([111.0, 85.0]), 0)   # 3 px from the other one
    assert touches_other(owner, box, np.array([112.0, 85.0]), 0)       # 2 px from it
    assert not touches_other(owner, box, np.array([112.0, 85.0]), 1)   # from the other's side, it is its own
    owner[0, 0] = -2                                                   # several people: not this one alone
    assert touches_other(owner, box, np.array([100.0, 50.0]), 0)
    assert touches_other(owner, box, np.array([np.nan, 60.0]), 0)      # no pixel: nothing to trust


def test_a_person_whole_in_view_near_the_edge_is_not_cut_by_the_border(seen):
    tracker, labels, instance, truth = seen
    cam = tracker.scene.cameras["cam"]
    body = instance == truth["id"]
    vs, us = np.nonzero(body)
    # Shift the image so the person stands 3 px from the left edge; the search box (the tallest
    # person's ellipse and ring) then reaches past the edge, the silhouette does not.
    shift = int(us.min()) - 3
    moved = np.zeros_like(labels)
    moved[:, : labels.shape[1] - shift] = labels[:, shift:]
    region = np.zeros((int(vs.max()) + 6, 40), bool)
    region[:, :] = True
    box = (0, 40, 0, region.shape[0])
    mine = np.zeros_like(moved)
    mine[:, : labels.shape[1] - shift] = body[:, shift:]
    fg = np.where(mine, moved, 0).astype(np.uint8)
    assert cut_by_border(cam, fg, region, box)                              # the box test: cut
    assert not cut_by_border(cam, fg, region, box, bottom=False, border="silhouette")
    fg[vs.min():vs.max(), 0] = 1                                            # foreground at the edge
    assert cut_by_border(cam, fg, region, box, bottom=False, border="silhouette")


def test_where_somebody_else_covers_the_place_below_the_head_still_places_the_track(seen):
    tracker, labels, instance, truth = seen
    p, xy = misplaced(tracker, truth, 1.5)
    p.height = truth["height"] - 0.15
    # Somebody tracked standing 0.35 m beside the feet: p's own region is clear of them, the region
    # drawn at the cut (nearer, larger) is theirs more than p's.
    other, _ = misplaced(tracker, truth, 0.0)
    other.height = truth["height"]
    cam = tracker.scene.cameras["cam"]
    ray = (xy - cam.centre[:2]) / np.hypot(*(xy - cam.centre[:2]))
    other.x, other.y = other.x - 0.35 * ray[1], other.y + 0.35 * ray[0]
    start = np.array([p.x, p.y])
    anchor_to_feet([p, other], tracker.views, {"cam": labels}, tracker.walkable, FeetConfig(anchor=True),
                   HeightConfig())
    # No feet taken from under the other person: p stays on its line of sight, beyond them.
    assert np.hypot(p.x - xy[0], p.y - xy[1]) > 0.5
    assert np.hypot(p.x - start[0], p.y - start[1]) < 1.2
