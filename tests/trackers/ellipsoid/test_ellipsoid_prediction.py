"""The prediction before matching: constant velocity, the part along a lone camera's ray damped
(``crowd.predict_along_ray``, :mod:`worldtrack.trackers.ellipsoid.prediction`)."""

import numpy as np
import pytest
from _ellipsoid_scenes import noise_backgrounds, one_camera_scene, two_camera_scene

from worldtrack.foreground import make_foregrounds
from worldtrack.trackers.ellipsoid import EllipsoidConfig, EllipsoidTracker
from worldtrack.trackers.base import Person
from worldtrack.trackers.ellipsoid.prediction import MeasuredShare, depth_observed, lone_camera, lone_rays, predicted_places


@pytest.mark.parametrize("share", [0.0, 0.3, 1.0])
def test_only_the_velocity_along_the_lone_cameras_ray_is_scaled(share):
    scene = one_camera_scene()
    cam = scene.cameras["cam"]
    xy = np.array([[-1.0, 1.5], [0.5, 3.0], [-2.0, 2.0]])
    v = np.array([[0.4, 1.2], [-0.8, 0.3], [1.0, -1.0]])
    lone = np.array([True, True, False])
    out = predicted_places(xy, v, 0.1, [cam], np.zeros(3, int), lone, share)
    ray = cam.floor_rays(xy, min_distance=0.3)[0]
    move = (out - xy) / 0.1
    along, want_along = np.sum(move * ray, axis=1), np.sum(v * ray, axis=1)
    across, want_across = move[:, 0] * ray[:, 1] - move[:, 1] * ray[:, 0], v[:, 0] * ray[:, 1] - v[:, 1] * ray[:, 0]
    np.testing.assert_allclose(across, want_across, atol=1e-12)            # across the ray: all of it
    np.testing.assert_allclose(along[:2], share * want_along[:2], atol=1e-12)
    np.testing.assert_allclose(out[2], xy[2] + 0.1 * v[2], atol=1e-12)     # several cameras: the full velocity


def test_each_person_is_damped_along_their_own_cameras_ray():
    scene = two_camera_scene()
    cams = [scene.cameras["c1"], scene.cameras["c2"]]
    xy = np.array([[-1.0, 1.5], [-1.0, 1.5]])
    v = np.array([[0.5, 0.5], [0.5, 0.5]])
    out = predicted_places(xy, v, 1.0, cams, np.array([0, 1]), np.array([True, True]), 0.0)
    for k in range(2):
        ray = cams[k].floor_rays(xy[k], min_distance=0.3)[0]
        assert abs((out[k] - xy[k]) @ ray) < 1e-12
    assert np.linalg.norm(out[0] - out[1]) > 0.1       # the two cameras' rays differ there


def test_the_lone_camera_is_the_only_one_of_the_trackers_that_showed_the_person():
    assert lone_camera(("c2",), ["c1", "c2"]) == 1
    assert lone_camera(("c1", "c2"), ["c1", "c2"]) == -1
    assert lone_camera(("other",), ["c1", "c2"]) == -1      # another tracker's camera
    assert lone_camera((), ["cam"]) == 0                    # one camera: always it


def _one_camera_walker(crowd: dict, before=lambda tracker, person: None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A one-camera tracker with ``crowd`` settings and one person at (-1, 2) m walking 0.8 m/s along
    the camera's ray and 0.5 m/s across it (``before(tracker, person)`` runs first), predicted 0.1 s
    ahead: (their move (2,) m, the ray's floor direction (2,), the direction across it (2,))."""
    scene = one_camera_scene()
    rng = np.random.default_rng(0)
    tracker = EllipsoidTracker(scene, make_foregrounds(scene, noise_backgrounds(scene, rng), "colour"),
                               EllipsoidConfig(crowd=crowd))
    person = tracker.position_map[tracker.init_track(-1.0, 2.0).id]
    before(tracker, person)
    ray = scene.cameras["cam"].floor_rays(np.array([-1.0, 2.0]), min_distance=0.3)[0]
    across = np.array([-ray[1], ray[0]])
    person.vx, person.vy = 0.8 * ray + 0.5 * across
    tracker._predict([person], 0.1, 0.1)
    return np.array([person.x, person.y]) - (-1.0, 2.0), ray, across


@pytest.mark.parametrize("share", [0.0, 1.0])
def test_the_tracker_predicts_a_one_camera_person_across_the_ray_only_when_asked(share):
    moved, ray, across = _one_camera_walker({"predict_along_ray": share})
    assert moved @ across == pytest.approx(0.05, abs=1e-9)
    assert moved @ ray == pytest.approx(0.08 * share, abs=1e-9)


def test_each_person_keeps_their_own_share_along_the_ray():
    scene = one_camera_scene()
    cam = scene.cameras["cam"]
    xy = np.array([[-1.0, 1.5], [0.5, 3.0]])
    v = np.array([[0.4, 1.2], [-0.8, 0.3]])
    out = predicted_places(xy, v, 0.1, [cam], np.zeros(2, int), np.array([True, True]), np.array([0.25, 1.0]))
    ray = cam.floor_rays(xy, min_distance=0.3)[0]
    along = np.sum((out - xy) / 0.1 * ray, axis=1)
    np.testing.assert_allclose(along, [0.25, 1.0] * np.sum(v * ray, axis=1), atol=1e-12)


def _seen(p, t, own_share):
    p.own_share = own_share
    p.mark_seen(t, ("cam",))


def test_the_measured_share_is_the_velocitys_average_of_observed_frames():
    p = Person(1, 0.0, 0.0, mode="tracking")
    m = MeasuredShare(0.5)
    assert m.shares([p]).tolist() == [1.0]                  # not counted yet: the full velocity
    for t in (0.1, 0.2, 0.3):                               # depth not observed three frames
        m.update([p], t, np.array([False]))
        m.update([p], t, np.array([False]))                 # once per time stamp
    assert m.shares([p])[0] == pytest.approx(0.125)
    m.update([p], 0.4, np.array([True]))                    # observed again: back up by a
    assert m.shares([p])[0] == pytest.approx(0.5625)


def test_depth_counts_as_observed_where_a_camera_that_showed_them_sees_their_feet():
    scene = one_camera_scene()
    rng = np.random.default_rng(0)
    tracker = EllipsoidTracker(scene, make_foregrounds(scene, noise_backgrounds(scene, rng), "colour"))
    view = tracker.views["cam"]
    near = np.array([-1.0, 1.0])
    far = near + 1.2 * view.camera.floor_rays(near, min_distance=0.3)[0]     # right behind, on the same ray
    people = [Person(k, *xy, mode="tracking") for k, xy in enumerate([near, far, [0.3, 1.5]], 1)]
    for p in people:
        _seen(p, 0.1, 0.3)
    assert depth_observed(people, [], [view], 0.1).tolist() == [True, False, True]
    assert depth_observed(people[1:], people[:1], [view], 0.1).tolist() == [False, True]  # others cover too
    assert depth_observed(people, [], [view], 0.2).tolist() == [False] * 3   # nobody showed them at 0.2


@pytest.mark.parametrize("measured", [False, True])
def test_the_tracker_damps_along_the_ray_by_the_measured_share_only_when_asked(measured):
    def half_a_slide(tracker, person):   # half the velocity is a slide
        tracker.measured_share.update([person], 0.0, np.array([False]))

    moved, ray, across = _one_camera_walker({"predict_along_ray_measured": measured}, half_a_slide)
    assert moved @ across == pytest.approx(0.05, abs=1e-9)
    assert moved @ ray == pytest.approx(0.08 * (0.5 if measured else 1.0), abs=1e-9)


@pytest.mark.parametrize("hold, observed, lone", [(True, False, True), (True, True, True), (False, False, True),
                                                  (True, False, False)])
def test_an_unobserved_frame_does_not_change_the_velocity_along_the_ray_with_hold(hold, observed, lone):
    p = Person(1, 0.0, 0.0, mode="tracking", vx=0.3, vy=0.0)
    ray = np.array([[0.6, 0.8]])
    m = MeasuredShare(0.5, hold=hold)
    m.update([p], 0.1, np.array([True]), ray)               # the velocity measured with the feet in view
    p.vx, p.vy = 0.3 + 1.2 * 0.6 - 0.5 * 0.8, 1.2 * 0.8 + 0.5 * 0.6   # the next move: a slide along, a step across
    m.update([p], 0.2, np.array([observed]), ray if lone else np.full((1, 2), np.nan))
    v, before = np.array([p.vx, p.vy]), np.array([0.3, 0.0])
    across = np.array([-0.8, 0.6])
    assert v @ across == pytest.approx(before @ across + 0.5)                 # across the ray: as measured
    held = hold and not observed and lone
    assert v @ ray[0] == pytest.approx(before @ ray[0] + (0.0 if held else 1.2))
    assert m.shares([p])[0] == pytest.approx(1.0 if observed else 0.5)


def test_lone_rays_point_from_the_lone_camera_to_the_person():
    scene = two_camera_scene()
    cams = [scene.cameras["c1"], scene.cameras["c2"]]
    people = [Person(k, -1.0, 1.5, mode="tracking", seen_by=s) for k, s in enumerate([("c2",), ("c1", "c2")], 1)]
    rays = lone_rays(people, cams, ["c1", "c2"])
    np.testing.assert_allclose(rays[0], cams[1].floor_rays(np.array([-1.0, 1.5]), min_distance=0.3)[0])
    assert np.isnan(rays[1]).all()


def test_behind_an_obstacle_depth_counts_as_observed_with_alone_share_only_for_a_person_nobody_overlaps():
    from worldtrack.scene import scene_from_dict
    table = {"type": "box", "name": "table", "centre": [-1.0, 1.0, 0.4], "size": [1.2, 0.6, 0.8]}
    scene = scene_from_dict({
        "cameras": [{"id": "cam", "image_size": [160, 120], "position": [-1.0, -1.74, 2.64],
                     "look_at": [-1.0, 0.9, 0.68], "hfov_deg": 60}],
        "floor": {"walkable": [{"outer": [[-4, -1.5], [2, -1.5], [2, 5], [-4, 5]]}]}, "obstacles": [table]})
    view = EllipsoidTracker(scene, make_foregrounds(scene, noise_backgrounds(scene, np.random.default_rng(0)),
                                                    "colour")).views["cam"]
    alone, crowded = Person(1, -1.0, 2.0, mode="tracking"), Person(2, -1.0, 2.0, mode="tracking")
    _seen(alone, 0.1, 0.9)          # behind the table; nobody covers 90 % of their pixels
    _seen(crowded, 0.1, 0.5)        # the same place, half covered by others
    assert depth_observed([alone, crowded], [], [view], 0.1).tolist() == [False, False]
    assert depth_observed([alone, crowded], [], [view], 0.1, alone_share=0.75).tolist() == [True, False]
    for share, kept in ((MeasuredShare(0.5), 0.5), (MeasuredShare(0.5, alone_share=0.75), 1.0)):
        walker = Person(3, -1.0, 2.0, mode="tracking")   # counted once per time stamp: a fresh one each
        _seen(walker, 0.1, 0.9)
        share.observe([walker], [walker], {"cam": view}, ["cam"], 0.1)   # the share the tracker keeps
        assert share.shares([walker]).tolist() == [kept]


@pytest.mark.parametrize("on", [False, True])
def test_the_tracker_reads_alone_behind_obstacles_as_one_minus_the_duplicate_share(on):
    config = EllipsoidConfig(crowd={"predict_along_ray_measured": True, "alone_behind_obstacles": on},
                             support={"min_own_share": 0.3})
    share = MeasuredShare.from_config(config)
    assert share.alone_share == (pytest.approx(0.7) if on else None)
    assert share.smoothing == config.match.velocity_smoothing and share.hold is False
