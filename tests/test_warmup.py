"""The kernel warm-up: one line saying what it did, and the tiny scene it tracks is a real scene."""

import io

from worldtrack.warmup import _frames, _tiny_scene, say_warm_up, warm_up


def test_warm_up_says_one_line_with_its_time():
    out = io.StringIO()
    seconds = say_warm_up("blobs", stream=out)
    lines = out.getvalue().splitlines()
    assert len(lines) == 1 and lines[0].startswith("kernels: ") and f"{seconds:.1f} s" in lines[0]


def test_the_tiny_scene_shows_people_to_both_cameras():
    scene = _tiny_scene()
    backgrounds, frames = _frames(scene)
    assert set(backgrounds) == set(scene.cameras) == {"cam1", "cam2"}
    for bundle in frames:
        for cid, img in bundle.items():
            changed = (img != backgrounds[cid]).any(axis=2).mean()
            assert 0.001 < changed < 0.5, cid          # people in view, not the whole image


def test_warm_up_runs_the_ellipsoid_tracker_to_tracks():
    seconds, compiled = warm_up("ellipsoid")
    assert seconds > 0 and compiled >= 0


def test_the_people_put_on_the_map_stand_on_the_floor_one_with_hidden_feet():
    import cv2
    import numpy as np

    from worldtrack.warmup import _ON_FLOOR_AT_START, _PEOPLE

    scene = _tiny_scene()
    starts = np.array([_PEOPLE[n][0] for n in _ON_FLOOR_AT_START])
    assert scene.walkable.contains(starts).all()
    desk = scene.obstacles[0]
    for cam in scene.cameras.values():
        hull = cv2.convexHull(cam.project(desk.corners).astype(np.float32))
        feet = cam.project(np.column_stack([starts, np.zeros(len(starts))]))
        hidden = [cv2.pointPolygonTest(hull, (float(u), float(v)), False) > 0 for u, v in feet]
        assert hidden == [False, False, True], cam.id     # the crossing pair in view, the third behind the desk
