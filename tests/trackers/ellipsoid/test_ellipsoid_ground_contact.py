"""Whether one camera sees each person's feet (:mod:`worldtrack.trackers.ellipsoid.ground_contact`)."""

import numpy as np
from _ellipsoid_scenes import noise_backgrounds

from worldtrack.foreground import make_foregrounds
from worldtrack.scene import scene_from_dict
from worldtrack.trackers.ellipsoid import EllipsoidTracker
from worldtrack.trackers.ellipsoid.ground_contact import feet_in_view


def _view(obstacles=()):
    scene = scene_from_dict({
        "cameras": [{"id": "cam", "image_size": [160, 120], "position": [-1.0, -1.74, 2.64],
                     "look_at": [-1.0, 0.9, 0.68], "hfov_deg": 60}],
        "floor": {"walkable": [{"outer": [[-4, -1.5], [2, -1.5], [2, 5], [-4, 5]]}]},
        "obstacles": list(obstacles)})
    fgs = make_foregrounds(scene, noise_backgrounds(scene, np.random.default_rng(0)), "colour")
    return EllipsoidTracker(scene, fgs).views["cam"]


def _sizes(n):
    return np.full(n, 1.7), np.full(n, 0.45)


def test_the_nearer_person_covers_the_feet_of_the_one_behind_not_the_other_way():
    view = _view()
    near = np.array([-1.0, 1.0])
    behind = near + 1.0 * view.camera.floor_rays(near, min_distance=0.3)[0]
    assert feet_in_view(view, np.array([near, behind]), *_sizes(2)).tolist() == [True, False]
    assert feet_in_view(view, np.array([behind, near]), *_sizes(2)).tolist() == [False, True]
    assert feet_in_view(view, behind[None], *_sizes(1)).tolist() == [True]      # alone: seen


def test_a_table_in_front_hides_the_feet_and_a_person_out_of_the_image_has_none_seen():
    table = {"type": "box", "name": "table", "centre": [-1.0, 1.0, 0.4], "size": [1.2, 0.6, 0.8]}
    xy = np.array([[-1.0, 2.0], [0.3, 0.5], [30.0, 0.0]])       # behind the table, beside it, far out
    assert feet_in_view(_view(), xy[:2], *_sizes(2)).tolist() == [True, True]
    assert feet_in_view(_view([table]), xy, *_sizes(3)).tolist() == [False, True, False]


def test_without_obstacles_only_the_image_edge_and_people_hide_the_feet():
    table = {"type": "box", "name": "table", "centre": [-1.0, 1.0, 0.4], "size": [1.2, 0.6, 0.8]}
    view = _view([table])
    xy = np.array([[-1.0, 2.0], [30.0, 0.0]])                  # behind the table, far out of the image
    assert feet_in_view(view, xy, *_sizes(2), obstacles=False).tolist() == [True, False]
    near = np.array([-1.0, 0.2])                               # somebody in front of the one behind the table
    behind = near + 1.8 * view.camera.floor_rays(near, min_distance=0.3)[0]
    assert feet_in_view(view, np.array([near, behind]), *_sizes(2), obstacles=False).tolist() == [True, False]
