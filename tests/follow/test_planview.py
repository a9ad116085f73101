"""Plan-view detection and silhouettes: exact positions on hand-made depth images, people on rendered ones."""

import numpy as np
import pytest

from worldtrack.follow import FollowConfig
from worldtrack.follow.planview import back_project, detect
from worldtrack.follow.silhouette import box_silhouettes, covering, silhouettes, upsample_labels
from worldtrack.geometry.camera import Camera

CAM = Camera.look_at("c", 320, 240, position=(0, 0, 1.1), target=(1, 0, 1.1), hfov_deg=66)


def board_depth(boards, cam=CAM):
    """Depth image of vertical boards (x, y, width, height) facing the camera (ray-traced exactly)."""
    v, u = np.mgrid[0:cam.height, 0:cam.width]
    _, d = cam.rays(np.stack([u.ravel(), v.ravel()], axis=1).astype(float))
    depth = np.full(u.size, np.inf)
    o = cam.centre
    for x, y, w, h in boards:
        s = (x - o[0]) / d[:, 0]                   # plane X = x
        hit = o + s[:, None] * d
        ok = (s > 0) & (np.abs(hit[:, 1] - y) <= w / 2) & (hit[:, 2] >= 0) & (hit[:, 2] <= h)
        z = s * (d @ cam.optical_axis)
        depth = np.where(ok & (z < depth), z, depth)
    return np.where(np.isfinite(depth), depth, 0).reshape(cam.height, cam.width).astype(np.float32)


def test_back_projection_puts_points_where_they_are():
    depth = board_depth([(3.0, 0.0, 0.4, 1.7)])
    pts = back_project(depth, CAM, 1, 8.0)
    assert len(pts.xyz) > 1000
    np.testing.assert_allclose(pts.xyz[:, 0], 3.0, atol=1e-6)
    assert pts.xyz[:, 1].min() >= -0.2 - 1e-6 and pts.xyz[:, 1].max() <= 0.2 + 1e-6
    # Visible area: the board is 0.4 m x 1.7 m, all of it in view.
    assert pts.area.sum() == pytest.approx(0.4 * 1.7, rel=0.06)      # ±1 px at the 33 px wide edges


def test_a_board_of_person_size_is_one_candidate_pushed_back_by_the_surface_offset():
    depth = board_depth([(3.0, 0.5, 0.45, 1.75)])
    cands = detect(depth, CAM, FollowConfig())
    assert len(cands) == 1
    offset = FollowConfig().surface_offset
    ray = np.array([3.0, 0.5]) / np.hypot(3.0, 0.5)
    np.testing.assert_allclose(cands.xy[0], np.array([3.0, 0.5]) + offset * ray, atol=0.02)
    assert cands.top[0] == pytest.approx(1.75, abs=0.03)
    assert cands.depth[0] == pytest.approx(3.0, abs=0.01)


def test_two_people_side_by_side_stay_two_and_walls_benches_and_far_things_are_nobody():
    people = [(3.0, -0.3, 0.4, 1.7), (3.0, 0.3, 0.4, 1.8)]                 # 0.6 m apart
    clutter = [(5.0, 2.0, 3.0, 3.5),       # a wall section, taller than a person
               (2.5, -1.2, 1.5, 0.45),     # a bench
               (9.5, 0.0, 0.45, 1.7)]      # a person beyond the stereo range
    cands = detect(board_depth(people + clutter), CAM, FollowConfig())
    assert len(cands) == 2
    np.testing.assert_allclose(np.sort(cands.xy[:, 1]), [-0.3, 0.3], atol=0.05)
    np.testing.assert_allclose(np.sort(cands.top), [1.7, 1.8], atol=0.03)


def test_the_walkable_area_removes_points_of_walls():
    from worldtrack.synth import make_scenario
    sc = make_scenario("follow-target", size=(160, 120), frames=1, seed=0, others=0)
    cam = Camera.look_at("robot", 320, 240, position=(14.0, 6.0, 1.1), target=(16, 6, 1.0), hfov_deg=66)
    depth = board_depth([(16.2, 6.0, 0.45, 1.7)], cam)        # something person-shaped beyond the east wall
    assert len(detect(depth, cam, FollowConfig())) == 1
    assert len(detect(depth, cam, FollowConfig(), sc.scene.distance_field(0.05))) == 0


def test_rendered_people_are_found_within_ten_centimetres(lookalike_cut_in):
    sc, bundles = lookalike_cut_in
    cfg, walk = FollowConfig(), sc.scene.distance_field(0.05)
    errors, missed = [], 0
    for b in bundles[::3]:
        v = b.views["robot"]
        cands = detect(v.sensor_depth, v.camera, cfg, walk)
        for r in b.gt:
            dist = np.hypot(r["x"] - v.camera.centre[0], r["y"] - v.camera.centre[1])
            if r["vis_robot"] < 0.7 or dist > 6:
                continue
            d = np.hypot(*(cands.xy - [r["x"], r["y"]]).T) if len(cands) else np.array([9.0])
            if d.min() < 0.3:
                errors.append(d.min())
            else:
                missed += 1
    assert len(errors) >= 30 and missed <= 1
    assert np.sqrt(np.mean(np.square(errors))) < 0.1


def test_silhouettes_fill_blocks_drop_far_pixels_and_nearer_ones_win():
    labels = np.zeros((3, 4), np.int32)
    labels[1, 1] = 1
    labels[1, 2] = 2
    depth = np.full((6, 8), 3.0, np.float32)
    depth[2:4, 2:4] = 2.0                  # candidate 0 (nearer) at 2 m
    depth[2, 5] = 9.0                       # background seen through candidate 1
    sil = silhouettes(labels, 2, depth, np.array([2.0, 3.0]), depth_tolerance=0.5)
    assert np.all(sil[2:4, 2:4] == 1)
    assert sil[2, 5] == 0 and sil[3, 5] == 2
    np.testing.assert_array_equal(upsample_labels(labels, 2, (6, 8))[2:4, 4:6], 2)


def test_box_silhouettes_and_covering():
    sil = box_silhouettes((100, 100), np.array([[10, 0, 40, 100], [30, 10, 40, 90]], float))
    # the second box reaches as low as the first and is drawn after it: it keeps the overlap
    assert (sil == 2).sum() > (sil == 1).sum() > 0
    cover = covering(sil, 2, (30, 10, 70, 100))
    assert cover[1] > 0.4 and cover.sum() <= 1.0
    np.testing.assert_array_equal(covering(sil, 2, None), [0, 0])
