"""Motion: random walkers' constraints, scripted paths, gait phase tied to speed, entries."""

import numpy as np
import pytest

from worldtrack.synth import make_scenario
from worldtrack.synth.joints import stride_length
from worldtrack.synth.motion import Waypoint, finish_track, scripted_track


@pytest.fixture(scope="module")
def crowd50():
    return make_scenario("crowd", people=50, cameras=1, frames=120, seed=2, size=(64, 48))


def test_walkers_stay_on_the_floor_and_off_obstacles(crowd50):
    sc = crowd50
    df = sc.scene.distance_field(0.05)
    xy = np.concatenate([p.track.xy for p in sc.people])
    assert np.all(sc.scene.walkable.contains(xy))
    assert df.sample(xy, outside=-1.0).min() >= 0.3 - 0.03       # clearance, up to the grid's interpolation
    for ob in sc.scene.obstacles:                                # no centre within 0.25 m of a footprint
        fp = ob.footprint                                        # (axis-aligned boxes in this hall)
        centre, half = (fp.min(axis=0) + fp.max(axis=0)) / 2, (fp.max(axis=0) - fp.min(axis=0)) / 2
        gap = np.linalg.norm(np.maximum(np.abs(xy - centre) - half, 0.0), axis=1)
        assert gap.min() >= 0.25, ob.name


def test_walkers_keep_their_distance_move_and_sometimes_stop(crowd50):
    sc = crowd50
    xy = np.stack([p.track.xy for p in sc.people], axis=1)       # (T, N, 2)
    d = np.linalg.norm(xy[:, :, None] - xy[:, None, :], axis=3)
    d[:, np.arange(50), np.arange(50)] = np.inf
    assert d.min() >= 0.6 - 1e-9
    path = np.linalg.norm(np.diff(xy, axis=0), axis=2).sum(axis=0)
    assert np.median(path) > 2.5          # 12 s at ~1 m/s, minus waits and crowding (0.6 people/m²)
    speed = np.stack([p.track.speed for p in sc.people])
    assert np.any(speed == 0.0) and speed.max() < 2.0


def test_scripted_path_dwells_exactly_with_zero_speed():
    route = [Waypoint(0, 0, dwell=1.0), Waypoint(2, 0, speed=1.0, dwell=2.0), Waypoint(2, 2, speed=0.5)]
    tr = scripted_track(route, 10.0, 120, 1.7)
    at = np.all(tr.xy == [2.0, 0.0], axis=1)
    assert 19 <= at.sum() <= 21
    inner = np.flatnonzero(at)[1:-1]
    assert np.all(tr.speed[inner] == 0.0) and np.all(tr.amplitude[inner] == 0.0)
    assert np.all(tr.speed <= 1.0 + 1e-9)
    assert np.allclose(tr.xy[-1], [2.0, 2.0])
    moving = tr.speed > 0.95
    assert moving.sum() > 5


def test_gait_phase_advances_with_speed_and_stops_when_standing():
    fps, H = 10.0, 1.8
    x = np.concatenate([np.zeros(10), np.cumsum(np.full(30, 1.2 / fps)), np.full(10, 3.6)])
    tr = finish_track(np.column_stack([x, np.zeros_like(x)]), fps, H)
    dphi = np.diff(tr.phase)
    assert np.all(dphi[:8] == 0) and np.all(dphi[-8:] == 0)
    walking = slice(15, 35)
    expected = 2 * np.pi * 1.2 / fps / stride_length(H, 1.2)
    np.testing.assert_allclose(dphi[walking], expected, rtol=1e-6)
    assert np.all(tr.amplitude[:8] == 0) and tr.amplitude[20] > 0.8


def test_entry_pairs_come_in_side_by_side_then_split_and_leave():
    sc = make_scenario("entry", pairs=2, singles=1, seed=0, size=(64, 48))
    door = sc.scene.entry_regions[0]
    p1, p2 = sc.people[0].track, sc.people[1].track
    first = np.flatnonzero(p1.present)[0]
    assert first == np.flatnonzero(p2.present)[0] and first > 0   # appear together, not at t = 0
    assert door.contains(p1.xy[first:first + 1])[0]
    together = np.flatnonzero(p1.present & p2.present)[:15]
    np.testing.assert_allclose(np.linalg.norm(p1.xy[together] - p2.xy[together], axis=1), 0.5, atol=1e-6)
    both = p1.present & p2.present
    assert np.linalg.norm(p1.xy[both] - p2.xy[both], axis=1).max() > 2.0   # split up
    for p in sc.people:                                                   # everybody leaves again
        assert p.track.present.any() and not p.track.present[-1]
        last = np.flatnonzero(p.track.present)[-1]
        assert any(r.contains(p.track.xy[last:last + 1])[0] for r in sc.scene.entry_regions)


def test_robot_follows_the_target():
    sc = make_scenario("follow-target", frames=150, seed=0, size=(64, 48))
    target = sc.people[0].track
    centres = np.array([sc.camera_at("robot", k).centre[:2] for k in range(sc.n_frames)])
    d = np.linalg.norm(centres - target.xy, axis=1)
    assert np.median(d[50:]) == pytest.approx(1.9, abs=0.5)
    assert np.all(sc.scene.walkable.contains(centres))
