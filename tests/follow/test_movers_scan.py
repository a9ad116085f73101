"""People's velocities in the robot's speed limit, the simulated range scanner, and who caused a contact."""

from types import SimpleNamespace

import numpy as np
import pytest

from worldtrack.follow import PIDFollower
from worldtrack.follow.loop import Robot, _collision, camera_pose
from worldtrack.follow.movers import moving_speed_limit
from worldtrack.follow.scan import ScanMovers, segments, simulate_scan
from worldtrack.geometry.camera import Camera

NOBODY = np.zeros((0, 2))


def test_a_standing_person_gives_the_braking_limit():
    # 1.5 m ahead, clearance 0.7: v·0.1 + v²/2.4 <= 0.8 -> v <= 1.27; on the 0.1 m/s grid 1.2
    v = moving_speed_limit((0, 0), 0.0, 0.0, [[1.5, 0.0]], [[0.0, 0.0]])
    assert v == pytest.approx(1.2, abs=0.11)
    assert moving_speed_limit((0, 0), 0.0, 0.0, NOBODY, NOBODY) == 1.6
    assert moving_speed_limit((0, 0), 0.0, 0.0, [[0.6, 0.0]], [[0.0, 0.0]]) == 0.0   # already too near ahead


def test_walking_away_or_out_of_the_path_does_not_hold_the_robot():
    standing = moving_speed_limit((0, 0), 0.0, 0.0, [[1.0, 0.1]], [[0.0, 0.0]])
    ahead = moving_speed_limit((0, 0), 0.0, 0.0, [[1.0, 0.1]], [[1.0, 0.0]])      # cut in, walking our way
    leaving = moving_speed_limit((0, 0), 0.0, 0.0, [[1.0, -0.3]], [[0.0, -1.2]])  # crossing out of the path
    assert standing <= 0.7                     # v·0.1 + v²/2.4 <= 0.3
    assert ahead >= 1.2 and leaving >= standing + 0.5


def test_a_walker_closing_on_a_steady_bearing_outside_the_view_slows_the_robot():
    # 45° off the heading, 1.4 m away, walking at the point the robot reaches in 1 s: a collision course.
    # As a standing person they would not be in the path at all.
    p = np.array([[1.0, 1.0]])
    closing = moving_speed_limit((0, 0), 0.0, 0.0, p, [[0.0, -1.0]])
    assert moving_speed_limit((0, 0), 0.0, 0.0, p, [[0.0, 0.0]]) == 1.6
    assert closing <= 0.8                      # it stops 0.3 m on, 0.7 m short of where they cross


def test_somebody_walking_at_a_standing_robot_is_not_its_to_avoid():
    # from behind, 0.9 m, at 1 m/s: the robot that drives on gets away; the check ends when it stands
    assert moving_speed_limit((0, 0), 0.0, 0.0, [[-0.9, 0.0]], [[1.0, 0.0]]) == 1.6


def test_the_scan_hits_people_and_walls_where_they_are():
    wall = lambda xy: 2.0 - np.asarray(xy)[:, 0]                          # noqa: E731  a wall at x = 2
    hits = simulate_scan((0.0, 0.0), 0.0, NOBODY, np.zeros(0), wall, fov_deg=90, step_deg=45, noise=0.0)
    np.testing.assert_allclose(hits, [[2.0, -2.0], [2.0, 0.0], [2.0, 2.0]], atol=0.03)
    person = simulate_scan((0.0, 0.0), 0.0, [[1.0, 0.0]], [0.25], wall, fov_deg=2, step_deg=1, noise=0.0)
    np.testing.assert_allclose(person[1], [0.75, 0.0], atol=1e-9)         # the body's near side
    far = simulate_scan((0.0, 0.0), np.pi, NOBODY, np.zeros(0), wall, fov_deg=10, noise=0.0)
    assert len(far) == 0                                                  # nothing within 4 m behind


def test_segments_keep_people_and_drop_walls_and_movers_learn_velocity():
    open_floor = lambda xy: np.full(len(xy), 9.0)                          # noqa: E731
    people = np.array([[1.5, 0.8], [1.5, -0.8]])
    hits = simulate_scan((0.0, 0.0), 0.0, people, [0.2, 0.2], open_floor, noise=0.0)
    found = segments(hits, origin=(0.0, 0.0))
    assert len(found) == 2
    assert np.hypot(*(found[np.argsort(found[:, 1])] - people[::-1]).T).max() < 0.06
    wall = lambda xy: 1.0 - np.asarray(xy)[:, 1]                          # noqa: E731  a wall along y = 1
    assert len(segments(simulate_scan((0.0, 0.0), 0.0, NOBODY, np.zeros(0), wall, noise=0.0))) == 0
    movers = ScanMovers()
    rng = np.random.default_rng(0)
    for k in range(15):
        xy = np.array([[2.0, -1.5 + 0.1 * k]])                            # walking +y at 1 m/s
        centres, velocity = movers.update(segments(simulate_scan((0.0, 0.0), 0.0, xy, [0.2], open_floor, rng=rng),
                                                   origin=(0.0, 0.0)), 0.1 * k)
    np.testing.assert_allclose(velocity[0], [0.0, 1.0], atol=0.15)


def camera(x, y, yaw):
    R, t = camera_pose(Robot(x, y, yaw), 1.1)
    return Camera.look_at("robot", 160, 120, position=(0, 0, 1.1), target=(1, 0, 1.1), hfov_deg=66).moved(R, t)


def test_the_pid_slows_for_a_walker_only_its_scan_sees():
    # the robot at (0, 0) heading east, the target 1.9 m ahead walking east; a walker 45° off the heading,
    # never in the camera's 66° view, walking across the robot's path 1 m ahead
    open_floor = lambda xy: np.full(len(xy), 9.0)                          # noqa: E731
    target = np.array([0.1 + 1.9, 0.0])
    step = SimpleNamespace(t=0.0, found=True, xy=target, velocity=np.array([1.0, 0.0]), chosen=0,
                           candidates=SimpleNamespace(xy=target[None]), others_xy=NOBODY, others_velocity=NOBODY)
    follower = PIDFollower(depth_stop=True, walkers=True)
    follower.command(step, camera(-0.1, 0.0, 0.0), 0.0)
    blind, _ = follower.command(step, camera(0.0, 0.0, 0.0), 0.1)
    scanning = PIDFollower(depth_stop=True, walkers=True)
    for k in range(6):                                                    # the robot stands, the walker comes
        walker = np.array([[1.0, 1.5 - 0.1 * k]])
        scan = simulate_scan((-0.1, 0.0), 0.0, walker, [0.2], open_floor, noise=0.0)
        v, _ = scanning.command(step, camera(0.0, 0.0, 0.0), 0.1 * k, scan=scan)
    assert blind >= 1.0
    assert v <= 0.8 and scanning.blocked


def test_who_caused_a_contact():
    robot = Robot(0.0, 0.0, 0.0, v=0.0)
    step = SimpleNamespace(candidates=SimpleNamespace(xy=NOBODY), others_xy=NOBODY, xy=np.array([3.0, 0.0]))
    walked = _collision(5, 2, np.array([0.45, 0.0]), robot, np.array([-0.8, 0.0]), 0.0, step, False)
    assert walked.cause == "walked into the robot" and not walked.robot_fault
    still = _collision(5, 2, np.array([0.0, 0.45]), robot, np.zeros(2), 0.0, step, False)
    assert still.cause == "side by side" and not still.robot_fault
    driving = Robot(0.0, 0.0, 0.0, v=0.6)
    unseen = _collision(5, 2, np.array([0.3, 0.35]), driving, np.array([0.3, 0.0]), 0.1, step, False)
    assert unseen.cause == "unseen" and unseen.robot_fault
    seen = _collision(5, 2, np.array([0.45, 0.0]), driving, np.zeros(2), 0.6, step, False)
    assert seen.cause == "seen, not stopped" and seen.robot_fault
