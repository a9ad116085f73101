"""Reading calibration files (Tsai XML, OpenCV FileStorage, JSON, 3x4 text) and ``calibrate --import``.

Fixtures are written by the tests: the Tsai XML carries PETS 2009 View_001's numbers, the JSON
EPFL mot3d's OpenCV refit of the same camera (both for 768x576 images, millimetres). The check
point of the PETS data README — world (-4140, -7400, 0) mm at (514.8, 232.0) px — must come out
of both.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from worldtrack.cli import main
from worldtrack.errors import InputError
from worldtrack.geometry.camera import Camera
from worldtrack.geometry.rotation import rotation_to_rodrigues
from worldtrack.io.calibration_formats import read_calibration
from worldtrack.io.calibration_import import decide_units, import_camera
from worldtrack.scene.load import scene_from_dict

TSAI_XML = """<?xml version="1.0" encoding="UTF-8"?>
<Camera name="View_001">
\t<Geometry width="768" height="576" ncx="7.9500000000e+02" nfx="7.5200000000e+02" dx="4.8500000000e-03" dy="4.6500000000e-03" dpx="5.1273271277e-03" dpy="4.6500000000e-03"/>
\t<Intrinsic focal="5.5549183034e+00" kappa1="5.1113043639e-03" cx="3.2422149053e+02" cy="2.8256650051e+02" sx="1.0937855397e+00"/>
\t<Extrinsic tx="8.2873214225e+02" ty="-3.1754796051e+03" tz="3.5469298547e+04" rx="2.0405458695e+00" ry="-8.9337703748e-01" rz="-4.3056124791e-01"/>
 </Camera>
"""

MOT3D_VIEW_001 = {
    "K": [[1125.8236906695045, 0.0, 289.70640779598557], [0.0, 1138.9890203787324, 258.4500241381447],
          [0.0, 0.0, 1.0]],
    "dist": [-0.14988085238733614, 0.04710693223566513, 0.001241571248317241, 0.0037717506846197926,
             6.955494674409888e-13],
    "R": [[0.5955009556019861, -0.8011119067498077, -0.05998603788223539],
          [-0.24405263946137604, -0.1092629036673589, -0.9635870106296126],
          [0.765386778726323, 0.5884567365115851, -0.26057963889198626]],
    "t": [1922.7173277390089, -2440.828743385048, 34426.054423720176],
}

CHECK_MM = np.array([-4140.0, -7400.0, 0.0])
CHECK_PX = np.array([514.8, 232.0])


def _write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.fixture
def tsai_file(tmp_path) -> Path:
    return _write(tmp_path, "View_001.xml", TSAI_XML)


@pytest.fixture
def mot3d_file(tmp_path) -> Path:
    other = {**MOT3D_VIEW_001, "t": [3566.2, -249.0, 47855.3]}
    return _write(tmp_path, "calibration.json", json.dumps({"View_001": MOT3D_VIEW_001, "View_003": other}))


# ---------------------------------------------------------------------------- Tsai XML

def test_tsai_file_imports_with_units_detected_and_the_check_point(tsai_file):
    cal = read_calibration(tsai_file)
    assert cal.format == "tsai-xml" and cal.camera == "View_001" and cal.image_size == (768, 576)
    imp = import_camera(cal)
    assert imp.units == "mm" and imp.units_note.startswith("millimetres (detected from |t| = 3562")
    assert "converted to metres" in imp.units_note
    assert np.linalg.norm(imp.tsai.project(CHECK_MM / 1000) - CHECK_PX) < 1.0
    assert np.linalg.norm(imp.camera.project(CHECK_MM / 1000) - CHECK_PX) < 1.0
    assert imp.conversion.max_error_px < 0.01
    assert np.linalg.norm(imp.camera.centre - [-28.9, -19.5, 7.07]) < 0.1


def test_tsai_file_rescaled_to_the_video(tsai_file):
    imp = import_camera(read_calibration(tsai_file), image_size=(480, 360))
    assert (imp.camera.width, imp.camera.height) == (480, 360) and imp.scale == 0.625
    uv = imp.camera.project(CHECK_MM / 1000)
    np.testing.assert_allclose(uv, 0.625 * (imp.native.project(CHECK_MM / 1000) + 0.5) - 0.5, atol=1e-9)
    same = import_camera(read_calibration(tsai_file), scale=0.625)
    np.testing.assert_allclose(same.camera.K, imp.camera.K)


def test_tsai_dpx_is_derived_from_dx_when_absent(tmp_path):
    text = TSAI_XML.replace(' dpx="5.1273271277e-03"', "")
    cal = read_calibration(_write(tmp_path, "c.xml", text))
    assert cal.tsai["dpx"] == pytest.approx(4.85e-3 * 795 / 752)
    assert any("dx·ncx/nfx" in n for n in cal.notes)


def test_multi_camera_tsai_file_selects_by_name(tmp_path):
    second = TSAI_XML.split("\n", 1)[1].replace("View_001", "View_009").replace('tz="3.5469298547e+04"',
                                                                               'tz="2.0e+04"')
    text = "<cameras>\n" + TSAI_XML.split("\n", 1)[1] + second + "</cameras>\n"
    path = _write(tmp_path, "all.xml", text)
    assert read_calibration(path, "View_009").tsai["tz"] == 2.0e4
    with pytest.raises(InputError, match=r"holds 2 cameras \(View_001, View_009\); choose one with --camera"):
        read_calibration(path)


# ---------------------------------------------------------------------------- JSON, YAML

def test_mot3d_json_selects_a_view_and_reproduces_the_check_point(mot3d_file):
    cal = read_calibration(mot3d_file, "View_001")
    assert cal.format == "json" and cal.cameras == ("View_001", "View_003") and cal.image_size is None
    imp = import_camera(cal, calibration_size=(768, 576))
    assert imp.units == "mm"
    assert np.linalg.norm(imp.camera.project(CHECK_MM / 1000) - CHECK_PX) < 1.0
    np.testing.assert_allclose(imp.camera.t, np.array(MOT3D_VIEW_001["t"]) / 1000)
    head = imp.camera.project((CHECK_MM + [0, 0, 1700]) / 1000)
    assert 69 < imp.camera.project(CHECK_MM / 1000)[1] - head[1] < 73
    assert np.linalg.norm(imp.camera.centre - [-28.9, -19.5, 7.07]) < 1.5   # a refit: its centre is 1 m off


def test_json_single_camera_with_rvec_metres_and_size(tmp_path):
    cam = Camera.look_at("c", 640, 480, position=(1, -4, 2.5), target=(0, 0, 1), hfov_deg=60,
                         dist=(-0.1, 0.01, 0, 0, 0))
    data = {"camera_matrix": cam.K.tolist(), "rvec": rotation_to_rodrigues(cam.R).tolist(),
            "tvec": cam.t.tolist(), "distCoeffs": cam.dist[:4].tolist(), "image_size": [640, 480]}
    imp = import_camera(read_calibration(_write(tmp_path, "c.json", json.dumps(data))))
    assert imp.units == "m" and imp.units_note.startswith("metres (detected from |t|")
    pts = np.array([[0.0, 0.0, 0.0], [0.5, 1.0, 1.7]])
    np.testing.assert_allclose(imp.camera.project(pts), cam.project(pts), atol=1e-9)


def test_plain_yaml_mapping_is_read(tmp_path):
    cam = Camera.look_at("c", 640, 480, position=(1, -4, 2.5), target=(0, 0, 1), hfov_deg=60)
    text = yaml.safe_dump({"K": cam.K.tolist(), "R": cam.R.tolist(), "t": cam.t.tolist(),
                           "width": 640, "height": 480})
    cal = read_calibration(_write(tmp_path, "c.yaml", text))
    assert cal.format == "yaml" and cal.image_size == (640, 480)


# ---------------------------------------------------------------------------- OpenCV FileStorage

@pytest.mark.parametrize("suffix", [".yml", ".xml"])
def test_opencv_filestorage_written_by_opencv(tmp_path, suffix):
    cam = Camera.look_at("c", 640, 480, position=(1500, -4000, 2500), target=(0, 0, 1000), hfov_deg=60,
                         dist=(-0.2, 0.05, 0.001, -0.002, 0))
    path = tmp_path / f"cam{suffix}"
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    fs.write("image_width", 640)
    fs.write("image_height", 480)
    fs.write("camera_matrix", cam.K)
    fs.write("distortion_coefficients", cam.dist.reshape(1, 5))
    fs.write("rvec", rotation_to_rodrigues(cam.R).reshape(3, 1))
    fs.write("tvec", cam.t.reshape(3, 1))
    fs.release()
    cal = read_calibration(path)
    assert cal.format == ("opencv-yaml" if suffix == ".yml" else "opencv-xml")
    imp = import_camera(cal)
    assert imp.units == "mm"                              # |t| ≈ 4900 → millimetres
    world_mm = np.array([[0.0, 0.0, 0.0], [500.0, 1000.0, 1700.0]])
    np.testing.assert_allclose(imp.camera.project(world_mm / 1000), cam.project(world_mm), atol=1e-6)


def test_opencv_yaml_by_hand_with_R_and_t(tmp_path):
    text = """%YAML:1.0
---
image_width: 768
image_height: 576
camera_matrix: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 1000., 0., 383.5, 0., 1000., 287.5, 0., 0., 1. ]
distortion_coefficients: !!opencv-matrix
   rows: 5
   cols: 1
   dt: d
   data: [ -0.1, 0.01, 0., 0., 0. ]
R: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 1., 0., 0., 0., 0., -1., 0., 1., 0. ]
t: [ 0., 1.5, 8. ]
"""
    imp = import_camera(read_calibration(_write(tmp_path, "cam.yml", text)))
    assert imp.units == "m" and (imp.camera.width, imp.camera.height) == (768, 576)
    np.testing.assert_allclose(imp.camera.centre, [0.0, -8.0, 1.5])   # C = −Rᵀt
    np.testing.assert_allclose(imp.camera.dist, [-0.1, 0.01, 0, 0, 0])


# ---------------------------------------------------------------------------- 3x4 matrices

def test_projection_text_bare_and_named(tmp_path):
    cam = Camera.look_at("c", 640, 480, position=(2, -5, 3), target=(0, 0, 1), hfov_deg=55)
    P = cam.P * 3.7                                                   # any scale
    bare = "# P of one camera\n" + "\n".join(" ".join(f"{v:.12g}" for v in row) for row in P) + "\n"
    imp = import_camera(read_calibration(_write(tmp_path, "p.txt", bare)), calibration_size=(640, 480))
    np.testing.assert_allclose(imp.camera.centre, cam.centre, atol=1e-9)
    named = "P0: " + " ".join(f"{v:.12g}" for v in P.ravel()) + "\nP1: " + " ".join(
        f"{v:.12g}" for v in Camera.look_at("d", 640, 480, (4, -5, 3), (0, 0, 1), hfov_deg=55).P.ravel())
    cal = read_calibration(_write(tmp_path, "kitti.txt", named), "P1")
    assert cal.cameras == ("P0", "P1") and cal.format == "projection-text"


# ---------------------------------------------------------------------------- units

def test_units_are_detected_declared_or_refused():
    assert decide_units(35621.0)[0] == "mm"
    assert decide_units(7.3)[0] == "m"
    assert decide_units(35621.0, "mm")[1].startswith("millimetres (declared with --units mm")
    with pytest.raises(InputError, match=r"cannot tell the units from \|t\| = 345 .*; give --units mm or --units m"):
        decide_units(345.0)
    with pytest.raises(InputError, match=r"--units m puts the camera 35.6 km from the world origin"):
        decide_units(35621.0, "m")
    with pytest.raises(InputError, match=r"--units mm puts the camera 7.3 mm from the world origin"):
        decide_units(7.3, "mm")
    assert decide_units(0.0, "mm")[0] == "mm"               # a camera at the origin: any unit
    with pytest.raises(InputError, match=r"--units: expected one of auto, mm, m, got 'cm'"):
        decide_units(3.0, "cm")


# ---------------------------------------------------------------------------- bad files

def _bad_cases():
    no_extrinsic = re.sub(r"\s*<Extrinsic[^>]*/>", "", TSAI_XML)
    return {
        "missing section": ("c.xml", no_extrinsic, None, r"missing <Extrinsic>"),
        "missing field": ("c.xml", TSAI_XML.replace(' kappa1="5.1113043639e-03"', ""), None,
                          r"Intrinsic: missing kappa1"),
        "not a number": ("c.xml", TSAI_XML.replace('focal="5.5549183034e+00"', 'focal="five"'), None,
                         r"Intrinsic.focal: expected a number, got 'five'"),
        "negative focal": ("c.xml", TSAI_XML.replace('focal="5.5549183034e+00"', 'focal="-5"'), None,
                           r"focal: expected a positive number"),
        "unknown camera": ("c.xml", TSAI_XML, "View_002", r"no camera 'View_002' \(cameras: View_001\)"),
        "json unknown camera": ("c.json", json.dumps({"View_001": MOT3D_VIEW_001}), "View_002",
                                r"no camera 'View_002' \(cameras: View_001\)"),
        "json missing t": ("c.json", json.dumps({k: v for k, v in MOT3D_VIEW_001.items() if k != "t"}), None,
                           r"missing the translation \(t or tvec\)"),
        "json bad K": ("c.json", json.dumps({**MOT3D_VIEW_001, "K": [[1, 0, 0], [0, 1, 0]]}), None,
                       r"K: expected a 3x3 matrix, got 2x3"),
        "json not rotation": ("c.json", json.dumps({**MOT3D_VIEW_001, "R": np.eye(3).dot(2).tolist()}), None,
                              r"R: expected a rotation matrix"),
        "json k4": ("c.json", json.dumps({**MOT3D_VIEW_001, "dist": [0.1, 0, 0, 0, 0, 0.2, 0, 0]}), None,
                    r"non-zero k4.. terms"),
        "invalid json": ("c.json", '{"K": [1, 2,', None, r"not valid JSON"),
        "no camera": ("c.json", json.dumps({"foo": 1}), None, r"no camera found"),
        "xml other": ("c.xml", "<dataset><frame/></dataset>", None, r"neither a Tsai <Camera>"),
        "bad xml": ("c.xml", "<Camera><Geometry", None, r"not valid XML"),
        "empty": ("c.txt", "", None, r"empty file"),
        "eleven numbers": ("p.txt", " ".join(["1"] * 11), None, r"12 numbers each\), got 11"),
        "prose": ("c.txt", "hello: world\nthis is not a calibration", None, r"unrecognised calibration format"),
        "bad filestorage": ("c.yml", "%YAML:1.0\n---\ncamera_matrix: !!opencv-matrix\n  rows: [", None,
                            r"not a valid OpenCV FileStorage file"),
    }


@pytest.mark.parametrize("case", list(_bad_cases()))
def test_bad_calibration_files_raise_one_input_error(case, tmp_path):
    name, text, camera, message = _bad_cases()[case]
    path = _write(tmp_path, name, text)
    with pytest.raises(InputError, match=message) as info:
        read_calibration(path, camera)
    assert "\n" not in str(info.value) and str(info.value).startswith(str(path))


def test_missing_and_binary_files(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        read_calibration(tmp_path / "nope.xml")
    binary = tmp_path / "b.bin"
    binary.write_bytes(b"\xff\xfe\x00\x81" * 10)
    with pytest.raises(InputError, match="not a text file"):
        read_calibration(binary)


def test_image_size_must_be_known_and_keep_its_aspect(mot3d_file, tsai_file):
    with pytest.raises(InputError, match=r"does not state the image size .* give --calibration-size"):
        import_camera(read_calibration(mot3d_file, "View_001"), image_size=(480, 360))
    with pytest.raises(InputError, match=r"another aspect ratio"):
        import_camera(read_calibration(tsai_file), image_size=(480, 480))


# ---------------------------------------------------------------------------- the command line

def test_cli_import_prints_units_fit_block_centre_and_checks(tsai_file, tmp_path, capsys):
    out = tmp_path / "cam.yaml"
    rc = main(["calibrate", "--import", str(tsai_file), "--image-size", "480x360",
               "--check=-4140,-7400,0,514.8,232.0", "--check=-4140,-7400,1700", "--out", str(out)])
    text = capsys.readouterr().out
    assert rc == 0
    assert "units: millimetres (detected from |t| = 35621), converted to metres" in text
    fit = re.search(r"Tsai -> OpenCV fit error: max (\S+) px over every image pixel", text)
    assert fit and float(fit.group(1)) < 0.01
    assert "rescaled by 0.625 to 480x360 px" in text
    assert "camera centre: (-28.940, -19.529, 7.066) m" in text
    check = re.search(r"check \(-4140, -7400, 0\) mm: Tsai model \((\S+), (\S+)\) px, converted camera "
                      r"\((\S+), (\S+)\) px at 768x576; given \(514.8, 232\): error (\S+) px", text)
    assert check and float(check.group(5)) < 1.0
    block = out.read_text()
    assert "# made with: worldtrack calibrate --import" in block and "--image-size 480x360" in block
    scene = scene_from_dict(yaml.safe_load("cameras:\n" + block +
                                           "floor: {walkable: [{outer: [[-20, -15], [5, -15], [5, 5], [-20, 5]]}]}\n"))
    cam = scene.cameras["View_001"]
    assert (cam.width, cam.height) == (480, 360)
    assert np.linalg.norm(cam.project(CHECK_MM / 1000) - (0.625 * (CHECK_PX + 0.5) - 0.5)) < 1.0


def test_cli_import_json_with_camera_and_calibration_size(mot3d_file, capsys):
    rc = main(["calibrate", "--import", str(mot3d_file), "--camera", "View_001", "--calibration-size", "768x576",
               "--check=-4140,-7400,0,514.8,232.0"])
    text = capsys.readouterr().out
    assert rc == 0 and "imported camera 'View_001'" in text and "  - id: View_001" in text
    err = float(re.search(r"given \(514.8, 232\): error (\S+) px", text).group(1))
    assert err < 1.0


def _cli_bad(tsai_file: Path, mot3d_file: Path, tmp_path: Path):
    return {
        "unknown camera": (["--import", str(tsai_file), "--camera", "View_002"], r"no camera 'View_002'"),
        "several cameras": (["--import", str(mot3d_file)], r"holds 2 cameras"),
        "wrong units": (["--import", str(tsai_file), "--units", "m"],
                        r"^error: \S+View_001.xml: --units m puts the camera 35.6 km"),
        "unknown units": (["--import", str(tsai_file), "--units", "cm"], r"^error: --units: expected mm, m or auto"),
        "no size": (["--import", str(mot3d_file), "--camera", "View_001"], r"--calibration-size"),
        "bad check": (["--import", str(tsai_file), "--check", "1,2"], r"^error: --check: expected X,Y,Z"),
        "bad scale": (["--import", str(tsai_file), "--scale", "zero"], r"^error: --scale: expected a positive"),
        "scale and size": (["--import", str(tsai_file), "--scale", "0.5", "--image-size", "384x288"],
                           r"^error: give --image-size or --scale, not both"),
        "missing file": (["--import", str(tmp_path / "nope.xml")], r"nope.xml: no such file"),
        "both inputs": (["points.csv", "--import", str(tsai_file)], r"^error: give either POINTS.csv"),
        "neither": ([], r"^error: expected POINTS.csv"),
        "import option on csv": (["points.csv", "--units", "mm"], r"^error: --units only applies with --import"),
    }


@pytest.mark.parametrize("case", list(_cli_bad(Path("a"), Path("b"), Path("c"))))
def test_cli_import_errors_are_one_line_and_exit_2(case, tsai_file, mot3d_file, tmp_path, capsys):
    argv, message = _cli_bad(tsai_file, mot3d_file, tmp_path)[case]
    rc = main(["calibrate", *argv])
    captured = capsys.readouterr()
    assert rc == 2
    lines = captured.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), captured.err
    assert re.search(message, lines[0]), lines[0]
    assert "Traceback" not in captured.err
