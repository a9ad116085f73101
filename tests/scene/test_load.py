"""Scene files: every mistake reported with file, field path and what was expected."""

import copy
from pathlib import Path

import numpy as np
import pytest
import yaml

from worldtrack.cli import main
from worldtrack.errors import SceneError
from worldtrack.scene import dump_scene, load_scene, scene_from_dict

LAB = Path(__file__).parents[2] / "examples" / "scenes" / "kato_lab.yaml"


def lab_dict():
    return yaml.safe_load(LAB.read_text())


def problems(data):
    with pytest.raises(SceneError) as e:
        scene_from_dict(data, label="scene.yaml")
    return e.value.problems


def test_example_lab_matches_the_papers_cameras():
    scene = load_scene(LAB)
    np.testing.assert_allclose(scene.cameras["cam1"].centre, [-1.00, -1.74, 2.64], atol=1e-9)
    np.testing.assert_allclose(scene.cameras["cam2"].centre, [-1.07, 1.32, 3.09], atol=1e-9)
    assert scene.obstacles[0].top == pytest.approx(0.73)
    assert scene.people.size_of(7) == (1.65, 0.40)


def test_wrong_matrix_shape_names_the_field():
    d = lab_dict()
    d["cameras"][1]["K"] = [[90, 0], [0, 90], [0, 0]]
    assert problems(d) == ["scene.yaml: cameras[1].K: expected 3x3 matrix, got 3x2"]


def test_unknown_key_is_an_error():
    d = lab_dict()
    d["cameras"][0]["focal"] = 500
    d["obstacles"][0]["colour"] = "red"
    p = problems(d)
    assert "scene.yaml: cameras[0].focal: unknown key (not part of the scene format)" in p
    assert "scene.yaml: obstacles[0].colour: unknown key (not part of the scene format)" in p


def test_every_problem_is_reported_at_once():
    d = lab_dict()
    d["floor"]["walkable"][0]["outer"] = [[0, 0], [1, 1]]
    d["obstacles"][1]["size"] = [0.5, -1, 1.8]
    del d["cameras"][0]["image_size"]
    p = problems(d)
    assert "scene.yaml: floor.walkable[0].outer: expected a polygon of at least 3 points, got 2" in p
    assert "scene.yaml: obstacles[1].size: expected positive sizes in metres, got [0.5, -1.0, 1.8]" in p
    assert "scene.yaml: cameras[0].image_size: required field is missing" in p
    assert len(p) == 3


def test_projection_matrix_rank_and_camera_behind_the_floor():
    d = lab_dict()
    d["cameras"] = [{"id": "bad", "image_size": [160, 120],
                     "P": [[1, 0, 0, 0], [0, 1, 0, 0], [1, 1, 0, 1]]}]
    assert problems(d) == ["scene.yaml: cameras[0]: P: rank of the left 3x3 block is below 3 (not a finite camera)"]
    d["cameras"] = [{"id": "under", "image_size": [160, 120], "position": [0, 0, -1], "look_at": [0, 1, 0],
                     "hfov_deg": 60}]
    (msg,) = problems(d)
    assert msg.startswith("scene.yaml: cameras[0]: camera centre at Z = -1.000 m is at or below the floor")


def test_two_poses_or_none_is_an_error_and_types_are_checked():
    d = lab_dict()
    d["cameras"][0]["P"] = np.eye(3, 4).tolist()
    d["cameras"][1]["K"] = [[90, 0, "x"], [0, 90, 59.5], [0, 0, 1]]
    d["obstacles"][0]["type"] = "cylinder"
    p = problems(d)
    assert any(m.startswith("scene.yaml: cameras[0]: expected exactly one pose") for m in p)
    assert "scene.yaml: cameras[1].K[0][2]: expected a number, got 'x'" in p
    assert "scene.yaml: obstacles[0]: expected type 'box' or 'patch', got 'cylinder'" in p


def test_dump_and_load_round_trip(tmp_path):
    d = lab_dict()
    d["obstacles"][0]["yaw_deg"] = 30.0                                  # a turned desk
    pillar = [[-2.0, 0.0], [-1.6, 0.0], [-1.6, 0.4], [-2.0, 0.4]]
    d["floor"]["walkable"][0]["holes"] = [pillar]
    d["people"]["overrides"] = {3: {"height": 1.80}}                    # width from the default
    scene = scene_from_dict(d, label="scene.yaml")
    out = tmp_path / "copy.yaml"
    dump_scene(scene, out)
    again = load_scene(out)
    for cid, cam in scene.cameras.items():
        np.testing.assert_allclose(again.cameras[cid].P, cam.P, atol=1e-8)
        np.testing.assert_allclose(again.cameras[cid].dist, cam.dist)
    assert [o.name for o in again.obstacles] == ["desk", "shelf"]
    assert again.obstacles[0].yaw == pytest.approx(np.radians(30.0))
    np.testing.assert_allclose(again.obstacles[0].footprint, scene.obstacles[0].footprint, atol=1e-9)
    (poly,) = again.walkable.polygons
    assert len(poly.holes) == 1
    np.testing.assert_allclose(poly.holes[0], pillar)
    assert poly.contains([[-1.8, 0.2], [-1.0, 0.2]]).tolist() == [False, True]
    assert again.people.size_of(3) == (1.80, 0.40) and again.people.size_of(7) == (1.65, 0.40)
    np.testing.assert_allclose(again.entry_regions[0].polygon, scene.entry_regions[0].polygon)


@pytest.mark.parametrize("mutate, expected", [
    (lambda d: d["cameras"][0].update(image_size=[160]), "cameras[0].image_size: expected [width, height]"),
    (lambda d: d.pop("floor"), "floor: required field is missing"),
    (lambda d: d["cameras"][1].update(distortion=[0.1] * 7), "cameras[1].distortion: expected 1 to 5"),
    (lambda d: d["entry_regions"][0].update(polygon=[[0, 0], [1, 0], [2, 0]]), "expected a polygon with non-zero area"),
    (lambda d: d["cameras"][0].update(look_at=[-1.0, -1.74, 2.64]), "look_at: expected a point different"),
])
def test_cli_reports_each_broken_file_on_one_line(tmp_path, capsys, mutate, expected):
    d = copy.deepcopy(lab_dict())
    mutate(d)
    bad = tmp_path / "broken.yaml"
    bad.write_text(yaml.safe_dump(d))
    assert main(["scene", "check", str(bad)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("error: broken.yaml: ") and expected in err
    assert "Traceback" not in err


def test_cli_reports_yaml_syntax_and_missing_file(tmp_path, capsys):
    bad = tmp_path / "syntax.yaml"
    bad.write_text("cameras: [\n  - id: a\n")
    assert main(["scene", "check", str(bad)]) == 2
    assert capsys.readouterr().err.startswith("error: syntax.yaml: line ")
    assert main(["scene", "check", str(tmp_path / "nope.yaml")]) == 2
    assert "no such file" in capsys.readouterr().err


def test_scene_check_prints_summary_and_writes_plan(tmp_path, capsys):
    plan = tmp_path / "plan.png"
    assert main(["scene", "check", str(LAB), "--plot", str(plan)]) == 0
    out = capsys.readouterr().out
    assert "cam1" in out and "height 2.64 m" in out and "35.0 m²" in out and "desk" in out
    assert plan.stat().st_size > 10_000
    import matplotlib.image
    img = matplotlib.image.imread(plan)
    assert img.shape[0] > 300 and img.shape[1] > 300
