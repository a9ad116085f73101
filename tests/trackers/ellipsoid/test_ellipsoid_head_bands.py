"""Births of people behind known ones from a small head band (:mod:`worldtrack.trackers.ellipsoid.head_bands`)."""

import numpy as np
from _ellipsoid_scenes import person_mask
from _ellipsoid_seen import one_person_seen

from worldtrack.foreground import make_foregrounds
from worldtrack.trackers.ellipsoid import EllipsoidConfig, EllipsoidTracker
from worldtrack.trackers.ellipsoid.args import People


def test_the_top_of_a_head_above_a_known_persons_tall_ellipse_is_proposed_only_with_head_bands():
    # Issue 37 (crowd 50): somebody 1.5 m behind a tracked person on the same line of sight; the
    # tracked person's ellipse, too tall (1.9 m for 1.65 m), covers all of them but the top of the
    # head: a sliver below the births' smallest blob.
    scene, person, bgs, tracker, images, real = one_person_seen(seed=3)
    view = tracker.views["c1"]
    cam = view.camera
    ray = (person - cam.centre[:2]) / np.hypot(*(person - cam.centre[:2]))
    behind = person + 1.5 * ray
    mask = person_mask(cam, person, 1.65, 0.4) | person_mask(cam, behind, 1.65, 0.4)
    known = People(np.array([person]), np.array([1.9]), np.array([0.4]))
    assert tracker.births._in_camera("c1", mask, known) == []            # too small for a person
    tracker.births.head_bands = True
    proposals = tracker.births._in_camera("c1", mask, known)
    assert len(proposals) == 1 and proposals[0].height is None
    assert np.hypot(*(proposals[0].xy - behind)) < 0.1                  # by its top, at the default height
    # The same sliver with foreground above it is a gap inside a silhouette, not the top of one.
    top = int(np.nonzero(person_mask(cam, behind, 1.65, 0.4))[0].min())
    mask[max(top - 6, 0):top, :] = 1
    assert all(np.hypot(*(q.xy - behind)) > 0.3 for q in tracker.births._in_camera("c1", mask, known))


def test_births_head_bands_is_the_crowd_setting_and_off_by_default():
    scene, person, bgs, tracker, images, real = one_person_seen(seed=3)
    assert tracker.births.head_bands is False
    crowd = EllipsoidTracker(scene, make_foregrounds(scene, bgs, "colour"),
                             EllipsoidConfig(crowd={"births_head_bands": True}))
    assert crowd.births.head_bands is True


def test_a_small_blob_away_from_known_people_is_no_head_band():
    scene, person, bgs, tracker, images, real = one_person_seen(seed=3)
    cam = tracker.views["c1"].camera
    mask = person_mask(cam, person, 1.65, 0.4)
    known = People(np.array([person]), np.array([1.65]), np.array([0.4]))
    foot = cam.project(np.array([[*person, 0.0]]))[0]
    u, v = int(foot[0]) + 40, int(foot[1]) - 20                           # a patch beside them, on the floor
    mask[v:v + 8, u:u + 8] = 1
    tracker.births.head_bands = True
    assert tracker.births._in_camera("c1", mask, known) == []


def test_a_head_band_has_background_above_and_known_people_below():
    from worldtrack.trackers.ellipsoid.head_bands import is_head_band
    mask = np.zeros((40, 30), np.uint8)
    mask[10:40, 10:20] = 1                                                 # a silhouette from row 10
    explained = np.zeros_like(mask)
    explained[15:, :] = 1                                                  # a known person from row 15
    band, origin, down = mask[10:15, 10:20].astype(bool), (10, 10), np.array([0.0, 1.0])
    assert is_head_band(mask, explained, band, origin, down, head=8.0)
    assert not is_head_band(mask, np.zeros_like(mask), band, origin, down, head=8.0)   # nobody below
    above = mask.copy()
    above[5:10, 10:20] = 1                                                 # foreground above: inside a silhouette
    assert not is_head_band(above, explained, band, origin, down, head=8.0)
    assert not is_head_band(mask, explained, band, origin, down, head=20.0)            # too small for a head there
    assert not is_head_band(mask, explained, band, origin, None, head=8.0)
