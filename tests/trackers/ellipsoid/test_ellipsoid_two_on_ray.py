"""One tall person or two people on one line of sight: the head's size (:mod:`.two_on_ray`)."""

import cv2
import numpy as np
import pytest

from worldtrack.experiment import synthetic_tracker
from worldtrack.synth import make_scenario
from worldtrack.trackers.ellipsoid.births import head_height
from worldtrack.trackers.ellipsoid.forms import ellipse_crop
from worldtrack.trackers.ellipsoid.two_on_ray import head_width_px, silhouette_ratio, top_of_silhouette

NEAR_H, FAR_H = 1.69, 1.54


@pytest.fixture(scope="module")
def room():
    """The line-of-sight room's tracker (one 640x480 camera 2.5-3 m high), nobody on its map."""
    sc = make_scenario("line-of-sight", size=(640, 480), frames=1, seed=3)
    return synthetic_tracker(sc, "ellipsoid")


def _draw_person(labels, cam, xy, height):
    """A person as the foreground shows them (in place): a body 0.42 m wide up to the neck, a head
    0.16 m wide, seen from the camera."""
    xy = np.asarray(xy, float)
    ray = (xy - cam.centre[:2]) / np.hypot(*(xy - cam.centre[:2]))
    side = np.array([-ray[1], ray[0], 0.0])
    base = np.array([xy[0], xy[1], 0.0])
    up = np.array([0.0, 0.0, 1.0])
    neck = height - 0.22
    body = cam.project(np.array([base - 0.21 * side, base + 0.21 * side, base + 0.21 * side + neck * up,
                                 base - 0.21 * side + neck * up]))
    cv2.fillConvexPoly(labels, np.round(body).astype(np.int32), 1)
    centre = base + (height - 0.09) * up
    c, edge = cam.project(np.array([centre, centre + 0.08 * side]))
    cv2.ellipse(labels, (int(round(c[0])), int(round(c[1]))),
                (int(round(np.hypot(*(edge - c)))), int(round(0.09 / 0.08 * np.hypot(*(edge - c))))),
                0, 0, 360, 1, -1)


def _pair(cam, near_m=5.0, far_m=8.0):
    """Floor points of a near and a far person on one line of sight of ``cam``."""
    ray = np.array([0.15, 1.0]) / np.hypot(0.15, 1.0)
    return cam.centre[:2] + near_m * ray, cam.centre[:2] + far_m * ray


def _labels(cam, people):
    """Foreground labels (H, W) uint8 of ``people`` = [(floor point, height m), ...]."""
    labels = np.zeros((cam.height, cam.width), np.uint8)
    for xy, h in people:
        _draw_person(labels, cam, xy, h)
    return labels


def _ratio(tracker, labels, xy):
    """:func:`silhouette_ratio` in the region a height measurement reads for a person at ``xy``."""
    view = tracker.views["cam"]
    _, ring, box, valid, _ = view.forms(np.asarray(xy, float)[None], np.array([2.1]), np.array([0.56]))
    region = ellipse_crop(ring[0], box[0], view.grid, view.camera.has_distortion)
    b = tuple(box[0])
    down = view.down_direction(np.array([(b[0] + b[1]) / 2, (b[2] + b[3]) / 2]))
    return silhouette_ratio(view, labels, region, b, down)


def test_a_head_five_metres_away_is_as_wide_as_its_projection(room):
    cam = room.scene.cameras["cam"]
    near, _ = _pair(cam)
    labels = _labels(cam, [(near, NEAR_H)])
    top_uv = cam.project(np.array([[near[0], near[1], NEAR_H]]))[0]
    width = head_width_px(cam, np.array([near[0], near[1], 0.0]), top_uv)
    # 0.16 m at ~5.5 m from a 533 px focal length: ~15 px.
    assert 13 < width < 18
    ys, _ = np.nonzero(labels)
    found = top_of_silhouette(labels, np.ones_like(labels, bool), (0, cam.width, 0, cam.height),
                              np.array([0.0, 1.0]), (3.0, 6.0))
    assert found is not None and abs(found.top[1] - ys.min()) < 3  # the mean of the highest 1 %
    assert abs(found.width_px - width) < 0.25 * width


def test_one_person_reads_as_one_and_two_on_one_ray_as_two(room):
    cam = room.scene.cameras["cam"]
    near, far = _pair(cam)
    ratio, top, feet = _ratio(room, _labels(cam, [(near, NEAR_H)]), near)
    assert 0.85 < ratio < 1.2
    assert abs(head_height(cam, top, feet) - NEAR_H) < 0.04
    # Half the head "unsure" (a face or dark hair read as shadow-like): the head is as wide.
    faced = _labels(cam, [(near, NEAR_H)])
    ys, xs = np.nonzero(faced)
    head = (ys < ys.min() + 14) & (xs > np.median(xs[ys < ys.min() + 14]))
    faced[ys[head & (ys > ys.min() + 2)], xs[head & (ys > ys.min() + 2)]] = 2
    assert 0.85 < _ratio(room, faced, near)[0] < 1.2
    merged = _labels(cam, [(near, NEAR_H), (far, FAR_H)])
    ratio, top, feet = _ratio(room, merged, near)
    # The top is the far person's head: read as one person the near one would be ~1.9 m tall.
    assert head_height(cam, top, feet) > NEAR_H + 0.15
    assert 0.5 < ratio < 0.75          # ~ 5 m / 8 m


# ---------------------------------------------------------------- rendering both (two_hypotheses)

def _verdict(tracker, labels, xy, height):
    """The two-hypothesis test (:mod:`.two_hypotheses`) of one tracked person at ``xy`` of ``height``,
    nobody else on the map, on foreground ``labels``: (Verdict or None when no second person fits)."""
    from worldtrack.trackers.ellipsoid.real import ternary_real
    from worldtrack.trackers.ellipsoid.two_hypotheses import compare_on_ray

    view = tracker.views["cam"]
    t = tracker.fresh()
    p = t.position_map.add(xy[0], xy[1], height, 0.4, mode="tracking")
    joint = t.joint_image({"cam": ternary_real(labels, view.ring_px)}, [p])
    far = t.splitter.candidates(joint, {"cam": labels}, 0)
    if not len(far):
        return None
    cfg = t.config.split
    near = np.arange(height, 1.3, -cfg.shorter_step_m)
    return compare_on_ray(joint, 0, near, far, cfg.band_m)


def test_two_on_one_ray_win_when_both_are_rendered(room):
    cam = room.scene.cameras["cam"]
    near, far = _pair(cam, 5.0, 7.0)
    merged = _labels(cam, [(near, NEAR_H), (far, FAR_H)])
    _, top, feet = _ratio(room, merged, near)
    read = head_height(cam, top, feet)           # what one person's height measure reads: too tall
    assert read > NEAR_H + 0.1
    v = _verdict(room, merged, near, read)
    assert v is not None and v.gain > room.config.split.margin
    assert abs(v.near_height - NEAR_H) < 0.12
    assert np.hypot(*(v.far_xy - far)) < 0.6 and abs(v.far_height - FAR_H) < 0.12


@pytest.mark.parametrize("height", [1.6, 1.9])
def test_one_person_stays_one_when_both_are_rendered(room, height):
    cam = room.scene.cameras["cam"]
    near, _ = _pair(cam, 5.0, 7.0)
    v = _verdict(room, _labels(cam, [(near, height)]), near, height)
    assert v is None or v.gain < room.config.split.margin


def test_the_splitter_puts_the_second_person_behind(room):
    from worldtrack.trackers.ellipsoid.real import ternary_real
    from worldtrack.trackers.ellipsoid.two_hypotheses import BEHIND

    cam = room.scene.cameras["cam"]
    near, far = _pair(cam, 5.0, 7.0)
    merged = _labels(cam, [(near, NEAR_H), (far, FAR_H)])
    _, top, feet = _ratio(room, merged, near)
    t = room.fresh()
    read = head_height(cam, top, feet)
    p = t.position_map.add(near[0], near[1], read, 0.4, mode="tracking")
    real = {"cam": ternary_real(merged, t.views["cam"].ring_px)}
    born = []
    for k in range(t.config.split.held):       # "two" must win held frames in a row
        assert not born
        born = t.splitter.split(t.joint_image(real, [p]), {"cam": merged}, [p], t.position_map, 0.1 * k,
                                lambda q: t.life._confirm(q, 0.1 * k))
    assert len(born) == 1
    q = born[0]
    assert q.confirmed and q.id > 0 and BEHIND in q.flags and t.position_map.get(q.id) is q
    assert np.hypot(q.x - far[0], q.y - far[1]) < 0.6
    assert p.height < read - 0.05 and abs(p.height - NEAR_H) < 0.08 and not p.height_samples


def test_a_person_put_behind_is_not_a_young_duplicate():
    from worldtrack.trackers.base import PositionMap
    from worldtrack.trackers.ellipsoid import EllipsoidConfig
    from worldtrack.trackers.ellipsoid.life import LifeCycle, Measures
    from worldtrack.trackers.ellipsoid.two_hypotheses import BEHIND

    # A young track whose visible pixels are nearly all another person's: a duplicate, unless the
    # two-hypothesis test put it there (then it is hidden by the one in front).
    hidden = Measures(0.5, 200.0, float("nan"), 0.05, 0.5, 0.9, 0)
    kept = []
    for flag in (False, True):
        life = LifeCycle(EllipsoidConfig(), PositionMap(), False, lambda p: None)
        p = life.position_map.add(5.0, 7.0, 1.6, 0.4, mode="tracking")
        if flag:
            p.flags.add(BEHIND)
        kept.append(all(life._judge(p, hidden, 0.1 * i, (3, 10, 3)) for i in range(5)))
    assert kept == [False, True]
