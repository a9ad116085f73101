"""A person drawn as a body and a head (:mod:`.head_body`): exact geometry."""

import numpy as np

from worldtrack.geometry.camera import Camera
from worldtrack.trackers.ellipsoid.args import DrawArgs, camera_args
from worldtrack.trackers.ellipsoid.head_body import (HEAD_WIDTH_M, SampledWindow, lifted, person_masks,
                                                     window_score)

CAM = Camera.look_at("c", 640, 480, [0.0, 0.0, 2.8], [0.0, 6.0, 0.9], hfov_deg=62.0)
ARGS = camera_args(CAM, 10.0)
DRAW = DrawArgs(0.1, 0.0)


def _window(points: np.ndarray, occ: float = np.inf) -> SampledWindow:
    """A 'window' of the pixels the 3-D ``points`` (N, 3) project to."""
    uv = CAM.project(points)
    return SampledWindow(uv[:, 0], uv[:, 1], np.ones(len(uv), np.int8), np.full(len(uv), occ))


def test_a_lifted_camera_sees_its_floor_where_the_real_one_sees_that_height():
    up = lifted(ARGS, 1.3)
    for x in ([0.5, 5.0, 0.0], [-1.0, 7.0, 0.4]):
        a = ARGS.P @ np.array([x[0], x[1], x[2] + 1.3, 1.0])
        b = up.P @ np.array([x[0], x[1], x[2], 1.0])
        assert np.allclose(a, b)
    assert np.array_equal(ARGS.P, camera_args(CAM, 10.0).P)   # the original is not changed


def test_the_head_is_a_head_wide_and_on_top_of_the_body():
    xy, h, w = np.array([0.3, 6.0]), 1.75, 0.45
    side = np.array([1.0, 0.0, 0.0])
    top = np.array([xy[0], xy[1], h])
    points = np.array([top - [0, 0, 0.03],                         # just under the top: head
                       top + [0, 0, 0.04],                         # above it: nothing
                       top - [0, 0, 0.1] + 0.6 * HEAD_WIDTH_M * side,   # beside the head: nothing
                       top - [0, 0, 0.1] + 0.4 * HEAD_WIDTH_M * side,   # inside the head's width
                       [xy[0], xy[1], 0.9],                        # the body's middle
                       [xy[0] + 0.6 * w, xy[1], 0.9]])             # beside the body
    inside, ring = person_masks(ARGS, _window(points), xy, h, w, DRAW)
    assert inside.tolist() == [True, False, False, True, True, False]
    assert ring[:4].all()                                          # the ring hugs the head
    hidden, _ = person_masks(ARGS, _window(points, occ=3.0), xy, h, w, DRAW)
    assert not hidden.any()                                        # an obstacle 3 m away hides the person at 6 m


def test_the_window_score_is_eq5_with_the_unexplained_foreground():
    real = np.array([1, 1, 1, -1, 0, 1], np.int8)
    inside = np.array([1, 1, 0, 0, 0, 0], bool)
    ring = np.array([1, 1, 0, 1, 1, 0], bool)
    # sim = [1, 1, 0, -1, -1, 0]: num 1 + 1 + 1 = 3; den 4 drawn + 2 foreground nobody explains.
    assert window_score(real, inside, ring) == (3.0, 6.0)
