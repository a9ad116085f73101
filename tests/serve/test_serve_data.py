"""What the page is given: the plan's geometry, a run's timeline, a live state (no browser)."""

from __future__ import annotations

import numpy as np
import pytest

from worldtrack.geometry.camera import Camera
from worldtrack.io.tracks import read_tracks
from worldtrack.map.messages import MapPerson, MapState
from worldtrack.scene.floor import FloorPolygon, WalkableArea, points_in_polygon
from worldtrack.scene.model import Scene
from worldtrack.serve.plan import PlanTransform, cameras_seeing, plan_json
from worldtrack.serve.run import load_run, timeline_json, velocities


@pytest.fixture(scope="module")
def room() -> Scene:
    cam = Camera.look_at("c1", 320, 240, [0.0, 0.0, 3.0], [5.0, 2.0, 0.0], hfov_deg=60)
    floor = WalkableArea((FloorPolygon(np.array([[0.0, -2.0], [10.0, -2.0], [10.0, 6.0], [0.0, 6.0]])),))
    return Scene("room", {"c1": cam}, floor)


def test_coverage_is_the_floor_the_camera_sees(room):
    plan = plan_json(room)
    t = PlanTransform(**plan["transform"])
    rings = [np.array(r) for r in plan["cameras"][0]["coverage"]]
    assert rings
    rng = np.random.default_rng(0)
    xy = rng.uniform([0, -2], [10, 6], (2000, 2))
    uv = t.to_svg(xy)
    inside = np.zeros(len(xy), bool)
    for r in rings:
        inside |= points_in_polygon(uv, r)
    seen = room.cameras["c1"].in_image(room.cameras["c1"].project(np.column_stack([xy, np.zeros(len(xy))])))
    agree = (inside == seen).mean()
    assert agree > 0.98, f"coverage polygon agrees with the projection on {agree:.1%} of floor points"
    # The camera's icon is at its centre, heading along its floor direction (SVG: y down).
    cam = plan["cameras"][0]
    assert np.allclose(cam["at"], t.to_svg(room.cameras["c1"].centre[:2])[0], atol=0.01)
    d = room.cameras["c1"].floor_direction
    assert np.isclose(cam["heading"], np.arctan2(-d[1], d[0]))


def test_velocities_of_a_walk_at_constant_speed():
    t = np.arange(0, 5, 0.1)
    xy = np.column_stack([1.2 * t, -0.5 * t])
    ids = np.ones(len(t), int)
    order = np.random.default_rng(1).permutation(len(t))          # rows in any order
    v = velocities(ids[order], t[order], xy[order])
    assert np.allclose(v, [1.2, -0.5], atol=1e-9)


def test_timeline_of_a_run(finished_run):
    run = load_run(finished_run)
    tl = timeline_json(run)
    table = read_tracks(finished_run / "tracks.csv")
    assert tl["frames"] == list(range(int(table.frame.max()) + 1))         # empty frames too
    rows = tl["rows"]
    assert len(rows["id"]) == len(table)
    assert [tl["frames"][k] for k in rows["frame"]] == table.frame.tolist()
    assert np.allclose(rows["x"], table.x, atol=5e-4) and np.allclose(rows["y"], table.y, atol=5e-4)
    assert np.allclose(rows["sigma"], table.extra["sigma"].astype(float), atol=5e-4)
    k = np.flatnonzero(table.frame == tl["frames"][5])
    if len(k):
        assert np.isclose(tl["times"][5], table.time[k[0]])
    seen = cameras_seeing(run.scene, table.xy, table.extra["height"].astype(float))
    assert [[tl["cameras"][c] for c in cams] for cams in rows["cams"]] == seen


def test_run_folder_without_scene_is_one_clear_error(tmp_path, finished_run):
    from worldtrack.errors import InputError
    (tmp_path / "tracks.csv").write_text((finished_run / "tracks.csv").read_text())
    (tmp_path / "run.yaml").write_text("inputs: {scene: /nowhere/scene.yaml}\n")
    with pytest.raises(InputError, match="cannot find the scene /nowhere/scene.yaml that run.yaml names: give it"):
        load_run(tmp_path)


def test_live_state_sigma_and_cameras(room):
    from worldtrack.serve.live import LOST_GROWTH_M_S, state_message
    people = (MapPerson(1, 5.0, 2.0, 1.7, 0.45, 1.0, 0.0, 1.0, 0.9, "tracking", 100.0, 90.0, 1),
              MapPerson(2, 5.0, 2.0, 1.7, 0.45, 0.0, 0.0, 1.0, 0.9, "lost", 98.5, 90.0, 0),
              MapPerson(3, 9.5, -1.9, 1.7, 0.45, 0.0, 0.0, 1.0, 0.9, "tracking", 100.0, 90.0, 1))
    msg = state_message(MapState(100.0, people, reports=(("c1", 100.0, 100.01),)), room, now=100.25)
    seen, lost, outside = msg["people"]
    assert seen["cams"] == ["c1"] and 0.005 < seen["sigma"] < 0.2            # ~5.4 m away, 2 px
    assert lost["unmeasurable"] == 1 and np.isclose(lost["sigma"], seen["sigma"] + 1.5 * LOST_GROWTH_M_S, atol=2e-3)
    assert outside["cams"] == [] and outside["sigma"] == 1.0
    assert msg["lag_ms"] == 250.0


def test_floor_sigma_is_floor_information_vectorised(room):
    """The page's σ is the map's own floor information (fusion.floor_information), person by person."""
    from worldtrack.map.fusion import floor_information
    from worldtrack.scene.model import Box
    from worldtrack.serve.plan import floor_sigma
    cam2 = Camera.look_at("c2", 320, 240, [10.0, 6.0, 2.5], [5.0, 1.0, 0.0], hfov_deg=70)
    scene = Scene("room2", {**room.cameras, "c2": cam2}, room.walkable,
                  obstacles=[Box("cabinet", np.array([6.0, 3.0, 0.8]), np.array([1.0, 1.0, 1.6]))])
    xy = np.random.default_rng(2).uniform([0.5, -1.5], [9.5, 5.5], (60, 2))
    got = floor_sigma(scene, xy, 1.7)
    occlusion = [scene.occlusion(c).floor_distance for c in scene.cameras]
    for (x, y), s in zip(xy, got):
        ixx, ixy, iyy = floor_information(list(scene.cameras.values()), np.array([x, y]), 1.7, sigma_px=2.0,
                                          occlusion=occlusion)
        info = np.array([[ixx, ixy], [ixy, iyy]])
        want = np.sqrt(np.linalg.eigvalsh(np.linalg.inv(info))[-1]) if np.isfinite(info).all() else 1.0
        assert np.isclose(s, want, rtol=1e-6), (x, y, s, want)
