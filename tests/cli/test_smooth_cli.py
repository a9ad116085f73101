"""``worldtrack smooth``: outputs on a small office scene, and one clear line for bad input."""

import csv

import numpy as np
import pytest

from worldtrack.cli import main
from worldtrack.io.observations import ObservationTable, read_observations, write_observations
from worldtrack.scene import dump_scene
from worldtrack.synth import make_scenario
from worldtrack.synth.observations import head_pixels, head_tracks


@pytest.fixture(scope="module")
def office_files(tmp_path_factory):
    sc = make_scenario("non-overlapping", frames=300, seed=13, people=1, layout="detours", size=(640, 480), legs=10)
    tracks = head_tracks(sc)
    px = head_pixels(sc, noise_px=1.0, rng=2, tracks=tracks)
    d = tmp_path_factory.mktemp("smooth")
    table = ObservationTable(px.time, px.camera.astype(object), px.uv, np.full(len(px.time), 1.0), px.id,
                             np.full(len(px.time), tracks[1].height), np.arange(len(px.time)) + 2, "obs")
    write_observations(d / "obs.csv", table)
    dump_scene(sc.scene, d / "scene.yaml")
    return d, sc, tracks


def test_smooth_writes_the_trajectory_and_the_pictures(office_files, capsys):
    d, sc, tracks = office_files
    assert main(["smooth", str(d / "scene.yaml"), str(d / "obs.csv"), "--out", str(d / "out")]) == 0
    err = capsys.readouterr().err
    assert "person 1:" in err and "start '" in err
    with open(d / "out" / "trajectory.csv") as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0]) == ["id", "t", "x", "y", "z", "vx", "vy", "vz", "sigma_x", "sigma_y", "sigma_z", "rho_xy",
                             "observed", "barrier"]
    t = np.array([float(r["t"]) for r in rows])
    xy = np.array([[float(r["x"]), float(r["y"])] for r in rows])
    seen = np.array([int(r["observed"]) for r in rows]) > 0
    truth = tracks[1].points[np.rint(t * sc.fps).astype(int)]
    assert np.hypot(*(xy[seen] - truth[seen, :2]).T).max() < 0.05
    assert (d / "out" / "floorplan.png").stat().st_size > 10_000 and (d / "out" / "height.png").is_file()


def _bad(d, name, mutate):
    src = list(csv.reader(open(d / "obs.csv")))
    mutate(src)
    path = d / name
    with open(path, "w", newline="") as f:
        csv.writer(f).writerows(src)
    return path


@pytest.mark.parametrize("name, mutate, message", [
    ("unknown.csv", lambda rows: rows[3].__setitem__(1, "cam9"), "row 4: unknown camera 'cam9'"),
    ("backwards.csv", lambda rows: rows[5].__setitem__(0, "0.01"), "row 6: time 0.01 s is before the previous row"),
    ("nan.csv", lambda rows: rows[2].__setitem__(2, "nan"), "row 3: pixel (nan, "),
    ("outside.csv", lambda rows: rows[4].__setitem__(3, "700"), "row 5: pixel (") ,
    ("text.csv", lambda rows: rows[2].__setitem__(3, "abc"), "row 3: v is not a number ('abc')"),
])
def test_bad_observations_give_one_line_naming_the_row(office_files, capsys, name, mutate, message):
    d, _, _ = office_files
    path = _bad(d, name, mutate)
    assert main(["smooth", str(d / "scene.yaml"), str(path), "--out", str(d / "bad")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and "\n" not in err and message in err and name in err
    if name == "outside.csv":
        assert "outside camera cam" in err and "640x480 image" in err


def test_bad_options_and_files(office_files, capsys):
    d, _, _ = office_files
    assert main(["smooth", str(d / "scene.yaml"), str(d / "missing.csv")]) == 2
    assert "missing.csv: no such file" in capsys.readouterr().err
    assert main(["smooth", str(d / "scene.yaml"), str(d / "obs.csv"), "--dt", "-1"]) == 2
    assert "--dt: expected a positive number" in capsys.readouterr().err
    assert main(["smooth", str(d / "scene.yaml"), "cam7=tracks.csv"]) == 2
    assert "unknown camera 'cam7'" in capsys.readouterr().err


def test_tracks_csv_of_a_camera_run_are_read_as_head_pixels(office_files, tmp_path):
    d, sc, tracks = office_files
    from worldtrack.io.observations import observations_from_tracks
    cam = sc.scene.cameras["cam2"]
    head = tracks[1]
    seen = cam.in_image(cam.project(head.points))
    k = np.flatnonzero(seen)[:5]
    path = tmp_path / "tracks.csv"
    with open(path, "w") as f:
        f.write("frame,time,id,x,y,height,width,score,mode,flags\n")
        for i in k:
            f.write(f"{i},{i / sc.fps},1,{head.points[i, 0]},{head.points[i, 1]},{head.points[i, 2]},0.45,0.9,tracking,\n")
        f.write(f"{k[-1] + 1},{(k[-1] + 1) / sc.fps},1,30.0,4.0,1.7,0.45,0.9,tracking,\n")   # far outside: left out
    table = observations_from_tracks(path, cam)
    assert len(table) == 5
    np.testing.assert_allclose(table.uv, cam.project(head.points[k]), atol=1e-6)
    assert read_observations(d / "obs.csv", sc.scene.cameras).people() == [1]


def test_a_person_that_cannot_be_estimated_is_skipped_with_a_line(office_files, capsys, tmp_path):
    d, _, _ = office_files
    rows = list(csv.reader(open(d / "obs.csv")))
    header = rows[0]
    lone = [dict(zip(header, r)) for r in rows[1:3]]
    for r in lone:                                   # person 7: two cameras' rows at one time stamp
        r["id"], r["t"] = "7", "1.0"
    lone[1]["camera"] = "cam1" if lone[0]["camera"] != "cam1" else "cam2"
    path = tmp_path / "two_people.csv"
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, header)
        w.writeheader()
        w.writerows([dict(zip(header, r)) for r in rows[1:]] + lone)
    assert main(["smooth", str(d / "scene.yaml"), str(path), "--out", str(tmp_path / "out"), "--no-plots"]) == 0
    err = capsys.readouterr().err
    assert "person 7: skipped: cannot tell the time step" in err and "person 1:" in err


@pytest.fixture(scope="module")
def feet_files(office_files):
    """The same person with feet pixels (unknown height: no height column) and as boxes."""
    d, sc, tracks = office_files
    px = head_pixels(sc, noise_px=1.0, rng=2, tracks=tracks, feet=True)
    n = len(px.time)
    table = ObservationTable(px.time, px.camera.astype(object), px.uv, np.full(n, 1.0), px.id, np.full(n, np.nan),
                             np.arange(n) + 2, "obs", px.feet_uv, np.full(n, 1.0))
    write_observations(d / "feet.csv", table)
    with open(d / "boxes.csv", "w") as f:
        f.write("t,camera,left,top,right,bottom,sigma_px\n")
        for k in range(n):
            if np.all(np.isfinite(px.feet_uv[k])):
                u = (px.uv[k, 0] + px.feet_uv[k, 0]) / 2
                f.write(f"{px.time[k]},{px.camera[k]},{u - 20},{px.uv[k, 1]},{u + 20},{px.feet_uv[k, 1]},1\n")
    return d, sc, tracks


def test_feet_pixels_fit_the_head_height_and_boxes_give_both(feet_files, capsys):
    d, sc, tracks = feet_files
    table = read_observations(d / "feet.csv", sc.scene.cameras)
    assert table.feet_uv is not None and np.isfinite(table.feet_uv).all(axis=1).mean() > 0.5
    boxes = read_observations(d / "boxes.csv", sc.scene.cameras)
    with_feet = np.isfinite(table.feet_uv).all(axis=1)             # a box: top centre and bottom centre
    np.testing.assert_allclose(boxes.uv[:, 1], table.uv[with_feet, 1], atol=1e-3)
    np.testing.assert_allclose(boxes.feet_uv[:, 1], table.feet_uv[with_feet, 1], atol=1e-3)
    np.testing.assert_allclose(boxes.uv[:, 0], (table.uv[with_feet, 0] + table.feet_uv[with_feet, 0]) / 2, atol=1e-3)
    np.testing.assert_array_equal(boxes.uv[:, 0], boxes.feet_uv[:, 0])
    assert main(["smooth", str(d / "scene.yaml"), str(d / "feet.csv"), "--out", str(d / "feet_out"), "--no-plots"]) == 0
    err = capsys.readouterr().err
    assert "(fitted: feet seen)" in err
    with open(d / "feet_out" / "trajectory.csv") as f:
        rows = list(csv.DictReader(f))
    t = np.array([float(r["t"]) for r in rows])
    z = np.array([float(r["z"]) for r in rows])
    seen = np.array([int(r["observed"]) for r in rows]) > 0
    truth = tracks[1].points[np.rint(t * sc.fps).astype(int)]
    # 17 steps in view: the fitted height is right on average (the scene's 1.70 m would be 0.16 m low)
    assert abs(np.mean(z[seen] - truth[seen, 2])) < 0.03 and np.sqrt(np.mean((z[seen] - truth[seen, 2]) ** 2)) < 0.08


def _feet_bad(d, name, column, value, row=3):
    src = list(csv.reader(open(d / "feet.csv")))
    src[row - 1][src[0].index(column)] = value
    path = d / name
    with open(path, "w", newline="") as f:
        csv.writer(f).writerows(src)
    return path


@pytest.mark.parametrize("name, column, value, message", [
    ("half.csv", "u_feet", "", "row 3: u_feet and v_feet come together"),
    ("feet_nan.csv", "v_feet", "nan", "row 3: feet pixel ("),
    ("feet_text.csv", "u_feet", "left", "row 3: u_feet is not a number ('left')"),
    ("feet_outside.csv", "v_feet", "900", "row 3: feet pixel ("),
    ("feet_sigma.csv", "sigma_feet_px", "0", "row 3: sigma_feet_px must be a positive number"),
])
def test_bad_feet_give_one_line_naming_the_row(feet_files, capsys, name, column, value, message):
    d, _, _ = feet_files
    path = _feet_bad(d, name, column, value)
    assert main(["smooth", str(d / "scene.yaml"), str(path), "--out", str(d / "bad")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and "\n" not in err and message in err and name in err


def test_a_feet_column_alone_is_named(feet_files, capsys, tmp_path):
    d, _, _ = feet_files
    src = [r[:-2] for r in csv.reader(open(d / "feet.csv"))]     # drop v_feet and sigma_feet_px
    with open(tmp_path / "one.csv", "w", newline="") as f:
        csv.writer(f).writerows(src)
    assert main(["smooth", str(d / "scene.yaml"), str(tmp_path / "one.csv"), "--out", str(tmp_path / "o")]) == 2
    assert "u_feet and v_feet come together (only u_feet is given)" in capsys.readouterr().err
