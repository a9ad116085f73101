"""Built-in scenarios: all build and render, parameters are checked, scenes agree with the examples."""

from pathlib import Path

import numpy as np
import pytest

from worldtrack.errors import InputError
from worldtrack.geometry.rotation import rotation_angle_deg
from worldtrack.scene import load_scene, scene_from_dict
from worldtrack.synth import list_scenarios, make_scenario, scenario_parameters
from worldtrack.synth import scenes
from worldtrack.synth.bodies import (HEAD, L_FOOT, L_FOREARM, L_UPPER_ARM, PARTS_PER_PERSON, R_FOOT,
                                     R_FOREARM, R_UPPER_ARM)
from worldtrack.synth.kato_lab import CAM1_GRID, CAM2_GRID

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "scenes"


@pytest.mark.parametrize("name", sorted(list_scenarios()))
def test_every_scenario_renders(name):
    sc = make_scenario(name, size=(64, 48), frames=2, seed=0)
    bundles = sc.render()
    assert len(bundles) == 2 and sc.n_frames == 2
    cols = ["frame", "time", "id", "x", "y", "z_head", "height", "width", "speed"]
    for c in sc.camera_ids:
        cols += [f"vis_{c}", f"head_{c}", f"feet_{c}"]
    assert sc.gt_columns() == cols
    for b in bundles:
        assert b.time == pytest.approx(b.frame / sc.fps)
        assert set(b.meta) >= {"frame", "time", "light_level"} | {f"wb_r_{c}" for c in sc.camera_ids}
        for row in b.gt:
            assert list(row) == cols
            assert 1.5 <= row["height"] <= 1.95 and 0.35 <= row["width"] <= 0.55
        for c, v in b.views.items():
            assert v.image.shape == (48, 64, 3) and v.image.dtype == np.uint8
            assert v.depth.shape == (48, 64) and v.depth.dtype == np.float32
            assert v.instance.dtype == np.int32
    assert sc.background(sc.camera_ids[0]).shape == (48, 64, 3)


def test_bad_names_and_parameters_are_input_errors():
    with pytest.raises(InputError, match="unknown scenario 'nope'.*crowd"):
        make_scenario("nope")
    with pytest.raises(InputError, match="no parameter 'peeple'.*people"):
        make_scenario("crowd", peeple=3)
    with pytest.raises(InputError, match="people: expected 1 to 50"):
        make_scenario("crowd", people=51)
    with pytest.raises(InputError, match="aspect"):
        make_scenario("static-grid", size=(160, 160))
    with pytest.raises(InputError, match="size"):
        make_scenario("static-grid", size="big")
    with pytest.raises(InputError, match="frames"):
        make_scenario("static-grid", frames=0)
    with pytest.raises(InputError, match="camera"):
        make_scenario("static-grid", camera="cam3")
    assert "passing" in scenario_parameters("two-crossing")


def test_limb_swing_zero_makes_walkers_glide_on_the_same_paths():
    walk = make_scenario("two-crossing", size=(64, 48), seed=3)
    glide = make_scenario("two-crossing", size=(64, 48), seed=3, limb_swing=0.0)
    frame = walk.n_frames // 2
    for a, b in zip(walk.people, glide.people):
        np.testing.assert_array_equal(a.track.xy, b.track.xy)
        assert a.track.speed[frame] > 0.5 and a.track.amplitude[frame] > 0.3
        assert not b.track.amplitude.any()

    def stride(sc):
        """How far (m) each walker's feet are apart along the heading at ``frame``."""
        people, parts = sc.pose_people(frame)
        centre = parts.centre.reshape(len(people), PARTS_PER_PERSON, 3)
        yaw = np.array([p.track.yaw[frame] for p in people])
        apart = centre[:, L_FOOT, :2] - centre[:, R_FOOT, :2]
        return np.abs(apart[:, 0] * np.cos(yaw) + apart[:, 1] * np.sin(yaw))

    # Walking, one foot is ahead of the other; gliding they stay side by side, as standing.
    assert stride(walk).max() > 0.3
    assert stride(glide).max() < 0.02
    with pytest.raises(InputError, match="limb_swing: expected a value in \\[0, 1.5\\], got -1"):
        make_scenario("two-crossing", limb_swing=-1.0)


@pytest.mark.parametrize("camera, grid", [("cam1", CAM1_GRID), ("cam2", CAM2_GRID)])
def test_static_grid_stands_still_at_every_grid_point(camera, grid):
    sc = make_scenario("static-grid", camera=camera, seed=0, size=(32, 24))
    tr = sc.people[0].track
    still = tr.speed == 0.0
    points = {tuple(np.round(p, 6)) for p in tr.xy[still]}
    assert points == {(float(x), float(y)) for x, y in grid}
    for x, y in grid:   # dwell ≈ 1.5 s at each
        assert np.all(tr.xy == [x, y], axis=1).sum() >= 14
    assert sc.people[0].shape.height == 1.66 and sc.people[0].shape.shoulder_width == 0.42


def test_non_overlapping_views_do_not_overlap():
    sc = make_scenario("non-overlapping", size=(64, 48), frames=1)
    x, y = np.meshgrid(np.arange(0.05, 16, 0.1), np.arange(0.05, 8, 0.1))
    counts = 0
    for z in (0.0, 0.9, 1.8):
        pts = np.column_stack([x.ravel(), y.ravel(), np.full(x.size, z)])
        seen = np.zeros(len(pts), int)
        for cam in sc.scene.cameras.values():
            uv, d = cam.project(pts, return_depth=True)
            seen += (d > 0) & cam.in_image(np.nan_to_num(uv, nan=-9))
        assert seen.max() == 1
        counts += (seen == 1).sum()
    assert counts > 1000


def _same_scene(a, b):
    assert list(a.cameras) == list(b.cameras)
    for cid in a.cameras:
        np.testing.assert_allclose(a.cameras[cid].P, b.cameras[cid].P, atol=1e-9)
        np.testing.assert_allclose(a.cameras[cid].dist, b.cameras[cid].dist)
    assert [o.name for o in a.obstacles] == [o.name for o in b.obstacles]
    for oa, ob in zip(a.obstacles, b.obstacles):
        np.testing.assert_allclose(oa.footprint, ob.footprint)
    for pa, pb in zip(a.walkable.polygons, b.walkable.polygons):
        np.testing.assert_allclose(pa.outer, pb.outer)
    assert [r.name for r in a.entry_regions] == [r.name for r in b.entry_regions]


@pytest.mark.parametrize("name", sorted(scenes.BUILTIN))
def test_example_scene_files_match_the_builtin_scenes(name):
    _same_scene(load_scene(EXAMPLES / f"{name}.yaml"), scene_from_dict(scenes.scene_dict(name)))


def _quat_matrix(q):
    """Rotation matrix of a quaternion (w, x, y, z), renormalised (pose.csv rounds it)."""
    w, x, y, z = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def _angle_deg(A, B):
    """Angle of A·Bᵀ in degrees, accurate near 0 (atan2 of the sine and cosine parts, not arccos)."""
    D = A @ B.T
    s = np.linalg.norm([D[2, 1] - D[1, 2], D[0, 2] - D[2, 0], D[1, 0] - D[0, 1]]) / 2
    return np.degrees(np.arctan2(s, (np.trace(D) - 1) / 2))


def test_pose_scenarios_report_the_rendered_pose():
    sc = make_scenario("face-pose", motion="large", frames=12, size=(64, 48), seed=1)
    rows = [r for b in sc.frames() for r in b.pose]
    assert len(rows) == 12
    q = np.array([[r["qw"], r["qx"], r["qy"], r["qz"]] for r in rows])
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-7)
    yaw = np.array([r["rz_deg"] for r in rows])
    assert np.ptp(yaw) > 3.0                                   # the head turns
    # Every row is the rendered head: its quaternion is head → world (the head's axes as columns,
    # parts.axes[k].T) and its translation the head's centre. Rounding to 8 decimals bounds the
    # angle at ~1.2e-6°; a transposed or identity rotation is off by tens of degrees.
    for r, qr in zip(rows, q):
        people, parts = sc.pose_people(r["frame"])
        k = [p.id for p in people].index(r["id"]) * PARTS_PER_PERSON + HEAD
        assert _angle_deg(_quat_matrix(qr), parts.axes[k].T) < 2e-6
        np.testing.assert_allclose([r["tx"], r["ty"], r["tz"]], parts.centre[k], atol=1e-6)
    ub = make_scenario("upper-body", frames=3, size=(64, 48), seed=1)
    for b in ub.frames():
        row = b.pose[0]
        assert len([k for k in row if k.endswith("_deg")]) == 3 + 8          # 14 DoF = 3 translations + 11 angles
        people, parts = ub.pose_people(b.frame)
        base = [p.id for p in people].index(row["id"]) * PARTS_PER_PERSON
        for limb, part in (("l_upper_arm", L_UPPER_ARM), ("l_forearm", L_FOREARM),
                           ("r_upper_arm", R_UPPER_ARM), ("r_forearm", R_FOREARM)):
            axis = np.array([row[f"{limb}_axis_{c}"] for c in "xyz"])
            assert np.linalg.norm(axis) == pytest.approx(1.0, abs=1e-7)
            seg = parts.end[base + part] - parts.centre[base + part]
            np.testing.assert_allclose(axis, seg / np.linalg.norm(seg), atol=1e-7)
            np.testing.assert_allclose(axis, parts.axes[base + part][0], atol=1e-7)   # the capsule's own x axis


def test_face_pose_quaternion_matches_the_head_rotation():
    from worldtrack.synth.booth import _quat
    from worldtrack.geometry.rotation import euler_zyx
    R = euler_zyx(0.3, -0.2, 0.1)
    w, x, y, z = _quat(R)
    Rq = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                   [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                   [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    assert rotation_angle_deg(R, Rq) < 1e-6


def test_sitting_down_lowers_the_head_while_standing_still():
    sc = make_scenario("sit-down", size=(32, 24), seed=0)
    rows = [r for b in sc.frames() for r in b.gt]
    z = np.array([r["z_head"] for r in rows])
    speed = np.array([r["speed"] for r in rows])
    height = rows[0]["height"]
    assert z.max() == pytest.approx(height, abs=0.03)
    assert z.min() < height - 0.35
    assert np.all(speed[z < height - 0.3] == 0.0)
