"""Acceptance tests of the renderer: ground truth, depth, occlusion, shadows, visibility."""

import cv2
import numpy as np
import pytest

from worldtrack.synth import kernels, make_scenario
from worldtrack.synth.environment import FLOOR
from worldtrack.synth.people_pass import people_pass


def _pixel(cam, point):
    uv, depth = cam.project(np.asarray(point, float)[None], return_depth=True)
    return uv[0], float(depth[0])


def test_ground_truth_positions_project_onto_the_persons_pixels(crossing):
    sc, bundles = crossing
    own = other = 0
    for b in bundles:
        for cid, view in b.views.items():
            cam = view.camera
            depth_of = {r["id"]: _pixel(cam, (r["x"], r["y"], 0.55 * r["height"]))[1] for r in b.gt}
            for r in b.gt:
                uv, z = _pixel(cam, (r["x"], r["y"], 0.55 * r["height"]))
                if not cam.in_image(uv, margin=1.0):
                    continue
                seen = view.instance[int(round(uv[1])), int(round(uv[0]))]
                if seen == r["id"]:
                    own += 1
                else:  # only another person in front may cover it
                    assert seen in depth_of and depth_of[seen] < z, (b.frame, cid, r["id"], seen)
                    other += 1
    assert own > 80 and other < own / 5


def test_instance_pixels_are_nearer_than_the_static_scene(crossing):
    sc, bundles = crossing
    for cid in sc.camera_ids:
        static = sc._renderer.static_layer(sc.scene.cameras[cid]).depth
        for b in bundles[::5]:
            v = b.views[cid]
            person = v.instance > 0
            assert person.any()
            assert np.all(v.depth[person] < static[person])
            np.testing.assert_array_equal(v.depth[~person], static[~person])


def test_floor_depth_equals_the_analytic_value(crossing):
    sc, bundles = crossing
    for cid in sc.camera_ids:          # cam2 has barrel distortion
        cam = sc.scene.cameras[cid]
        layer = sc._renderer.static_layer(cam)
        view = bundles[0].views[cid]
        floor = (layer.kind == FLOOR) & (view.instance == 0)
        v, u = np.nonzero(floor)
        assert len(u) > 2000
        X = cam.backproject(np.column_stack([u, v]).astype(float), 0.0)
        expected = cam.depth(X)
        np.testing.assert_allclose(view.depth[v, u], expected, rtol=2e-6, atol=1e-6)


def test_person_behind_desk_is_hidden_exactly_where_the_desk_is_nearer(desk):
    sc, bundles = desk
    cam = sc.scene.cameras["cam1"]
    r = sc._renderer
    static = r.static_layer(cam).depth
    dwell = [b for b in bundles if b.gt and b.gt[0]["speed"] == 0.0]
    assert len(dwell) > 50
    hidden_total = 0
    for b in dwell[::4]:
        people, parts = sc.pose_people(b.frame)
        alone = people_pass(cam, r.rays(cam), parts, 1, np.array([1]), np.full(static.shape, np.inf, np.float32))
        v = b.views["cam1"]
        hidden = (alone.inst == 1) & (v.instance != 1)
        visible = v.instance == 1
        assert np.all(static[hidden] < alone.zbuf[hidden])
        assert np.all(alone.zbuf[visible] < static[visible])
        hidden_total += hidden.sum()
        row = b.gt[0]
        assert row["feet_cam1"] == 0 and row["head_cam1"] == 1, row
        assert 0.2 < row["vis_cam1"] < 0.97
        assert row["vis_cam1"] == pytest.approx(visible.sum() / alone.alone[0], abs=1e-4)
    assert hidden_total > 100


def test_head_and_feet_hidden_variant():
    sc = make_scenario("desk-occlusion", hide="head-and-feet", frames=45, speed=1.0, dwell=1.0, noise=0.0)
    rows = [r for b in sc.frames() for r in b.gt if r["speed"] == 0.0 and b.frame > 5]
    assert rows
    assert all(r["head_cam1"] == 0 and r["feet_cam1"] == 0 for r in rows)


def _clean(**kw):
    return make_scenario("two-crossing", size=(160, 120), frames=25, seed=1, noise=0.0, blur=0.0, vignetting=0.0,
                         light_drift=0.0, **kw)


def test_shadows_darken_the_floor_only_where_the_light_says():
    lit = list(_clean(shadow_strength=0.7).frames())[-1]
    flat = list(_clean(shadow_strength=0.0).frames())[-1]
    sc = _clean(shadow_strength=0.7)
    people, parts = sc.pose_people(24)
    light, _ = sc.lighting.at(24 / sc.fps)
    for cid in sc.camera_ids:
        cam = sc.scene.cameras[cid]
        layer = sc._renderer.static_layer(cam)
        a, b = lit.views[cid], flat.views[cid]
        receiver = (layer.kind == FLOOR) & (a.instance == 0)
        expected = kernels.trace_shadows_reference(layer.points, receiver, light.L, parts.geometry())
        assert expected.sum() > 20
        assert (a.shadow != expected).sum() <= 2
        diff = a.image.astype(int) - b.image.astype(int)
        assert np.all(diff[~a.shadow] == 0)
        assert np.all(diff[a.shadow].sum(axis=-1) < 0)
        # The shadow falls away from the light: behind the people as seen from it.
        pts = layer.points[a.shadow][:, :2].astype(float)
        feet = np.array([[r["x"], r["y"]] for r in lit.gt])
        owner = np.argmin(np.linalg.norm(pts[:, None] - feet[None], axis=2), axis=1)
        assert np.mean(np.sum((pts - feet[owner]) * light.L[:2], axis=1)) < 0


def test_visibility_fractions_and_border_cut(crossing):
    sc, bundles = crossing
    rows = [r for b in bundles for r in b.gt]
    for cid in sc.camera_ids:
        vis = np.array([r[f"vis_{cid}"] for r in rows])
        assert np.all((vis >= 0) & (vis <= 1))
    # Person 2 starts at x = 0.6, beyond camera 1's right border: only partly in view.
    first = {r["id"]: r for r in bundles[0].gt}
    assert 0 < first[2]["vis_cam1"] < 0.5
    # While person 2 passes in front of person 1 in camera 1, person 1 is partly hidden.
    v1 = [next(r["vis_cam1"] for r in b.gt if r["id"] == 1) for b in bundles]
    assert min(v1) < 0.75 and max(v1) == 1.0


def test_same_seed_same_arrays_different_seed_different_noise():
    a = list(make_scenario("static-grid", frames=3, seed=4).frames())[-1].views["cam1"]
    b = list(make_scenario("static-grid", frames=3, seed=4).frames())[-1].views["cam1"]
    c = list(make_scenario("static-grid", frames=3, seed=5).frames())[-1].views["cam1"]
    np.testing.assert_array_equal(a.image, b.image)
    np.testing.assert_array_equal(a.depth, b.depth)
    np.testing.assert_array_equal(a.instance, b.instance)
    assert np.any(a.image != c.image)


def test_background_matches_the_empty_parts_of_frame_zero():
    sc = make_scenario("two-crossing", size=(160, 120), frames=1, seed=0, noise=0.0, reflection=0.0)
    bg = sc.background("cam1")
    view = next(sc.frames()).views["cam1"]
    # Away from people, their shadows and the blur around them, frame 0 is the background plate.
    near = cv2.dilate(((view.instance > 0) | view.shadow).astype(np.uint8), np.ones((5, 5), np.uint8)).astype(bool)
    ok = ~near
    assert ok.mean() > 0.8
    assert np.abs(view.image[ok].astype(int) - bg[ok]).max() <= 1
