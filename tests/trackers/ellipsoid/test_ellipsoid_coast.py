"""A track behind a pillar coasts instead of ending as "left the view"
(``crowd.coast_behind_obstacles_s``, :mod:`worldtrack.trackers.ellipsoid.coast`)."""

import numpy as np
import pytest

from worldtrack.foreground import make_foregrounds
from worldtrack.scene import scene_from_dict
from worldtrack.trackers.base import Frame
from worldtrack.trackers.ellipsoid import EllipsoidConfig, EllipsoidTracker
from worldtrack.trackers.ellipsoid.coast import behind_obstacles


def pillar_scene(pillar_height=3.0):
    return scene_from_dict({
        "cameras": [{"id": "c", "image_size": [160, 120], "position": [0, -4, 2.6], "look_at": [0, 0, 0.8],
                     "hfov_deg": 60}],
        "floor": {"walkable": [{"outer": [[-4, -3], [4, -3], [4, 5], [-4, 5]]}]},
        "obstacles": [{"type": "box", "name": "pillar", "centre": [0, 0, pillar_height / 2],
                       "size": [0.6, 0.6, pillar_height]}]})


def test_a_body_is_behind_obstacles_only_when_every_point_in_view_is_hidden():
    scene = pillar_scene()
    cams = list(scene.cameras.values())
    xy = np.array([[0.0, 1.5], [0.0, -1.0], [0.6, 1.5], [30.0, 0.0]])   # behind, in front, beside, out of view
    assert behind_obstacles(xy, np.full(4, 1.7), cams, scene.occlusion).tolist() == [True, False, False, False]
    # Head above the image's top, the rest behind the pillar: behind (what the image holds is hidden).
    assert behind_obstacles(xy[:1], np.array([3.0]), cams, scene.occlusion)[0]
    low = pillar_scene(pillar_height=1.3)                                # a cupboard: the head shows above it
    assert not behind_obstacles(xy[:1], np.array([1.7]), list(low.cameras.values()), low.occlusion)[0]


def run_unseen(x, y, coast_s, frames=25):
    """Frames (0.1 s apart) the track of a person put at (x, y) lasts on empty frames."""
    scene = pillar_scene()
    rng = np.random.default_rng(1)
    bg = rng.integers(70, 150, (120, 160, 3), dtype=np.uint8)
    tracker = EllipsoidTracker(scene, make_foregrounds(scene, {"c": bg}, "colour"),
                               EllipsoidConfig(crowd={"coast_behind_obstacles_s": coast_s}, warm_start={"frames": 0}))
    tid = tracker.init_track(x, y).id
    for i in range(frames):
        image = np.clip(bg + rng.normal(0, 3, bg.shape), 0, 255).astype(np.uint8)
        tracker.step({"c": Frame(image, i / 10, i)}, i / 10)
        if tid not in tracker.position_map:
            return i
    return frames


@pytest.mark.parametrize("coast_s, lasts", [(0.0, 1), (1.0, 9), (2.0, 19)])
def test_a_track_behind_the_pillar_is_kept_as_long_as_asked(coast_s, lasts):
    assert run_unseen(0.0, 1.5, coast_s) == lasts


def test_a_track_out_of_the_image_ends_as_before():
    assert run_unseen(30.0, 0.0, 2.0) == run_unseen(30.0, 0.0, 0.0) == 1
