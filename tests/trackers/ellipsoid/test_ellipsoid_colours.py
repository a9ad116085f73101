"""What the colour identity sees: one owner map and one bincount per camera give exactly the
per-person answers (``cv2.calcHist`` on each person's masked crop, an owner map per person)."""

import numpy as np
import pytest

from worldtrack.experiment import synthetic_tracker
from worldtrack.synth import make_scenario
from worldtrack.trackers.ellipsoid.colours import colours_of, look, part_histograms_reference
from worldtrack.trackers.ellipsoid.forms import owner_crop


@pytest.fixture(scope="module")
def crowd():
    """Frame 3 of a 12-person crowd (320x240, one camera): the view, image, labels and people
    placed 0–0.15 m off their true places, so that ellipses overlap as a tracker's do."""
    sc = make_scenario("crowd", size=(320, 240), frames=4, seed=4, people=12, cameras=1)
    tracker = synthetic_tracker(sc, "ellipsoid")
    b = list(sc.frames())[3]
    view = tracker.views["c1"]
    image = b.views["c1"].image
    rng = np.random.default_rng(0)
    m = tracker.fresh().position_map
    people = [m.add(g["x"] + rng.normal(0, 0.08), g["y"] + rng.normal(0, 0.08), g["height"], 0.45, mode="tracking",
                    time=-10.0, track_id=int(g["id"])) for g in b.gt]
    return view, image, view.foreground.labels(image), people


def _reference(view, image, labels, people, min_pixels):
    """Person by person: their box, who owns each of its pixels, calcHist on their masked crop."""
    cam = view.camera
    sight = look(view, people)
    out = {}
    for k, p in enumerate(people):
        u0, u1, v0, v1 = (int(c) for c in sight.forms.box[k])
        if not sight.shown[k]:
            continue
        own = owner_crop(np.array([u0, u1, v0, v1], np.int64), sight.forms, view.grid, cam.has_distortion) == k
        parts = part_histograms_reference(cam, image[v0:v1, u0:u1], own & (labels[v0:v1, u0:u1] == 1), (u0, v0),
                                          np.array([p.x, p.y]), p.height, min_pixels)
        if parts is not None:
            out[k] = parts
    return out


@pytest.mark.parametrize("min_pixels", [20, 150])
def test_the_histograms_of_everyone_at_once_equal_calchist_person_by_person(crowd, min_pixels):
    view, image, labels, people = crowd
    ref = _reference(view, image, labels, people, min_pixels)
    got = colours_of(view, image, labels, look(view, people), np.arange(len(people)), min_pixels)
    # At 20 pixels a part most people are seen; at 150 the small, far or hidden ones drop out.
    assert (len(ref) >= 8) if min_pixels == 20 else (2 <= len(ref) <= 6)
    assert list(got) == sorted(ref)
    for k, parts in ref.items():
        for a, b in zip(parts, got[k].parts):
            assert a.dtype == b.dtype == np.float32 and a.shape == b.shape
            np.testing.assert_array_equal(a, b)
    # Asking about one person at a time (a smaller window) gives the same.
    for k in ref:
        one = colours_of(view, image, labels, look(view, people), [k], min_pixels)
        assert list(one) == [k]
        for a, b in zip(ref[k], one[k].parts):
            np.testing.assert_array_equal(a, b)


def _crowded_reference(view, people):
    """Person by person: (alone flags, met pairs) from an owner map of the grown ellipses over
    each person's box."""
    sight = look(view, people)
    forms, box = sight.forms, sight.forms.box
    grown = forms._replace(inner=forms.ring)
    alone, met = sight.shown.copy(), []
    for k in np.flatnonzero(sight.shown):
        u0, u1, v0, v1 = box[k]
        others = np.flatnonzero(forms.valid & (box[:, 0] < u1) & (box[:, 1] > u0) & (box[:, 2] < v1) & (box[:, 3] > v0))
        others = others[others != k]
        if len(others) and (owner_crop(box[k], grown, view.grid, False) == -2).any():
            alone[k] = False
            met += [tuple(sorted((people[k].id, people[j].id))) for j in others]
    return alone, met


def test_who_stands_clear_and_who_met_equal_the_per_person_test(crowd):
    view, _, _, people = crowd
    sight = look(view, people)
    alone, met = _crowded_reference(view, people)
    np.testing.assert_array_equal(sight.alone, alone)
    assert met == sight.met
    assert 0 < sight.alone.sum() < sight.shown.sum()   # both kinds are in the test
    # Two people drawn together step by step: the first shared pixel, not only big overlaps.
    pair = people[:2]
    ray = np.array([pair[0].x, pair[0].y]) - view.camera.centre[:2]
    across = np.array([-ray[1], ray[0]]) / np.hypot(*ray)     # sideways in the image
    pair[1].x, pair[1].y = np.array([pair[0].x, pair[0].y]) + 1.5 * across
    steps = 0
    while steps < 400:
        alone, met = _crowded_reference(view, pair)
        sight = look(view, pair)
        np.testing.assert_array_equal(sight.alone, alone)
        assert sight.met == met
        if not alone.all():
            break
        pair[1].x, pair[1].y = pair[1].x - 0.005 * across[0], pair[1].y - 0.005 * across[1]
        steps += 1
    ids = tuple(sorted(p.id for p in pair))
    assert 10 < steps < 400 and not alone.any() and met == [ids, ids]


def test_with_isolation_by_ellipse_rings_that_touch_still_leave_both_clear(crowd):
    view, _, _, people = crowd
    pair = people[2:4]
    ray = np.array([pair[0].x, pair[0].y]) - view.camera.centre[:2]
    across = np.array([-ray[1], ray[0]]) / np.hypot(*ray)
    pair[1].x, pair[1].y = np.array([pair[0].x, pair[0].y]) + 1.5 * across
    seen = []
    for _ in range(300):
        ring, ellipse = look(view, pair, "ring"), look(view, pair, "ellipse")
        assert ring.met == ellipse.met and (ellipse.alone >= ring.alone).all()
        seen.append((ring.alone.all(), ellipse.alone.all()))
        if not ellipse.alone.any():
            break
        pair[1].x, pair[1].y = pair[1].x - 0.005 * across[0], pair[1].y - 0.005 * across[1]
    # Far apart both clear; then rings meet while the ellipses do not; then the ellipses meet.
    assert seen[0] == (True, True) and (False, True) in seen and seen[-1] == (False, False)
    first = seen.index((False, True))
    assert all(s == (True, True) for s in seen[:first]) and seen.count((False, True)) >= 3
