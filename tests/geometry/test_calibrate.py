"""Calibration: normalised DLT, reprojection refinement, planar pose, input checks and the CLI."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
import yaml

from worldtrack.cli import main
from worldtrack.cli.calibrate import read_points
from worldtrack.errors import InputError
from worldtrack.geometry.calibrate import calibrate, dlt, floor_backprojection_errors
from worldtrack.geometry.camera import Camera, normalise_projection
from worldtrack.geometry.rotation import rotation_angle_deg
from worldtrack.scene.load import scene_from_dict

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "calibration"
CENTRE = np.array([-1.0, -1.74, 2.64])


def lab_camera(dist=None, K=None) -> Camera:
    """Kato-lab cam1 at 640x480, with a non-square, off-centre K by default."""
    if K is None:
        K = [[560.0, 0.0, 325.0], [0.0, 548.0, 236.0], [0.0, 0.0, 1.0]]
    return Camera.look_at("cam1", 640, 480, position=CENTRE, target=(-1.0, 0.9, 0.68), K=K, dist=dist)


def box_points(placements=((-1.0, 1.4), (-2.4, 0.9), (0.3, 0.8), (-2.1, 3.3), (0.0, 3.0))) -> np.ndarray:
    """The paper's 0.3 x 0.3 x 1.1 m box, markers at corners and mid-height: (12·k, 3) metres."""
    h = 0.15
    corners = np.array([[-h, -h], [h, -h], [h, h], [-h, h]])
    pts = [[x + cx, y + cy, z] for x, y in placements for z in (0.0, 0.55, 1.1) for cx, cy in corners]
    return np.array(pts)


def noisy(cam: Camera, world: np.ndarray, sigma: float, seed: int = 1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return cam.project(world) + rng.normal(0.0, sigma, (len(world), 2))


# ---------------------------------------------------------------------------- DLT and refinement

def test_dlt_recovers_projection_matrix_up_to_scale():
    K = [[560.0, 1.5, 325.0], [0.0, 548.0, 236.0], [0.0, 0.0, 1.0]]  # with skew: DLT fits all 11 dof
    cam = lab_camera(K=K)
    W = box_points()
    P = dlt(W, cam.project(W))
    np.testing.assert_allclose(P, normalise_projection(cam.P * -3.7), rtol=0, atol=1e-8 * np.abs(cam.P).max())
    np.testing.assert_allclose(Camera.from_projection("c", 640, 480, P).centre, CENTRE, atol=1e-9)


def test_dlt_does_not_depend_on_where_the_world_origin_is():
    # Hartley's normalisation makes the noisy fit invariant to moving and scaling the world
    # coordinates; the unnormalised DLT is not (it weights the equations by the coordinates' size).
    cam = lab_camera()
    W = box_points()
    I = noisy(cam, W, 1.0, seed=5)
    centre = Camera.from_projection("c", 640, 480, dlt(W, I)).centre
    assert np.linalg.norm(centre - CENTRE) < 0.05
    shift = np.array([50.0, -30.0, 20.0])
    moved = Camera.from_projection("c", 640, 480, dlt(W + shift, I)).centre
    np.testing.assert_allclose(moved - shift, centre, atol=1e-6)
    in_mm = Camera.from_projection("c", 640, 480, dlt(W * 1000.0, I)).centre
    np.testing.assert_allclose(in_mm / 1000.0, centre, atol=1e-6)


def test_noise_free_points_give_the_camera_exactly():
    cam = lab_camera()
    W = box_points()
    r = calibrate(W, cam.project(W), 640, 480, camera_id="cam1")
    assert r.success, r.message
    assert r.camera.id == "cam1" and (r.camera.width, r.camera.height) == (640, 480)
    np.testing.assert_allclose(r.camera.centre, CENTRE, atol=1e-6)
    np.testing.assert_allclose(r.camera.K, cam.K, atol=1e-6)
    assert rotation_angle_deg(cam.R, r.camera.R) < 1e-6
    assert r.rms < 1e-6
    assert r.floor_errors.shape == (20,) and np.all(r.floor_errors < 1e-6)
    assert r.warnings == []


def test_half_pixel_noise_gives_rms_near_noise_and_centre_within_2cm():
    cam = lab_camera()
    W = box_points()
    r = calibrate(W, noisy(cam, W, 0.5), 640, 480)
    assert r.success
    assert r.n_points == 60 and r.residuals.shape == (60, 2) and r.per_point_error.shape == (60,)
    # Per-point error is a 2-D length: its RMS is √2·σ·√(1 − 10/120) ≈ 0.68 px for σ = 0.5 px.
    assert 0.5 < r.rms < 0.8
    assert np.linalg.norm(r.camera.centre - CENTRE) < 0.02
    assert abs(r.camera.K[0, 0] - 560.0) < 10
    np.testing.assert_allclose(r.residuals, r.camera.project(W) - noisy(cam, W, 0.5), atol=1e-9)
    np.testing.assert_allclose(r.per_point_error, np.linalg.norm(r.residuals, axis=1))
    assert r.rms == pytest.approx(np.sqrt(np.mean(r.per_point_error ** 2)))


def test_refinement_is_a_minimum_of_the_reprojection_error():
    cam = lab_camera()
    W = box_points()
    I = noisy(cam, W, 1.0, seed=4)
    r = calibrate(W, I, 640, 480)

    def rms(c: Camera) -> float:
        return float(np.sqrt(np.mean(np.sum((c.project(W) - I) ** 2, axis=1))))

    assert r.rms == pytest.approx(rms(r.camera))
    linear = Camera.from_projection("c", 640, 480, dlt(W, I))
    no_skew = Camera("c", 640, 480, linear.K * [[1, 0, 1], [1, 1, 1], [1, 1, 1]], linear.R, linear.t)
    assert r.rms < rms(no_skew)                        # the refinement's starting point
    c = r.camera
    for dK in ([[1, 0, 0], [0, 0, 0], [0, 0, 0]], [[0, 0, 0], [0, 0, 1], [0, 0, 0]]):
        for sign in (-1, 1):
            assert r.rms < rms(Camera("c", 640, 480, c.K + sign * np.array(dK), c.R, c.t))
    for axis in np.eye(3):
        for sign in (-1, 1):
            moved = Camera("c", 640, 480, c.K, c.R, c.t - c.R @ (sign * 0.005 * axis))
            assert r.rms < rms(moved)


def test_known_intrinsics_are_held_fixed():
    cam = lab_camera()
    W = box_points()
    k = [560.0, 548.0, 325.0, 236.0]
    r = calibrate(W, noisy(cam, W, 0.5), 640, 480, intrinsics=k)
    np.testing.assert_array_equal(r.camera.K, cam.K)
    assert np.linalg.norm(r.camera.centre - CENTRE) < 0.01


# ---------------------------------------------------------------------------- lens distortion

def test_distortion_fit_recovers_k1_and_lowers_rms():
    cam = lab_camera(dist=[-0.20, 0.04, 0, 0, 0])
    W = box_points()
    I = noisy(cam, W, 0.3, seed=2)
    plain = calibrate(W, I, 640, 480)
    fitted = calibrate(W, I, 640, 480, distortion=True)
    assert fitted.success
    assert fitted.camera.dist[0] == pytest.approx(-0.20, abs=0.03)
    # k2 trades off against k1 inside this camera's field (r ≤ 0.54); the displacement they
    # give together, f·r·(k1 r² + k2 r⁴), must match to a fraction of a pixel.
    r = np.linspace(0.0, 0.5, 11)
    k1, k2 = fitted.camera.dist[:2]
    np.testing.assert_allclose(560 * r * (k1 * r**2 + k2 * r**4), 560 * r * (-0.2 * r**2 + 0.04 * r**4), atol=0.5)
    assert fitted.rms < 0.5 and plain.rms > 1.5
    assert np.linalg.norm(fitted.camera.centre - CENTRE) < 0.02 < np.linalg.norm(plain.camera.centre - CENTRE)
    assert not any("--distortion" in w for w in plain.warnings)           # 1.7 px: not flagged yet
    k1_only = calibrate(W, noisy(lab_camera(dist=[-0.2, 0, 0, 0, 0]), W, 0.3, seed=2), 640, 480, distortion=1)
    assert k1_only.camera.dist[0] == pytest.approx(-0.20, abs=0.01)


def test_noise_free_distorted_points_fit_exactly():
    # The optimiser's projection and Camera.project must be the same model.
    cam = lab_camera(dist=[-0.25, 0.05, 0, 0, 0.01])
    W = box_points()
    r = calibrate(W, cam.project(W), 640, 480, distortion=3)
    assert r.rms < 1e-5
    np.testing.assert_allclose(r.camera.dist, cam.dist, atol=1e-4)
    np.testing.assert_allclose(r.camera.centre, CENTRE, atol=1e-6)
    np.testing.assert_allclose(r.floor_errors, 0.0, atol=1e-6)


def test_one_radial_term():
    cam = lab_camera(dist=[-0.1, 0, 0, 0, 0])
    W = box_points()
    r = calibrate(W, cam.project(W), 640, 480, distortion=1)
    assert r.camera.dist[0] == pytest.approx(-0.1, abs=1e-6)
    assert np.all(r.camera.dist[1:] == 0)


# ---------------------------------------------------------------------------- planar points

def test_floor_points_with_known_intrinsics_give_the_pose():
    cam = lab_camera()
    xs, ys = np.meshgrid(np.linspace(-2.4, 0.4, 5), np.linspace(0.2, 3.5, 5))
    W = np.column_stack([xs.ravel(), ys.ravel(), np.zeros(25)])
    k = [560.0, 548.0, 325.0, 236.0]
    exact = calibrate(W, cam.project(W), 640, 480, intrinsics=k)
    np.testing.assert_allclose(exact.camera.centre, CENTRE, atol=1e-6)
    assert rotation_angle_deg(cam.R, exact.camera.R) < 1e-6
    r = calibrate(W, noisy(cam, W, 0.5), 640, 480, intrinsics=k)
    assert r.success and np.linalg.norm(r.camera.centre - CENTRE) < 0.03
    assert 0.3 < r.rms < 0.8


def test_tilted_plane_with_known_intrinsics_gives_the_pose():
    cam = lab_camera()
    # A wall-like plane through (-1, 2, 0), tilted: points X = -1 + a, Y = 2 + 0.3 b, Z = b.
    a, b = np.meshgrid(np.linspace(-1.2, 1.2, 5), np.linspace(0.0, 1.6, 4))
    W = np.column_stack([-1.0 + a.ravel(), 2.0 + 0.3 * b.ravel(), b.ravel()])
    r = calibrate(W, cam.project(W), 640, 480, intrinsics=[560.0, 548.0, 325.0, 236.0])
    np.testing.assert_allclose(r.camera.centre, CENTRE, atol=1e-6)


def test_floor_points_without_intrinsics_say_what_is_needed():
    cam = lab_camera()
    W = box_points()
    W = W[W[:, 2] == 0] + [0, 0, 0.0004]                   # within 1 mm counts as one plane
    with pytest.raises(InputError, match=r"all points lie on the plane Z = 0\.000 m.*"
                                         r"give --intrinsics fx,fy,cx,cy or add points at other heights"):
        calibrate(W, cam.project(W), 640, 480)


# ---------------------------------------------------------------------------- floor errors

def test_floor_errors_match_an_independent_back_projection():
    cam = lab_camera()
    W = box_points()
    I = noisy(cam, W, 1.0, seed=3)
    r = calibrate(W, I, 640, 480)
    # Independent: the floor homography of P, H = P[:, (0, 1, 3)], maps (X, Y, 1) to the image.
    H = r.camera.P[:, [0, 1, 3]]
    g = np.column_stack([I, np.ones(len(I))]) @ np.linalg.inv(H).T
    xy = g[:, :2] / g[:, 2:]
    floor = W[:, 2] == 0
    expected = np.linalg.norm(xy[floor] - W[floor, :2], axis=1)
    np.testing.assert_allclose(r.floor_errors, expected, rtol=1e-9, atol=1e-12)
    np.testing.assert_array_equal(r.on_floor, floor)
    assert 0 < r.floor_error_mean < 0.05


def test_floor_errors_split_into_image_centre_and_edge():
    cam = lab_camera()
    W = box_points()
    I = noisy(cam, W, 0.5)
    r = calibrate(W, I, 640, 480)
    pp = r.camera.K[:2, 2]
    corners = np.array([[-0.5, -0.5], [639.5, -0.5], [-0.5, 479.5], [639.5, 479.5]])
    r_max = np.max(np.linalg.norm(corners - pp, axis=1))      # ≈ 400 px for a central principal point
    radius = np.linalg.norm(I[r.on_floor] - pp, axis=1)
    np.testing.assert_array_equal(r.floor_in_centre, radius < r_max / 2)
    assert r.floor_in_centre.any() and not r.floor_in_centre.all()
    assert r.floor_error_centre == pytest.approx(r.floor_errors[r.floor_in_centre].mean())
    assert r.floor_error_edge == pytest.approx(r.floor_errors[~r.floor_in_centre].mean())


def test_floor_backprojection_errors_with_a_known_offset():
    cam = lab_camera()
    W = np.array([[-1.0, 1.0, 0.0], [0.0, 2.0, 0.0]])
    assert np.allclose(floor_backprojection_errors(cam, W + [0.03, -0.04, 0], cam.project(W)), 0.05)


def test_no_floor_points_gives_nan_and_a_warning():
    cam = lab_camera()
    W = box_points()
    W = W[W[:, 2] > 0]
    r = calibrate(W, cam.project(W), 640, 480)
    assert r.floor_errors.shape == (0,)
    assert np.isnan(r.floor_error_centre) and np.isnan(r.floor_error_edge) and np.isnan(r.floor_error_mean)
    assert any("no points on the floor" in w for w in r.warnings)


# ---------------------------------------------------------------------------- warnings and bad input

def test_fewer_than_20_points_warns():
    cam = lab_camera()
    W = box_points(((-1.0, 1.4),))
    r = calibrate(W, noisy(cam, W, 0.2), 640, 480)
    assert r.success and r.n_points == 12
    assert any("the paper advises ≥ 20" in w for w in r.warnings)


def test_an_outlier_and_points_outside_the_image_are_named():
    cam = lab_camera()
    W = box_points()
    I = noisy(cam, W, 0.3)
    I[7] += [25.0, -18.0]
    r = calibrate(W, I, 640, 480)
    assert any(w.startswith("point 7 has error") for w in r.warnings)
    r = calibrate(W, cam.project(W), 400, 300)
    assert any("outside the 400x300 image" in w and "check the image size" in w for w in r.warnings)


def test_points_behind_the_camera_make_the_fit_fail():
    cam = lab_camera()
    W = box_points()
    I = cam.project(W)
    # A point mirrored through the camera centre projects to the same pixel, but from behind.
    W_bad = W.copy()
    W_bad[[4, 9]] = 2 * CENTRE - W[[4, 9]]
    r = calibrate(W_bad, I, 640, 480)
    assert not r.success
    assert r.message == "2 points are behind the fitted camera (point 4, point 9): check the signs of their coordinates"
    mirrored = calibrate(W * [1, 1, -1], I, 640, 480)          # Z down
    assert not mirrored.success and "look mirrored" in mirrored.message


def test_camera_below_the_floor_warns():
    cam = Camera.look_at("c", 640, 480, position=(0, -4, -1.0), target=(0, 0, -2.0), hfov_deg=60)
    W = box_points() + [0.0, 0.0, -3.0]
    r = calibrate(W, cam.project(W), 640, 480)
    assert r.success
    assert any("camera centre is at Z = -1.000 m, not above the floor" in w for w in r.warnings)


def _degenerate_cases():
    cam = lab_camera()
    W = box_points()
    I = cam.project(W)
    nan = I.copy()
    nan[4, 1] = np.nan
    inf = W.copy()
    inf[9, 2] = np.inf
    twice_pair = (np.vstack([W, W[3]]), np.vstack([I, I[3]]))
    twice_world = (np.vstack([W, W[3]]), np.vstack([I, I[3] + 5]))
    line = np.column_stack([np.linspace(-2, 0, 8), np.linspace(0, 3, 8), np.zeros(8)])
    wall = np.column_stack([np.linspace(-2, 0, 8), np.full(8, 2.0), np.tile([0.0, 1.0], 4)])
    tilted = np.column_stack([np.tile([-2.0, -1.0, 0.0], 3), np.repeat([1.0, 2.0, 3.0], 3), np.repeat([0, .5, 1], 3)])
    return [
        ("five points", W[:5], I[:5], {}, r"at least 6 points.*got 5"),
        ("lengths", W, I[:-1], {}, r"as many image points as world points, got 60 world and 59 image"),
        ("shape", W[:, :2], I, {}, r"world points: expected an \(N, 3\) array"),
        ("nan", W, nan, {}, r"point 4: expected finite numbers, got y = nan"),
        ("inf", inf, I, {}, r"point 9: expected finite numbers, got Z = inf"),
        ("same pair", *twice_pair, {}, r"point 3 and point 60 are the same pair twice"),
        ("same world", *twice_world, {}, r"point 3 and point 60 give the same world point .* mislabelled"),
        ("collinear", line, cam.project(line), {}, r"all world points lie on one line"),
        ("wall", wall, cam.project(wall), {}, r"all points lie on one plane .*--intrinsics.* off that plane"),
        ("tilted", tilted, cam.project(tilted), {}, r"all points lie on one plane"),
        ("image line", W, np.column_stack([I[:, 0], 2 * I[:, 0] + 1]), {}, r"all image points lie on one line"),
        ("intrinsics", W, I, {"intrinsics": [500, -500, 320, 240]}, r"intrinsics: expected 4 finite numbers"),
        ("k3 few", W[:12], I[:12], {"distortion": 3}, r"k3 needs at least 20 points, got 12"),
        ("terms", W, I, {"distortion": 4}, r"distortion: expected"),
    ]


@pytest.mark.parametrize("name, world, image, kwargs, message", _degenerate_cases(),
                         ids=[c[0] for c in _degenerate_cases()])
def test_degenerate_input_raises_input_error(name, world, image, kwargs, message):
    with pytest.raises(InputError, match=message) as info:
        calibrate(world, image, 640, 480, **kwargs)
    assert "\n" not in str(info.value)


def test_dlt_rejects_coplanar_points_even_on_the_floor():
    cam = lab_camera()
    W = box_points()
    W = W[W[:, 2] == 0]
    with pytest.raises(InputError, match="one plane"):
        dlt(W, cam.project(W))


def test_point_names_appear_in_messages():
    cam = lab_camera()
    W = box_points()
    I = cam.project(W)
    I[2, 0] = np.nan
    with pytest.raises(InputError, match=r"^line 9: expected finite numbers, got x = nan$"):
        calibrate(W, I, 640, 480, point_names=[f"line {i + 7}" for i in range(len(W))])


# ---------------------------------------------------------------------------- command line

def _write_csv(path: Path, world: np.ndarray, image: np.ndarray, header: str = "X,Y,Z,x,y",
               comments: str = "# image_size: 640x480\n") -> Path:
    rows = "\n".join(",".join(f"{v:.6f}" for v in row) for row in np.hstack([world, image]))
    path.write_text(comments + header + "\n" + rows + "\n")
    return path


def test_cli_prints_block_centre_table_rms_and_floor_error(tmp_path, capsys):
    cam = lab_camera()
    W = box_points()
    csv_path = _write_csv(tmp_path / "pts.csv", W, noisy(cam, W, 0.5), header="x,y,z,X,Y")
    out = tmp_path / "cam1.yaml"
    assert main(["calibrate", str(csv_path), "--id", "cam1", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "camera centre: (" in text and "reprojection error: RMS" in text
    assert "floor back-projection error (20 points at Z = 0)" in text
    table = [line for line in text.splitlines() if re.match(r"^\s+\d+\s+\d+\s+-?\d", line)]
    assert len(table) == 60
    # The written block pastes under `cameras:` and loads back to the same camera.
    block = out.read_text()
    scene = scene_from_dict(yaml.safe_load("cameras:\n" + block +
                                           "floor: {walkable: [{outer: [[-3, -2], [2, -2], [2, 4], [-3, 4]]}]}\n"))
    loaded = scene.cameras["cam1"]
    assert np.linalg.norm(loaded.centre - CENTRE) < 0.02
    printed = re.search(r"camera centre: \((\S+), (\S+), (\S+)\) m", text)
    np.testing.assert_allclose([float(v) for v in printed.groups()], loaded.centre, atol=6e-4)
    assert "cameras:" in text and "  - id: cam1" in text


def test_cli_help_explains_the_csv(capsys):
    with pytest.raises(SystemExit) as info:
        main(["calibrate", "--help"])
    assert info.value.code == 0
    text = capsys.readouterr().out
    assert "X,Y,Z,x,y" in text and "metres" in text and "pixels" in text and "image_size" in text


def _bad_files(tmp_path: Path):
    cam = lab_camera()
    W = box_points()
    I = cam.project(W)
    rows = [",".join(f"{v:.4f}" for v in row) for row in np.hstack([W, I])]
    good = "\n".join(rows)
    head = "# image_size: 640x480\nX,Y,Z,x,y\n"            # data from line 3
    text_rows = rows.copy()
    text_rows[3] = ",".join(c if k != 2 else "abc" for k, c in enumerate(text_rows[3].split(",")))
    nan_rows = rows.copy()
    nan_rows[5] = "1,2,nan,3,4"
    return {
        "missing": (None, [], r"no such file"),
        "text": (head + "\n".join(text_rows), [],
                 r"line 6: column Z: expected a number, got 'abc'"),
        "extra": ("X,Y,Z,x,y,id,note\n" + good, ["--image-size", "640x480"],
                  r"line 1: unexpected column\(s\) 'id', 'note'"),
        "header": ("X,Y,Z,u,v\n" + good, ["--image-size", "640x480"], r"line 1: expected the header X,Y,Z,x,y"),
        "no header": (good, ["--image-size", "640x480"], r"line 1: expected the header X,Y,Z,x,y before"),
        "short row": (head + good + "\n1,2,3", [], r"line 63: expected 5 values X,Y,Z,x,y, got 3"),
        "few": (head + "\n".join(good.splitlines()[:4]), [], r"at least 6 points.*got 4"),
        "coplanar": (head + "\n".join(r for r in good.splitlines() if r.split(",")[2] == "0.0000"), [],
                     r"all points lie on the plane Z = 0.000 m; give --intrinsics"),
        "nan": (head + "\n".join(nan_rows), [], r"line 8: expected finite numbers, got Z = nan"),
        "duplicate": (head + good + "\n" + good.splitlines()[0], [],
                      r"line 3 and line 63 are the same pair twice"),
        "no size": ("X,Y,Z,x,y\n" + good, [], r"image size unknown; give --image-size"),
        "bad size comment": ("# image_size: 640\nX,Y,Z,x,y\n" + good, [], r"line 1: image_size: expected WxH"),
        "empty": ("", [], r"expected a header line X,Y,Z,x,y"),
        "bad size": (head + good, ["--image-size", "640by480"], r"^error: --image-size: expected WxH"),
        "bad intrinsics": (head + good, ["--intrinsics", "500,500,320"], r"^error: --intrinsics: expected fx,fy"),
    }


@pytest.mark.parametrize("case", list(_bad_files(Path("."))))
def test_cli_bad_input_is_one_error_line_and_exit_2(case, tmp_path, capsys):
    text, extra, message = _bad_files(tmp_path)[case]
    path = tmp_path / "points.csv"
    if text is not None:
        path.write_text(text)
    rc = main(["calibrate", str(path), *extra])
    captured = capsys.readouterr()
    assert rc == 2
    lines = captured.err.splitlines()
    assert len(lines) == 1, captured.err
    assert lines[0].startswith("error: ")
    if not message.startswith("^"):
        assert lines[0].startswith(f"error: {path}: ")
    assert re.search(message, lines[0]), lines[0]
    assert "Traceback" not in captured.err and captured.out == ""


# ---------------------------------------------------------------------------- the bundled examples

def _stated(path: Path) -> tuple[np.ndarray, float]:
    text = path.read_text()
    centre = re.search(r"# true camera centre: \((\S+), (\S+), (\S+)\) m", text)
    sigma = re.search(r"# image noise: Gaussian, sigma = (\S+) px", text)
    return np.array([float(v) for v in centre.groups()]), float(sigma.group(1))


def test_example_cam1_recovers_its_stated_centre():
    path = EXAMPLES / "lab_cam1_points.csv"
    centre, sigma = _stated(path)
    pts = read_points(path)
    assert pts.image_size == (640, 480) and 30 <= len(pts.world) <= 40 and np.sum(pts.world[:, 2] == 0) >= 8
    r = calibrate(pts.world, pts.image, *pts.image_size)
    assert r.success and r.warnings == []
    assert np.linalg.norm(r.camera.centre - centre) < 0.02
    assert sigma * 0.6 < r.rms < np.sqrt(2) * sigma      # per-point RMS of 2-D noise is √2·σ before fitting
    assert r.floor_error_mean < 0.02


def test_example_cam2_needs_its_distortion():
    path = EXAMPLES / "lab_cam2_points.csv"
    centre, sigma = _stated(path)
    k1 = float(re.search(r"distortion k1 = (\S+),", path.read_text()).group(1))
    pts = read_points(path)
    plain = calibrate(pts.world, pts.image, *pts.image_size)
    fitted = calibrate(pts.world, pts.image, *pts.image_size, distortion=True)
    assert plain.rms > 5.0 and fitted.rms < np.sqrt(2) * sigma
    assert fitted.camera.dist[0] == pytest.approx(k1, abs=0.01)
    assert np.linalg.norm(fitted.camera.centre - centre) < 0.02
    assert fitted.floor_error_mean < plain.floor_error_mean


def test_cli_distortion_on_the_wide_angle_example(capsys):
    assert main(["calibrate", str(EXAMPLES / "lab_cam2_points.csv"), "--id", "cam2", "--distortion"]) == 0
    text = capsys.readouterr().out
    assert re.search(r"lens distortion \(radial\): k1 = -0\.2[45]\d*, k2 = ", text)
    assert "    distortion: [-0.2" in text and "warnings:" not in text


def test_cli_failed_fit_prints_the_report_and_one_error_line(tmp_path, capsys):
    cam = lab_camera()
    W = box_points()
    path = _write_csv(tmp_path / "mirrored.csv", W * [1, 1, -1], cam.project(W))
    assert main(["calibrate", str(path)]) == 2
    captured = capsys.readouterr()
    assert "camera centre:" in captured.out
    assert captured.err.splitlines() == [f"error: {path}: calibration failed: every point is behind the fitted "
                                         "camera: the world coordinates look mirrored (expected right-handed "
                                         "axes with Z up)"]
