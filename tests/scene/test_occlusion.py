"""Obstacle depth maps: hidden behind a desk, visible above it."""

import numpy as np

from worldtrack.geometry.camera import Camera
from worldtrack.scene.model import Box, Patch
from worldtrack.scene.occlusion import OcclusionMap


def desk_setup():
    cam = Camera.look_at("c", 320, 240, position=(0, -3, 2.5), target=(0, 1, 0.5), hfov_deg=60)
    desk = Box("desk", np.array([0, 0, 0.365]), np.array([1.2, 0.6, 0.73]))
    return cam, desk, OcclusionMap.build(cam, [desk])


def test_pixel_behind_desk_is_hidden_and_one_above_it_is_not():
    cam, desk, occ = desk_setup()
    foot = np.array([[0.0, 0.8, 0.0]])     # the floor just behind the desk: hidden from this camera
    head = np.array([[0.0, 0.8, 1.6]])     # a head above it: visible
    for p, expected in ((foot, True), (head, False)):
        uv = cam.project(p)
        dist = cam.floor_distance(p)
        assert occ.hidden(uv, dist).tolist() == [expected]
        assert occ.hidden(uv, cam.depth(p), true_depth=True).tolist() == [expected]
    # In front of the desk nothing is hidden even where the desk is behind it in the image.
    front = np.array([[0.0, -0.6, 0.3]])
    assert occ.hidden(cam.project(front), cam.floor_distance(front)).tolist() == [False]


def test_depth_map_values_are_the_analytic_distances():
    cam, desk, occ = desk_setup()
    # The desk top centre: a known point on the surface.
    p = np.array([[0.0, 0.0, 0.73]])
    uv = np.round(cam.project(p)).astype(int)[0]
    # The ray through the rounded pixel hits the top within a pixel of p.
    o, d = cam.rays(uv[None].astype(float))
    s = (0.73 - o[2]) / d[0, 2]
    hit = o + s * d[0]
    assert abs(occ.depth[uv[1], uv[0]] - float(cam.depth(hit))) < 1e-5
    assert abs(occ.floor_distance[uv[1], uv[0]] - np.hypot(hit[0] - o[0], hit[1] - o[1])) < 1e-5
    # Pixels that see only floor hold inf.
    assert np.isinf(occ.depth[5, 5])


def test_patch_occludes_like_its_rectangle():
    cam = Camera.look_at("c", 160, 120, position=(0, -3, 1.5), target=(0, 0, 1.0), hfov_deg=60)
    screen = Patch("partition", np.array([[-0.5, 0, 0], [0.5, 0, 0], [0.5, 0, 1.2], [-0.5, 0, 1.2]], float))
    occ = OcclusionMap.build(cam, [screen])
    behind_low = np.array([[0.0, 1.0, 0.5]])
    behind_high = np.array([[0.0, 1.0, 1.9]])
    assert occ.hidden(cam.project(behind_low), cam.floor_distance(behind_low))[0]
    assert not occ.hidden(cam.project(behind_high), cam.floor_distance(behind_high))[0]
