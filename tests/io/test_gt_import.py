"""Image-box ground truth → world ground truth: a round trip through a known camera.

People stand at known floor points; their foot points are projected through a known camera
(with lens distortion) at the annotation resolution 768x576, written as CVML boxes and as
MOTChallenge text, and imported through the same camera rescaled to 480x360 — as PETS 2009's GT
is used with the 480x360 video. The positions must come back within 1 cm.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
import yaml

from worldtrack.cli import main
from worldtrack.cli.eval import parse_area
from worldtrack.cli.gt import read_area
from worldtrack.errors import InputError
from worldtrack.geometry.camera import Camera
from worldtrack.io.gt_import import boxes_to_world, read_boxes, read_cvml, read_mot_boxes
from worldtrack.io.tracks import read_tracks
from worldtrack.scene import load_scene
from worldtrack.scene.load import camera_to_dict

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
BOX_W, BOX_H = 30.0, 80.0


@pytest.fixture(scope="module")
def camera_768() -> Camera:
    return Camera.look_at("View_001", 768, 576, position=(-12.0, -14.0, 7.0), target=(-4.0, -6.0, 0.0),
                          hfov_deg=40, dist=(-0.16, 0.07, 0.0, 0.0, -0.03))


@pytest.fixture(scope="module")
def truth() -> dict[tuple[int, int], np.ndarray]:
    """(frame, id) → floor point (x, y, 0), metres: three people walking for six frames."""
    out = {}
    for pid, (x0, y0, vx, vy) in {1: (-6.0, -8.0, 0.3, 0.1), 2: (-3.0, -5.0, -0.2, 0.25),
                                  4: (-4.5, -9.5, 0.0, -0.1)}.items():
        for f in range(6):
            out[(f, pid)] = np.array([x0 + vx * f, y0 + vy * f, 0.0])
    return out


def _cvml(camera: Camera, truth: dict, extra_objects: str = "") -> str:
    frames: dict[int, list[str]] = {}
    for (f, pid), X in sorted(truth.items()):
        u, v = camera.project(X)
        frames.setdefault(f, []).append(
            f'<object id="{pid}"><box h="{BOX_H}" w="{BOX_W}" xc="{u:.6f}" yc="{v - BOX_H / 2:.6f}"/></object>')
    body = "".join(f'<frame number="{f}"><objectlist>{"".join(objs)}{extra_objects if f == 0 else ""}'
                   f"</objectlist></frame>\n" for f, objs in frames.items())
    return f'<?xml version="1.0" encoding="utf-8"?>\n<dataset>\n{body}</dataset>\n'


def _scene_file(tmp_path: Path, camera: Camera) -> Path:
    scene = {"name": "t", "cameras": [camera_to_dict(camera)],
             "floor": {"walkable": [{"outer": [[-20, -20], [10, -20], [10, 10], [-20, 10]]}]}}
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(scene, sort_keys=False))
    return path


def _errors(table, truth) -> np.ndarray:
    want = np.array([truth[(int(f), int(i))][:2] for f, i in zip(table.frame, table.id)])
    return np.linalg.norm(table.xy - want, axis=1)


# ---------------------------------------------------------------------------- round trips

def test_cvml_round_trip_through_a_rescaled_camera_within_1cm(tmp_path, camera_768, truth):
    path = tmp_path / "gt.xml"
    path.write_text(_cvml(camera_768, truth))
    boxes = read_cvml(path)
    assert len(boxes) == len(truth) and boxes.format == "cvml"
    result = boxes_to_world(boxes, camera_768.scaled(0.625), scale=0.625, fps=7.0)
    t = result.table
    assert len(t) == 18 and set(t.ids()) == {1, 2, 4}
    assert _errors(t, truth).max() < 0.01
    np.testing.assert_allclose(t.time, t.frame / 7.0)
    assert result.outside == 0 and np.all(t.extra["foot_outside"] == 0)
    # Foot pixels are in the 480x360 image; the box keeps its proportions.
    np.testing.assert_allclose(t.extra["bb_height"], 0.625 * BOX_H)
    small = camera_768.scaled(0.625)
    feet = np.array([small.project(truth[(int(f), int(i))]) for f, i in zip(t.frame, t.id)])
    np.testing.assert_allclose(np.column_stack([t.extra["foot_u"], t.extra["foot_v"]]), feet, atol=1e-4)


def test_mot_text_round_trip_with_one_based_frames_and_pixels(tmp_path, camera_768, truth):
    lines = []
    for (f, pid), X in sorted(truth.items()):
        u, v = camera_768.project(X)
        lines.append(f"{f + 1},{pid},{u - BOX_W / 2 + 1:.6f},{v - BOX_H + 1:.6f},{BOX_W},{BOX_H},1,-1,-1,-1")
    path = tmp_path / "gt.txt"
    path.write_text("\n".join(lines) + "\n")
    boxes = read_boxes(path)                                   # auto: not XML → MOTChallenge
    assert boxes.format == "mot" and boxes.frame.min() == 0
    t = boxes_to_world(boxes, camera_768).table
    assert _errors(t, truth).max() < 0.01
    # With the wrong pixel origin the positions move (by about a pixel's worth).
    shifted = boxes_to_world(read_mot_boxes(path, pixel_origin=0), camera_768).table
    assert _errors(shifted, truth).max() > 0.01


def test_mot16_consider_flag_drops_rows(tmp_path):
    path = tmp_path / "gt.txt"
    path.write_text("1,1,10,20,30,80,1,1,1.0\n1,2,100,20,30,80,0,7,1.0\n2,1,12,20,30,80,1,1,0.5\n")
    boxes = read_mot_boxes(path)
    assert len(boxes) == 2 and boxes.dropped == 1


def test_feet_outside_the_image_are_flagged_kept_or_dropped(tmp_path, camera_768, truth):
    u, v = camera_768.project(truth[(0, 1)])
    outside = f'<object id="7"><box h="100" w="30" xc="{u:.3f}" yc="{575.5 - 40:.3f}"/></object>'
    path = tmp_path / "gt.xml"
    path.write_text(_cvml(camera_768, truth, extra_objects=outside))   # foot at v = 585.5 > 575.5
    boxes = read_cvml(path)
    kept = boxes_to_world(boxes, camera_768)
    assert kept.outside == 1 and len(kept.table) == 19
    flagged = kept.table.select(kept.table.extra["foot_outside"] == 1)
    assert list(flagged.id) == [7] and np.all(np.isfinite(flagged.xy))
    dropped = boxes_to_world(boxes, camera_768, keep_outside=False)
    assert dropped.dropped_outside == 1 and len(dropped.table) == 18


def test_area_keeps_only_people_inside(camera_768, truth, tmp_path):
    path = tmp_path / "gt.xml"
    path.write_text(_cvml(camera_768, truth))
    area = np.array([[-7.0, -9.0], [-2.0, -9.0], [-2.0, -3.0], [-7.0, -3.0]])   # excludes person 4
    result = boxes_to_world(read_cvml(path), camera_768, area=area)
    assert set(result.table.ids()) == {1, 2} and result.outside_area == 6


def test_ids_from_zero_are_shifted_to_start_at_one(tmp_path, camera_768, truth):
    text = _cvml(camera_768, {(0, 0): truth[(0, 1)], (0, 3): truth[(0, 2)]})
    path = tmp_path / "gt.xml"
    path.write_text(text)
    result = boxes_to_world(read_cvml(path), camera_768)
    assert result.id_offset == 1 and list(result.table.id) == [1, 4]


# ---------------------------------------------------------------------------- bad input

@pytest.mark.parametrize("text, message", [
    ("<dataset></dataset>", r"no <frame> elements"),
    ("<dataset><frame><objectlist/></frame></dataset>", r"<frame>: missing attribute 'number'"),
    ('<dataset><frame number="0"><objectlist><object><box xc="1" yc="2" w="3" h="4"/></object>'
     "</objectlist></frame></dataset>", r"frame 0: <object>: missing attribute 'id'"),
    ('<dataset><frame number="0"><objectlist><object id="1"><box xc="1" yc="2" w="3"/></object>'
     "</objectlist></frame></dataset>", r"frame 0, object 1: <box> is missing 'h'"),
    ('<dataset><frame number="0"><objectlist><object id="1"><box xc="a" yc="2" w="3" h="4"/></object>'
     "</objectlist></frame></dataset>", r"xc: expected a number, got 'a'"),
    ('<dataset><frame number="0"><objectlist><object id="1"><box xc="1" yc="2" w="3" h="4"/></object>'
     '<object id="1"><box xc="1" yc="2" w="3" h="4"/></object></objectlist></frame></dataset>',
     r"frame 0, object 1: id appears twice"),
    ("<dataset><frame", r"not valid XML"),
])
def test_bad_cvml_is_one_input_error(tmp_path, text, message):
    path = tmp_path / "gt.xml"
    path.write_text(text)
    with pytest.raises(InputError, match=message) as info:
        read_cvml(path)
    assert "\n" not in str(info.value)


def test_bad_mot_text_is_one_input_error(tmp_path):
    path = tmp_path / "gt.txt"
    path.write_text("1,1,10,20,30\n")
    with pytest.raises(InputError, match=r"line 1: expected at least 6 values"):
        read_mot_boxes(path)
    path.write_text("0,1,10,20,30,80\n")
    with pytest.raises(InputError, match=r"line 1: expected an integer frame >= 1"):
        read_mot_boxes(path)


# ---------------------------------------------------------------------------- the command line

def test_cli_writes_gt_csv_that_eval_reads(tmp_path, camera_768, truth, capsys):
    gt = tmp_path / "gt.xml"
    gt.write_text(_cvml(camera_768, truth))
    scene = _scene_file(tmp_path, camera_768.scaled(0.625))
    out = tmp_path / "gt.csv"
    rc = main(["gt", "import", str(gt), "--scene", str(scene), "--camera", "View_001", "--scale", "0.625",
               "--fps", "7", "--out", str(out)])
    text = capsys.readouterr().out
    assert rc == 0
    assert "read 18 boxes (CVML)" in text and "time = frame / 7 fps" in text
    assert "foot points outside the image: 0" in text
    assert re.search(r"wrote .*gt.csv: 18 rows, 3 ids, frames 0-5", text)
    table = read_tracks(out)
    assert table.columns[:8] == ["frame", "time", "id", "x", "y", "foot_u", "foot_v", "foot_outside"]
    assert _errors(table, truth).max() < 0.01
    # --gt-size says the same as --scale.
    out2 = tmp_path / "gt2.csv"
    assert main(["gt", "import", str(gt), "--scene", str(scene), "--gt-size", "768x576", "--out", str(out2)]) == 0
    np.testing.assert_allclose(read_tracks(out2).xy, table.xy)


def test_cli_area_from_a_file(tmp_path, camera_768, truth, capsys):
    gt = tmp_path / "gt.xml"
    gt.write_text(_cvml(camera_768, truth))
    area = tmp_path / "area.txt"
    area.write_text("# a rectangle\n-7,-9, -2,-9,\n-2,-3,-7,-3\n")
    out = tmp_path / "gt.csv"
    rc = main(["gt", "import", str(gt), "--scene", str(_scene_file(tmp_path, camera_768)), "--area", str(area),
               "--out", str(out)])
    assert rc == 0 and "outside the --area polygon (left out): 6" in capsys.readouterr().out
    assert set(read_tracks(out).ids()) == {1, 2}


@pytest.mark.parametrize("extra, message", [
    (["--camera", "View_009"], r"View_009"),
    (["--fps", "0"], r"^error: --fps: expected a positive number"),
    (["--scale", "-1"], r"^error: --scale: expected a positive number"),
    (["--scale", "0.5", "--gt-size", "768x576"], r"^error: give --scale or --gt-size, not both"),
    (["--gt-size", "768x100"], r"another aspect ratio"),
    (["--area", "1,2,3"], r"^error: --area"),
    (["--area", "nofile.txt"], r"^error: --area 'nofile.txt': no such file"),
])
def test_cli_errors_are_one_line(tmp_path, camera_768, truth, capsys, extra, message):
    gt = tmp_path / "gt.xml"
    gt.write_text(_cvml(camera_768, truth))
    rc = main(["gt", "import", str(gt), "--scene", str(_scene_file(tmp_path, camera_768)),
               "--out", str(tmp_path / "gt.csv"), *extra])
    err = capsys.readouterr().err.splitlines()
    assert rc == 2 and len(err) == 1 and re.search(message, err[0]), err


# ---------------------------------------------------------------------------- the PETS example files

def test_pets_tracking_area_file_is_milans_rectangle():
    path = EXAMPLES / "pets2009" / "tracking_area.txt"
    ring = read_area(str(path))
    np.testing.assert_allclose(ring.min(axis=0), [-14.0696, -14.2740])
    np.testing.assert_allclose(ring.max(axis=0), [4.9813, 1.7335])
    body = ",".join(ln for ln in path.read_text().splitlines() if not ln.startswith("#"))
    np.testing.assert_allclose(parse_area(body), ring)           # what `eval --area` reads


def test_pets_scene_camera_reproduces_the_check_point():
    scene = load_scene(EXAMPLES / "scenes" / "pets2009_view001.yaml")
    cam = scene.cameras["View_001"]
    assert (cam.width, cam.height) == (480, 360)
    uv = cam.project([-4.140, -7.400, 0.0])                      # README: (514.8, 232.0) at 768x576
    assert np.linalg.norm(uv - (0.625 * (np.array([514.8, 232.0]) + 0.5) - 0.5)) < 0.7
    assert np.linalg.norm(cam.centre - [-28.9, -19.5, 7.07]) < 0.1
    assert scene.walkable.on_floor([[-4.14, -7.4], [-14.0, -14.2], [4.9, 1.7]]).all()
