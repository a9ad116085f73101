"""The local planner: catch-up, people's velocities, the depth safety layer, and the way round an obstacle."""

from types import SimpleNamespace

import numpy as np
import pytest

from worldtrack.follow.loop import Robot, camera_pose
from worldtrack.follow.navigation import NavigationGrid
from worldtrack.follow.planner import LocalPlanner, _blocks_view
from worldtrack.follow.safety import free_path, near_points
from worldtrack.geometry.camera import Camera
from worldtrack.synth import make_scenario


@pytest.fixture(scope="module")
def scene():
    return make_scenario("follow-target", size=(160, 120), frames=2, seed=0, others=0).scene


def camera(x, y, yaw):
    """The robot's camera for a robot at (x, y) heading ``yaw`` (rad), as the closed loop makes it."""
    R, t = camera_pose(Robot(x, y, yaw), 1.1)
    return Camera.look_at("robot", 160, 120, position=(0, 0, 1.1), target=(1, 0, 1.1), hfov_deg=66).moved(R, t)


def step(t, xy, velocity=(0.0, 0.0), found=True, others=(), others_velocity=()):
    xy = np.asarray(xy, float)
    return SimpleNamespace(t=t, found=found, xy=xy, velocity=np.asarray(velocity, float), measured=xy,
                           candidates=SimpleNamespace(xy=xy[None] if found else np.zeros((0, 2))),
                           others_xy=np.asarray(others, float).reshape(-1, 2),
                           others_velocity=np.asarray(others_velocity, float).reshape(-1, 2))


def moving(planner, x, y, speed, target, target_velocity, **kw):
    """The planner's command after one frame in which the robot drove east at ``speed`` (odometry)."""
    planner.command(step(0.0, np.asarray(target) - [0.1 * target_velocity[0], 0.0], target_velocity, **kw),
                    camera(x - 0.1 * speed, y, 0.0), 0.0)
    return planner.command(step(0.1, target, target_velocity, **kw), camera(x, y, 0.0), 0.1)


def test_catches_up_faster_than_the_target_and_then_matches_its_speed(scene):
    # open floor along y = 4 (the bench is at y = 6, walls at y = 1)
    v, w = moving(LocalPlanner(scene), 4.0, 4.0, 1.1, (4.1 + 2.8, 4.0), (1.1, 0.0))
    assert v >= 1.4 and abs(w) < 0.2                 # 1 m behind: faster than the target's 1.1 m/s
    v, w = moving(LocalPlanner(scene), 4.0, 4.0, 1.1, (4.1 + 1.8, 4.0), (1.1, 0.0))
    assert v == pytest.approx(1.1, abs=0.2)          # at the set distance: the target's speed


def test_a_crosser_leaving_the_path_lets_the_robot_go_on_one_standing_holds_it(scene):
    target = (4.1 + 2.6, 4.0)
    leaving = LocalPlanner(scene)
    v_leaving, _ = moving(leaving, 4.0, 4.0, 1.0, target, (1.0, 0.0), others=[(5.0, 4.2)],
                          others_velocity=[(0.0, 1.2)])
    standing = LocalPlanner(scene)
    v_standing, _ = moving(standing, 4.0, 4.0, 1.0, target, (1.0, 0.0), others=[(5.0, 4.2)],
                           others_velocity=[(0.0, 0.0)])
    assert v_leaving > 1.2 and not leaving.blocked
    assert v_standing < v_leaving - 0.3 and standing.blocked


def test_a_person_the_detector_missed_stops_the_robot_by_depth_alone(scene):
    cam = camera(4.0, 4.0, 0.0)
    depth = np.zeros((120, 160), np.float32)
    depth[20:100, 60:100] = 0.55                      # something 0.55 m in front of the camera, no candidate
    target = (4.1 + 2.8, 4.0)
    blind = LocalPlanner(scene)
    v_blind, _ = blind.command(step(0.0, target), cam, 0.0)
    seeing = LocalPlanner(scene)
    v_seeing, _ = seeing.command(step(0.0, target), cam, 0.0, frame=SimpleNamespace(depth=depth))
    assert v_blind > 0.5                              # without the depth it would drive on
    assert v_seeing < 0.1 and seeing.blocked          # at most creeps while it turns away


def test_a_target_lost_behind_the_kiosk_is_looked_for_round_it(scene):
    # the kiosk spans x 11.75-13.25, y 8.25-9.75; the robot faces it from the south, the target was
    # last seen walking behind it and is predicted at (12.5, 10.8)
    planner = LocalPlanner(scene)
    nav = NavigationGrid(scene)
    robot = Robot(12.5, 7.4, np.pi / 2)
    goal = np.array([12.5, 10.8])
    planner.command(step(0.0, goal), camera(robot.x, robot.y, robot.yaw), 0.0)
    clearance = []
    for k in range(1, 120):
        t = 0.1 * k
        cam = camera(robot.x, robot.y, robot.yaw)
        v, w = planner.command(step(t, goal, found=False), cam, t)
        robot.drive(v, w, 0.1, nav.clearance)
        clearance.append(nav.clearance([[robot.x, robot.y]])[0])
    cam = camera(robot.x, robot.y, robot.yaw)
    assert min(clearance) > 0.35                      # never touched the kiosk (robot radius 0.3)
    assert nav.line_of_sight(cam.centre[:2][None], goal)[0]          # went round: it sees the spot
    assert np.hypot(*(cam.centre[:2] - goal)) < 1.5


def test_sight_line_blocking_and_the_free_path():
    cams = np.array([[0.0, 0.0], [0.0, 1.0]])
    blocked = _blocks_view(cams, np.array([3.0, 0.0]), np.array([[1.5, 0.1]]))
    assert blocked.tolist() == [1.0, 0.0]             # in the line from the first camera only
    path = np.column_stack([np.linspace(0.0, 2.0, 21), np.zeros(21)])
    assert free_path(path, np.array([[1.5, 0.0]]), 0.35) == pytest.approx(1.15, abs=0.01)
    assert free_path(path, np.array([[1.5, 1.0]]), 0.35) == np.inf


def test_a_lone_stereo_mismatch_is_not_an_obstacle():
    cam = Camera.look_at("robot", 160, 120, position=(0, 0, 1.1), target=(1, 0, 1.1), hfov_deg=66)
    depth = np.zeros((120, 160), np.float32)
    depth[60, 80] = 1.0                               # one pixel
    assert len(near_points(depth, cam)) == 0
    depth[50:70, 75:85] = 1.0                         # a surface
    assert len(near_points(depth, cam)) > 0


def test_the_pid_with_the_depth_stop_stops_for_what_the_detector_missed():
    from worldtrack.follow import PIDFollower
    cam = Camera.look_at("robot", 160, 120, position=(0, 0, 1.1), target=(1, 0, 1.1), hfov_deg=66)
    depth = np.zeros((120, 160), np.float32)
    depth[20:100, 60:100] = 0.55
    st = SimpleNamespace(found=True, xy=np.array([3.5, 0.0]), velocity=np.zeros(2), chosen=0,
                         candidates=SimpleNamespace(xy=np.array([[3.5, 0.0]])), others_xy=np.zeros((0, 2)))
    frame = SimpleNamespace(depth=depth)
    v_paper, _ = PIDFollower().command(st, cam, 0.0, frame=frame)
    stopping = PIDFollower(depth_stop=True)
    v_safe, _ = stopping.command(st, cam, 0.0, frame=frame)
    # 0.55 m ahead of the camera, 0.65 m from the robot's centre: 0.3 m before the body (0.35 m) touches,
    # so at most √(2·1.2·0.3) − 1.2·0.1 = 0.73 m/s, the speed it can still stop from
    assert v_paper > 1.0 and 0.6 < v_safe < 0.8 and stopping.blocked
