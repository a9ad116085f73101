"""Heights: the ends of a person's foreground (kernel against reference), one view's measurement,
head rays triangulated, and when the tracker asks for measurements."""

import numpy as np
import pytest
from _ellipsoid_scenes import drawn_frame, ellipsoid_frames, noise_backgrounds, one_camera_scene, two_camera_scene

import worldtrack.trackers.ellipsoid.height as height_module
from worldtrack.geometry import quadric as q
from worldtrack.foreground import make_foregrounds
from worldtrack.synth import make_scenario
from worldtrack.trackers.base import Frame
from worldtrack.trackers.ellipsoid import EllipsoidConfig, EllipsoidTracker
from worldtrack.trackers.ellipsoid.forms import ellipse_crop
from worldtrack.trackers.ellipsoid.height import (extreme_ends, extreme_ends_reference, measure_height,
                                                  triangulate_height)


@pytest.mark.parametrize("down", [(0.0, 1.0), (0.6, 0.8), (-0.28, 0.96), (1.0, 0.0)])
def test_extreme_ends_equals_the_reference(down):
    # Axis-aligned directions put whole rows (or columns) of pixels on the same value along
    # ``down``: the ties at the cut must be taken in the same (row-major) order.
    rng = np.random.default_rng(3)
    for trial in range(20):
        H, W = 120, 90
        labels = np.zeros((H, W), np.uint8)
        y, x = rng.integers(0, 60), rng.integers(0, 50)
        labels[y:y + rng.integers(5, 60), x:x + rng.integers(3, 40)] = 1
        labels[rng.random((H, W)) < 0.1] = rng.choice([0, 1, 2])
        u0, v0 = int(rng.integers(0, 20)), int(rng.integers(0, 30))
        h, w = int(rng.integers(10, H - v0)), int(rng.integers(10, W - u0))
        region = rng.random((h, w)) < 0.9
        n, first, last = extreme_ends(labels, region, u0, v0, *down)
        rn, rfirst, rlast = extreme_ends_reference(labels, region, u0, v0, *down)
        assert n == rn == np.count_nonzero((labels[v0:v0 + h, u0:u0 + w] == 1) & region)
        np.testing.assert_array_equal(first, rfirst)
        np.testing.assert_array_equal(last, rlast)


def test_extreme_ends_of_a_rectangle_are_its_top_and_bottom_rows():
    labels = np.zeros((300, 200), np.uint8)
    labels[50:250, 80:120] = 1              # 8000 pixels: the 80 extreme are exactly two rows
    region = np.ones((300, 200), bool)
    n, top, bottom = extreme_ends(labels, region, 0, 0, 0.0, 1.0)
    assert n == 8000
    np.testing.assert_allclose(top, [99.5, 50.5])      # rows 50 and 51, columns 80…119
    np.testing.assert_allclose(bottom, [99.5, 248.5])  # rows 248 and 249
    n, _, _ = extreme_ends(labels, np.zeros((300, 200), bool), 0, 0, 0.0, 1.0)
    assert n == 0


@pytest.fixture(scope="module")
def still_tall_person():
    """A 1.85 m person standing still, head and feet in view: (camera, per frame (labels, xy, region, box, down))."""
    sc = make_scenario("static-grid", size=(320, 240), frames=170, seed=0, camera="cam1", height=1.85)
    cam = sc.scene.cameras["cam1"]
    fg = make_foregrounds(sc.scene, {"cam1": sc.background("cam1")}, "colour", 20)["cam1"]
    tr = EllipsoidTracker(sc.scene, {"cam1": fg})
    cs, (lo, hi) = tr.views["cam1"], tr.config.height.range_m
    views = []
    for b in sc.render():
        g = b.gt[0]
        if not (g["speed"] == 0 and g["head_cam1"] and g["feet_cam1"]):
            continue
        # The region the tracker measures in: the tallest plausible person's ellipse, with its ring.
        xy = np.array([[g["x"], g["y"]]])
        _, ring, box, valid, _ = cs.forms(xy, np.array([hi]), np.array([1.25 * sc.scene.people.width]))
        region = ellipse_crop(ring[0], box[0], cs.grid, cam.has_distortion)
        u0, u1, v0, v1 = box[0]
        down = cs.down_direction(np.array([(u0 + u1) / 2, (v0 + v1) / 2]))
        views.append((fg.labels(b.views["cam1"].image), xy[0], region, tuple(box[0]), down))
    return cam, cs, (lo, hi), views


def test_measured_height_of_a_rendered_person(still_tall_person):
    cam, cs, height_range, views = still_tall_person
    measured = [measure_height(cam, labels, cs.occ, xy, region, box, height_range_m=height_range, down=down)
                for labels, xy, region, box, down in views]
    ok = [h for h in measured if h is not None]
    assert len(ok) >= 5
    assert abs(np.median(ok) - 1.85) < 0.05


def test_height_measured_for_a_track_off_along_the_line_of_sight_only(still_tall_person):
    # A tall person tracked with a short model sits too deep along the camera's line of sight:
    # the feet are then 0.6 m from the track, which max_depth_offset_m allows along the ray only.
    cam, cs, height_range, views = still_tall_person
    def heights(shift_along: float, shift_across: float, **kw):
        out = []
        for labels, xy, region, box, down in views:
            ray = (xy - cam.centre[:2]) / np.hypot(*(xy - cam.centre[:2]))
            moved = xy + shift_along * ray + shift_across * np.array([-ray[1], ray[0]])
            out.append(measure_height(cam, labels, cs.occ, moved, region, box, height_range_m=height_range,
                                      down=down, **kw))
        return [h for h in out if h is not None]
    assert heights(0.6, 0.0) == []                                      # the old 0.4 m limit everywhere
    deep = heights(0.6, 0.0, max_depth_offset_m=1.0)
    assert len(deep) >= 5 and abs(np.median(deep) - 1.85) < 0.05       # measured from the image alone
    assert heights(0.0, 0.6, max_depth_offset_m=1.0) == []              # across the ray: somebody else


def test_two_head_rays_from_different_sides_give_the_height():
    head = np.array([1.0, 2.0, 1.78])
    rays = []
    for cam in ((0.0, 0.0, 3.5), (4.0, 0.5, 3.2)):
        o = np.array(cam)
        rays.append((o, (head - o) / np.linalg.norm(head - o)))
    assert triangulate_height(rays, np.array([1.05, 2.0])) == pytest.approx(1.78, abs=1e-9)
    # Nearly parallel rays pin nothing; a point far from the person is someone else's head.
    assert triangulate_height([rays[0], (rays[0][0] + 0.01, rays[0][1])], np.array([1.0, 2.0])) is None
    assert triangulate_height(rays, np.array([2.0, 3.0])) is None


def test_head_rays_through_two_different_heads_give_no_height():
    # Camera 1 sees this person's head (1.70 m); camera 2's "top" is a taller person's 0.3 m
    # behind, at 1.95 m. The rays still have a nearest point, 6 cm off each ray, at a wrong height.
    c1, c2 = np.array([0.0, 0.0, 3.5]), np.array([4.0, 0.5, 3.2])
    mine, theirs = np.array([1.0, 2.0, 1.70]), np.array([0.8, 2.2, 1.95])
    rays = [(c1, (mine - c1) / np.linalg.norm(mine - c1)), (c2, (theirs - c2) / np.linalg.norm(theirs - c2))]
    h = triangulate_height(rays, np.array([1.0, 2.0]))
    assert h is not None and abs(h - 1.70) > 0.1  # without the gate: accepted, and wrong
    assert triangulate_height(rays, np.array([1.0, 2.0]), max_ray_gap_m=0.03) is None
    # Rays that do meet (up to 1 cm of pixel noise) still give the height.
    near = mine + np.array([0.0, 0.0, 0.01])
    good = [rays[0], (c2, (near - c2) / np.linalg.norm(near - c2))]
    assert triangulate_height(good, np.array([1.0, 2.0]), max_ray_gap_m=0.03) == pytest.approx(1.705, abs=0.01)


def test_height_is_no_longer_measured_once_the_samples_are_in(monkeypatch):
    # A person's height does not change: after ``height_samples`` measurements the median is final.
    # (The measurement itself is stubbed: this is about when it is asked for.)
    calls = []
    monkeypatch.setattr(height_module, "measure_height", lambda *a, **k: calls.append(1) or 1.8)
    scene = one_camera_scene((320, 240))
    rng = np.random.default_rng(2)
    bg = noise_backgrounds(scene, rng)["cam"]
    tr = EllipsoidTracker(scene, make_foregrounds(scene, {"cam": bg}, "colour"),
                          EllipsoidConfig(births={"where": "none"}, height={"samples": 4}))
    tr.init_track(-1.0, 1.5, track_id=1)
    per_frame = []
    for i in range(30):
        before = len(calls)
        tr.step({"cam": Frame(drawn_frame(scene, bg, [(-1.0, 1.5)], rng), i / 10, i)}, i / 10)
        per_frame.append(len(calls) - before)
    assert len(tr.position_map[1].height_samples) == 4     # measured, and no more than wanted
    assert sum(per_frame[:5]) >= 4 and sum(per_frame[-15:]) == 0
    assert tr.position_map[1].height == pytest.approx(1.8)


def _heights_measured(monkeypatch, heads: dict) -> list[float]:
    """Height samples of one person seen by both lab cameras over 5 frames, with each camera's
    head ray stubbed to pass through ``heads[camera id]`` (None: no head found in that view) and
    the single-view measurement stubbed to 1.50 m."""
    def head_ray(cam, *args, **kwargs):
        head = heads[cam.id]
        return None if head is None else (cam.centre, (head - cam.centre) / np.linalg.norm(head - cam.centre))

    monkeypatch.setattr(height_module, "head_ray", head_ray)
    monkeypatch.setattr(height_module, "measure_height", lambda *a, **k: 1.50)
    scene = two_camera_scene((320, 240))
    rng = np.random.default_rng(5)
    bgs = noise_backgrounds(scene, rng)
    tr = EllipsoidTracker(scene, make_foregrounds(scene, bgs, "colour"), EllipsoidConfig(births={"where": "none"}))
    tr.init_track(-1.0, 1.2, track_id=1)
    cen, rad = q.person_ellipsoid([[-1.0, 1.2]], 1.65, 0.4)
    for i in range(5):
        tr.step(ellipsoid_frames(scene, bgs, cen, rad, rng, i), i / 10)
    return tr.position_map[1].height_samples


def test_head_rays_that_miss_each_other_give_no_height_that_frame(monkeypatch):
    mine, theirs = np.array([-1.0, 1.2, 1.70]), np.array([-1.15, 1.45, 1.95])
    agree = _heights_measured(monkeypatch, {"c1": mine, "c2": mine})
    assert len(agree) == 5 and np.allclose(agree, 1.70, atol=0.02)       # triangulated, every frame
    # c2's "head" is a taller person's behind: no triangulated height, and no single-view one either.
    assert _heights_measured(monkeypatch, {"c1": mine, "c2": theirs}) == []
    # One head ray only: the single-view measurement is what there is.
    one = _heights_measured(monkeypatch, {"c1": mine, "c2": None})
    assert len(one) >= 1 and np.allclose(one, 1.50)


# ---------------------------------------------------------------- warm start
