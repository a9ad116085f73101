"""Births of people in front of confirmed ones from the legs below them
(:mod:`worldtrack.trackers.ellipsoid.in_front`), and head bands only above confirmed people
(:func:`worldtrack.trackers.ellipsoid.head_bands.confirmed_images`)."""

import numpy as np
from _ellipsoid_scenes import person_mask
from _ellipsoid_seen import one_person_seen

from worldtrack.foreground import make_foregrounds
from worldtrack.trackers.ellipsoid import EllipsoidConfig, EllipsoidTracker
from worldtrack.trackers.ellipsoid.args import People
from worldtrack.trackers.ellipsoid.in_front import in_front_proposals, legs_below


def _known_image(view, known: People) -> np.ndarray:
    from worldtrack.trackers.ellipsoid.head_bands import confirmed_images
    return confirmed_images(view, known, np.ones(len(known.xy), bool))[0]


def _scene():
    """The lab's first camera, a confirmed person at ``far`` (1.65 m) and somebody ``near`` 0.7 m in
    front of them on the same line of sight, the far one's ellipse over their head."""
    scene, far, bgs, tracker, images, real = one_person_seen(seed=3)
    view = tracker.views["c1"]
    ray = (far - view.camera.centre[:2]) / np.hypot(*(far - view.camera.centre[:2]))
    near = far - 0.7 * ray
    return view, far, near


def test_the_legs_below_a_farther_confirmed_person_propose_the_person_in_front():
    view, far, near = _scene()
    cam = view.camera
    mask = person_mask(cam, far, 1.65, 0.4) | person_mask(cam, near, 1.65, 0.4)
    known = People(np.array([far]), np.array([1.65]), np.array([0.4]))
    explained = _known_image(view, known)
    found = in_front_proposals(view, mask, known, np.array([True]), explained, 1.65, 0.4, 0.1, 0.4)
    assert len(found) == 1 and np.hypot(*(found[0] - near)) < 0.15        # feet at the lowest row
    # Not below a candidate; not without the legs; not where somebody known stands already.
    assert in_front_proposals(view, mask, known, np.array([False]), explained, 1.65, 0.4, 0.1, 0.4) == []
    alone = person_mask(cam, far, 1.65, 0.4)
    assert in_front_proposals(view, alone, known, np.array([True]), explained, 1.65, 0.4, 0.1, 0.4) == []
    # Somebody known whose ellipse reaches down to the feet explains the legs (whatever the separation).
    both = People(np.array([far, near]), np.array([1.65, 1.65]), np.array([0.4, 0.4]))
    assert in_front_proposals(view, mask, both, np.array([True, True]), _known_image(view, both),
                              1.65, 0.4, 0.1, 0.0) == []
    # Somebody known 0.3 m behind the feet (their ellipse ends above them) is within the separation.
    ray = (far - near) / np.hypot(*(far - near))
    close = People(np.array([far, near + 0.3 * ray]), np.array([1.65, 1.65]), np.array([0.4, 0.4]))
    assert in_front_proposals(view, mask, close, np.array([True, False]), _known_image(view, close),
                              1.65, 0.4, 0.1, 0.4) == []
    assert len(in_front_proposals(view, mask, close, np.array([True, False]), _known_image(view, close),
                                  1.65, 0.4, 0.1, 0.2)) == 1


def test_a_thin_streak_below_the_feet_is_not_a_person():
    # Foreground below the feet only in the strip looked down (a shadow, a pole): a person of the
    # default size standing at its end would not be mostly foreground.
    view, far, near = _scene()
    cam = view.camera
    mask = person_mask(cam, far, 1.65, 0.4)
    foot, near_foot = cam.project(np.array([[*far, 0.0], [*near, 0.0]]))
    u, v0, v1 = int(round(foot[0])), int(round(foot[1])), int(round(near_foot[1]))
    mask[v0:v1, u - 8:u + 9] = 1                                           # as wide as the strip
    known = People(np.array([far]), np.array([1.65]), np.array([0.4]))
    assert in_front_proposals(view, mask, known, np.array([True]), _known_image(view, known),
                              1.65, 0.4, 0.1, 0.4) == []


def test_legs_below_bridge_short_holes_and_stop_at_the_border():
    mask = np.zeros((60, 20), np.uint8)
    mask[5:50, 6:14] = 1
    feet, down = np.array([10.0, 20.0]), np.array([0.0, 1.0])
    assert legs_below(mask, feet, down, 3.0, 35) == 29
    mask[30:32] = 0                                                        # a 2-row hole in the mask
    assert legs_below(mask, feet, down, 3.0, 35) == 29
    mask[30:33] = 0                                                        # 3 rows: the legs end there
    assert legs_below(mask, feet, down, 3.0, 35) == 9
    mask[5:60, 6:14] = 1                                                   # down to the image's last row
    assert legs_below(mask, feet, down, 3.0, 45) == -1


def test_births_in_front_and_head_bands_confirmed_are_crowd_settings_off_by_default():
    scene, person, bgs, tracker, images, real = one_person_seen(seed=3)
    assert tracker.births.in_front == 0.0 and tracker.births.bands_confirmed is False
    assert tracker.births.bands_tallest == 0.0 and tracker.births.heights_clear is False
    crowd = EllipsoidTracker(scene, make_foregrounds(scene, bgs, "colour"),
                             EllipsoidConfig(crowd={"births_in_front": 0.15, "head_bands_confirmed": True}))
    assert crowd.births.in_front == 0.15 and crowd.births.bands_confirmed is True


def test_a_head_band_tops_out_above_the_confirmed_people_drawn_at_their_tallest():
    from worldtrack.trackers.ellipsoid.head_bands import is_head_band
    mask = np.zeros((40, 30), np.uint8)
    mask[10:40, 10:20] = 1
    explained = np.zeros_like(mask)
    explained[15:, :] = 1
    band, origin, down = mask[10:15, 10:20].astype(bool), (10, 10), np.array([0.0, 1.0])
    tall = np.zeros_like(mask)
    tall[12:, :] = 1                                                       # the person below at their tallest
    assert is_head_band(mask, explained, band, origin, down, 8.0, tall)
    tall[8:, :] = 1                                                        # ... would reach above the band's top
    assert not is_head_band(mask, explained, band, origin, down, 8.0, tall)


def test_confirmed_images_draw_only_confirmed_people_and_at_their_tallest():
    from worldtrack.trackers.ellipsoid.head_bands import confirmed_images
    scene, person, bgs, tracker, images, real = one_person_seen(seed=3)
    view = tracker.views["c1"]
    other = person + np.array([1.2, 0.0])
    people = People(np.array([person, other]), np.array([1.65, 1.65]), np.array([0.4, 0.4]))
    under, tall = confirmed_images(view, people, np.array([True, False]), 2.1)
    alone, alone_tall = confirmed_images(view, People(*(a[:1] for a in people)), np.array([True]), 2.1)
    assert under.any() and np.array_equal(under, alone) and np.array_equal(tall, alone_tall)
    assert np.nonzero(tall.any(axis=1))[0].min() < np.nonzero(under.any(axis=1))[0].min() - 5
    assert not confirmed_images(view, people, np.array([False, False]))[0].any()
    assert confirmed_images(view, people, np.array([True, False]))[1] is None


def test_head_bands_confirmed_drops_a_band_a_confirmed_persons_own_head_could_be():
    # s11's head-band case (a 1.9 m ellipse over a 1.65 m person, somebody 1.5 m behind): the band
    # is no higher than a 2.1 m person there would reach, so with the gate it is not proposed.
    scene, person, bgs, tracker, images, real = one_person_seen(seed=3)
    cam = tracker.views["c1"].camera
    ray = (person - cam.centre[:2]) / np.hypot(*(person - cam.centre[:2]))
    mask = person_mask(cam, person, 1.65, 0.4) | person_mask(cam, person + 1.5 * ray, 1.65, 0.4)
    known = People(np.array([person]), np.array([1.9]), np.array([0.4]))
    tracker.births.head_bands = True
    assert len(tracker.births._in_camera("c1", mask, known, np.array([True]))) == 1
    tracker.births.bands_confirmed = True                                  # confirmed people only: still one
    assert len(tracker.births._in_camera("c1", mask, known, np.array([True]))) == 1
    tracker.births.bands_tallest = 2.1                                     # and topping out above them at 2.1 m
    assert tracker.births._in_camera("c1", mask, known, np.array([True])) == []
    assert tracker.births._in_camera("c1", mask, known, np.array([False])) == []   # not above a candidate


def test_births_heights_clear_reads_no_height_from_a_blob_with_foreground_beyond_an_end():
    scene, person, bgs, tracker, images, real = one_person_seen(seed=3)
    cam = tracker.views["c1"].camera
    mask = person_mask(cam, person, 1.65, 0.4)
    nobody = People(np.zeros((0, 2)), np.zeros(0), np.zeros(0))
    top = int(np.nonzero(mask)[0].min())
    mask[top - 3, :] = 1                             # a 1-px line just above the head: opened away, not a gap
    tracker.births.heights_clear = False
    (whole,) = tracker.births._in_camera("c1", mask, nobody)
    assert whole.height is not None and abs(whole.height - 1.65) < 0.1
    tracker.births.heights_clear = True
    (cut,) = tracker.births._in_camera("c1", mask, nobody)
    assert cut.height is None and np.allclose(cut.xy, whole.xy)
    mask[top - 3, :] = 0                             # background above and below: a height
    (clear,) = tracker.births._in_camera("c1", mask, nobody)
    assert clear.height is not None and abs(clear.height - 1.65) < 0.1
