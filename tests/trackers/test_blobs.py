"""The blob baseline (MOG2 blobs → foot points → Stone Soup) on small rendered scenes with exact truth.

People are drawn as the filled outlines of 1.65 m × 0.40 m ellipsoids (the conic of each ellipsoid,
evaluated at pixel centres) walking along straight lines at known speeds over a fixed textured
background with seeded sensor noise, so every position and velocity is known exactly.

Accuracy bound. A clean blob's foot point is off by (a) the lowest point of an ellipsoid's outline
not being its floor contact point (0.00–0.04 m in these views) and (b) whole pixel rows: in the
320×240, 70° view from 3 m up, one row at the feet spans 0.035 m of floor at y = 3 m and 0.08 m
at y = 5.4 m, the far end of the walks (``row_footprint``). A track's error is then at most
(a) + (b) ≈ 0.12 m, and on average (a) + half a row < 0.06 m; those are the bounds asserted (the
baseline reaches about 0.02 m mean, 0.045 m worst here).
"""

from __future__ import annotations

import sys

import cv2
import numpy as np
import pytest

from worldtrack.errors import InputError
from worldtrack.foreground.background import AdaptiveBackground, StaticBackground
from worldtrack.geometry.quadric import ellipse_mask, ellipsoid_conics, person_ellipsoid
from worldtrack.trackers.base import Frame
from worldtrack.scene import scene_from_dict

from _render import texture  # tests/trackers/_render.py

pytest.importorskip("stonesoup")

from worldtrack.trackers import make_tracker  # noqa: E402
from worldtrack.trackers.blobs import BlobConfig, BlobTracker, merge_points  # noqa: E402

W, H = 320, 240
FRONT = {"id": "front", "image_size": [W, H], "position": [0, -1, 3], "look_at": [0, 4, 0.5], "hfov_deg": 70}
BACK = {"id": "back", "image_size": [W, H], "position": [0, 9, 3], "look_at": [0, 4, 0.5], "hfov_deg": 70}
FLOOR = {"walkable": [{"outer": [[-3, 0], [3, 0], [3, 8], [-3, 8]]}]}
PERSON_BGR = (40, 30, 140)


def make_scene(*cameras):
    return scene_from_dict({"name": "blobs-test", "cameras": list(cameras), "floor": FLOOR})


def render(cam, background, xy, rng) -> np.ndarray:
    """``background`` with ellipsoid people standing at ``xy`` (N, 2) m, plus sensor noise (σ = 2)."""
    img = background.astype(np.float32)
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    if len(xy):
        centres, radii = person_ellipsoid(xy, 1.65, 0.40)
        for C in ellipsoid_conics(cam.P, centres, radii):
            img[ellipse_mask(C, (H, W))] = PERSON_BGR
    img += rng.normal(0.0, 2.0, img.shape)
    return np.clip(img, 0, 255).astype(np.uint8)


def run(tracker, scene, backgrounds, positions, times, seed=1):
    """Step ``tracker`` over ``positions(t) -> (N, 2)`` at ``times``; returns [(t, truth, tracks)]."""
    rng = np.random.default_rng(seed)
    out = []
    for i, t in enumerate(times):
        xy = positions(t)
        frames = {cid: Frame(render(scene.cameras[cid], bg, xy, rng), float(t), i) for cid, bg in backgrounds.items()}
        out.append((float(t), xy, tracker.step(frames, float(t))))
    return out


def walking_apart(t):
    """Two people starting 0.8 m apart, walking apart at 1.0 m/s each (0.6, 0.8 and −0.6, 0.8)."""
    p0 = np.array([[-0.4, 3.0], [0.4, 3.0]])
    v = np.array([[-0.6, 0.8], [0.6, 0.8]])
    return p0 + v * t


def errors_by_id(history):
    """{track id: [(t, distance to the nearest true person, index of that person)]}."""
    out: dict[int, list] = {}
    for t, truth, tracks in history:
        for tr in tracks:
            d = np.hypot(*(truth - [tr.x, tr.y]).T)
            out.setdefault(tr.id, []).append((t, float(d.min()), int(d.argmin())))
    return out


# ---------------------------------------------------------------------------- detection

def row_footprint(cam, xy) -> float:
    """Floor length (m) of one image row at the foot of a person standing at ``xy``."""
    uv = cam.project([[*xy, 0.0]])[0]
    p = cam.backproject([uv, uv - [0.0, 1.0]], 0.0)[:, :2]
    return float(np.hypot(*(p[0] - p[1])))


def test_foot_point_of_a_clean_blob():
    """One blob per person, its foot point within 0.04 m + one pixel row of the truth, anywhere in view.

    0.04 m: the lowest point of an ellipsoid's outline is not its floor contact point; for these
    positions the exact outline's lowest row back-projects 0.00–0.04 m from the contact point.
    """
    scene = make_scene(FRONT)
    cam, bg = scene.cameras["front"], texture(0)
    rng = np.random.default_rng(0)
    for xy in [(0.0, 3.0), (-1.0, 3.0), (-2.1, 5.2), (2.0, 6.0), (0.0, 7.0), (-2.5, 4.0)]:
        tracker = BlobTracker(scene, {"front": StaticBackground(bg)})
        pts = tracker.detect("front", render(cam, bg, [xy], rng))
        assert pts.shape == (1, 2)
        assert np.hypot(*(pts[0] - xy)) < 0.04 + row_footprint(cam, xy), (xy, pts)


def test_box_foot_point_leans_outwards_off_centre():
    """The bounding-box alternative is off by the lean of off-centre people (≥ 0.08 m at x = −2.5)."""
    scene = make_scene(FRONT)
    cam, bg = scene.cameras["front"], texture(0)
    img = render(cam, bg, [(-2.5, 4.0)], np.random.default_rng(0))
    box = BlobTracker(scene, {"front": StaticBackground(bg)}, BlobConfig(detection={"foot_point": "box"})).detect("front", img)
    bottom = BlobTracker(scene, {"front": StaticBackground(bg)}).detect("front", img)
    assert box[0, 0] < -2.5 - 0.08
    assert abs(bottom[0, 0] + 2.5) < 0.03


def test_blob_touching_the_bottom_border_gives_no_detection():
    scene = make_scene(FRONT)
    cam, bg = scene.cameras["front"], texture(0)
    near, far = (0.3, 0.8), (0.3, 2.5)
    # The near person's feet are below the image, the rest of them in it; the far one is whole.
    assert cam.project([[*near, 0.0]])[0, 1] > H and cam.in_image(cam.project([[*near, 1.0]]))[0]
    assert cam.in_image(cam.project([[*far, 0.0]]))[0]
    # Without the border rule the near blob (2400 px, bottom edge on the floor at y ≈ 1.2 m)
    # would pass: no area-fraction test, so only the border can drop it.
    assert scene.walkable.contains(cam.backproject([[160.0, H - 0.5]], 0.0)[:, :2])[0]
    tracker = BlobTracker(scene, {"front": StaticBackground(bg)}, BlobConfig(detection={"min_area_fraction": 0.0}))
    rng = np.random.default_rng(0)
    assert tracker.detect("front", render(cam, bg, [near], rng)).shape == (0, 2)
    mask = tracker.last_masks["front"]
    assert mask.sum() > 2000 and mask[-1].any()  # the blob is there, on the border
    tracker = BlobTracker(scene, {"front": StaticBackground(bg)})
    assert tracker.detect("front", render(cam, bg, [far], rng)).shape == (1, 2)


def test_small_blobs_and_points_off_the_floor_are_dropped():
    scene = make_scene(FRONT)
    cam, bg = scene.cameras["front"], texture(0)
    img = render(cam, bg, [(0.0, 9.0)], np.random.default_rng(0))  # behind the back wall (y ≤ 8)
    cv2.circle(img, (60, 200), 3, (0, 0, 0), -1)                     # < 30 px of "noise" on the floor
    tracker = BlobTracker(scene, {"front": StaticBackground(bg)}, BlobConfig(detection={"min_area_fraction": 0.0}))
    assert tracker.detect("front", img).shape == (0, 2)
    _, _, stats, _ = cv2.connectedComponentsWithStats(tracker.last_masks["front"])
    assert sorted(stats[1:, 4] >= tracker.config.detection.min_area_px) == [False, True]  # both were foreground


def test_merge_points_averages_across_cameras_only():
    xy = np.array([[0.0, 0.0], [0.2, 0.0], [0.1, 0.1], [3.0, 0.0], [3.3, 0.0]])
    cams = np.array([0, 1, 0, 1, 1])
    out = merge_points(xy, cams, 0.5)
    # (0, 0)+(0.2, 0) or (0.2, 0)+(0.1, 0.1) may pair; never the two of camera 0, never the two at x≈3.
    assert len(out) == 4
    np.testing.assert_allclose(np.sort(out[:, 0])[-2:], [3.0, 3.3])
    assert merge_points(xy, np.zeros(5, int), 0.5).shape == (5, 2)
    np.testing.assert_allclose(merge_points([[0, 0], [0.3, 0.4]], [0, 1], 0.5), [[0.15, 0.2]])
    np.testing.assert_allclose(merge_points([[0, 0], [0.3, 0.5]], [0, 1], 0.5), [[0, 0], [0.3, 0.5]])


# ---------------------------------------------------------------------------- tracking

@pytest.mark.parametrize("fps", [5.0, 20.0])
def test_two_people_walking_apart(fps):
    scene = make_scene(FRONT)
    bg = {"front": texture(0)}
    tracker = BlobTracker(scene, {"front": StaticBackground(bg["front"])})
    history = run(tracker, scene, bg, walking_apart, np.arange(0, 3.0, 1 / fps))
    errs = errors_by_id(history)
    assert sorted(errs) == [1, 2], "two distinct ids, no others"
    for tid, rows in errs.items():
        t, d, who = np.array(rows).T
        assert len(set(who)) == 1, f"track {tid} switched person"
        assert d.mean() < 0.06 and d.max() < 0.12, (tid, d.mean(), d.max())
        # Confirmed from the init_min_points-th frame on and never lost.
        assert t[0] == pytest.approx((tracker.config.lifecycle.init_min_points - 1) / fps)
        assert len(t) == len(history) - (tracker.config.lifecycle.init_min_points - 1)
    assert errs[1][0][2] != errs[2][0][2]
    final = history[-1][2]
    assert all(tr.mode == "tracking" and not tr.flags and tr.score == 1.0 for tr in final)
    assert all(0.0 < tr.sigma < 0.1 for tr in final)
    assert [tr.id for tr in tracker.position_map] == [1, 2]
    assert set(tracker.last_masks) == {"front"}


def test_velocity_in_metres_per_second_at_any_frame_rate():
    """The same walk at 5 and 20 frames/s gives the same velocity in m/s: real time stamps."""
    scene = make_scene(FRONT)
    bg = {"front": texture(0)}
    v_true = np.array([0.8, 0.6])

    def walk(t):
        return np.array([[-1.5, 3.0]]) + v_true * t

    means = []
    for fps in (5.0, 20.0):
        tracker = BlobTracker(scene, {"front": StaticBackground(bg["front"])})
        history = run(tracker, scene, bg, walk, np.arange(0, 4.0, 1 / fps))
        # Second half of the walk, once the filter has converged.
        v = np.array([[tr.vx, tr.vy] for t, _, tracks in history if t >= 2.0 for tr in tracks])
        assert len(v) == len([t for t, _, _ in history if t >= 2.0]), "one track throughout"
        means.append(v.mean(axis=0))
        np.testing.assert_allclose(means[-1], v_true, atol=0.05)
    # With dt = 1 frame the two would differ 4× (a velocity in metres per frame).
    np.testing.assert_allclose(means[0], means[1], atol=0.05)


@pytest.mark.parametrize("delete_after_s", [0.5, 1.0])
def test_track_ends_after_the_configured_time_without_detections(delete_after_s):
    scene = make_scene(FRONT)
    bg = {"front": texture(0)}
    fps, gone_at = 10.0, 1.5

    def walk(t):
        return np.array([[0.0, 3.0]]) + np.array([[0.0, 1.0]]) * t if t < gone_at else np.zeros((0, 2))

    tracker = BlobTracker(scene, {"front": StaticBackground(bg["front"])},
                          BlobConfig(lifecycle={"delete_after_s": delete_after_s}))
    history = run(tracker, scene, bg, walk, np.arange(0, 3.5, 1 / fps))
    last_update = gone_at - 1 / fps
    for t, _, tracks in history:
        if gone_at <= t < last_update + delete_after_s - 1e-6:
            assert [tr.id for tr in tracks] == [1], t
            assert tracks[0].flags == {"coasting"} and tracks[0].score == 0.0
            assert tracks[0].last_seen == pytest.approx(last_update)
            # Coasting on at the estimated velocity (≈ 1 m/s in +y).
            assert tracks[0].y == pytest.approx(3.0 + t, abs=0.15)
        elif t > last_update + delete_after_s + 1e-6:
            assert tracks == [], t
    assert len(tracker.position_map) == 0


def test_a_person_standing_still_is_kept_for_seconds():
    """MOG2 at 1/history per frame: a standing person stays foreground for 3 s at 10 fps."""
    scene = make_scene(FRONT)
    bg = {"front": texture(0)}
    tracker = BlobTracker(scene, {"front": StaticBackground(bg["front"])})
    history = run(tracker, scene, bg, lambda t: np.array([[1.0, 4.0]]), np.arange(0, 3.0, 0.1))
    errs = errors_by_id(history)
    assert list(errs) == [1] and len(errs[1]) == len(history) - 2
    assert max(d for _, d, _ in errs[1]) < 0.04 + row_footprint(scene.cameras["front"], (1.0, 4.0))
    assert all(not tracks[0].flags for _, _, tracks in history[2:])
    assert np.hypot(history[-1][2][0].vx, history[-1][2][0].vy) < 0.05


def test_coasting_tracks_can_be_hidden():
    scene = make_scene(FRONT)
    bg = {"front": texture(0)}

    def walk(t):
        return np.array([[0.0, 3.0 + t]]) if t < 1.0 else np.zeros((0, 2))

    tracker = BlobTracker(scene, {"front": StaticBackground(bg["front"])}, BlobConfig(lifecycle={"report_coasting": False}))
    history = run(tracker, scene, bg, walk, np.arange(0, 1.5, 0.1))
    assert [len(tracks) for t, _, tracks in history if t >= 1.0] == [0] * 5
    assert len(tracker.position_map) == 1  # still held, not reported


def test_two_cameras_fuse_to_one_track_per_person():
    scene = make_scene(FRONT, BACK)
    bg = {"front": texture(0), "back": texture(1)}
    tracker = BlobTracker(scene, {cid: StaticBackground(b) for cid, b in bg.items()})
    history = run(tracker, scene, bg, walking_apart, np.arange(0, 2.5, 0.1))
    assert len(tracker.last_detections) == 2
    errs = errors_by_id(history)
    assert sorted(errs) == [1, 2]
    for rows in errs.values():
        d = np.array(rows)[:, 1]
        assert d.mean() < 0.06 and d.max() < 0.12


# ---------------------------------------------------------------------------- set-up and errors

def test_uses_a_given_mog2_and_builds_one_otherwise():
    scene = make_scene(FRONT)
    bg = texture(0)
    mog = AdaptiveBackground("mog2", background=bg)
    tracker = BlobTracker(scene, {"front": mog})
    assert tracker.detectors["front"].foreground is mog
    static = StaticBackground(bg)
    tracker = BlobTracker(scene, {"front": static})
    own = tracker.detectors["front"].foreground
    assert isinstance(own, AdaptiveBackground) and own.background is bg
    assert own.learning_rate == pytest.approx(1 / 500)


def test_make_tracker_builds_it_by_name_and_checks_options():
    scene = make_scene(FRONT)
    fg = {"front": StaticBackground(texture(0))}
    tracker = make_tracker("blobs", scene, fg, overrides={"lifecycle.delete_after_s": 2.0, "filter.gate": 4.0})
    assert isinstance(tracker, BlobTracker) and tracker.config.lifecycle.delete_after_s == 2.0
    assert tracker.config.filter.gate == 4.0 and tracker.extra_columns == ("sigma",)
    with pytest.raises(InputError, match=r"^blobs.no_such_option: unknown setting \(expected one of: foreground, "):
        make_tracker("blobs", scene, fg, no_such_option=1)
    with pytest.raises(InputError, match=r"^blobs.lifecycle.delete_after_s: expected a number > 0, got 0$"):
        make_tracker("blobs", scene, fg, overrides={"lifecycle.delete_after_s": 0})
    with pytest.raises(InputError, match=r"^blobs.detection.foot_point: expected one of 'bottom' or 'box', "
                                         r"got 'centroid'$"):
        BlobConfig(detection={"foot_point": "centroid"})


def test_unknown_camera_and_wrong_frame_size_are_input_errors():
    scene = make_scene(FRONT)
    bg = texture(0)
    tracker = BlobTracker(scene, {"front": StaticBackground(bg)})
    with pytest.raises(InputError, match="no foreground model for camera 'side'"):
        tracker.detect("side", bg)
    with pytest.raises(InputError, match="frame is 160x120 but the camera is 320x240"):
        tracker.step({"front": Frame(bg[::2, ::2].copy(), 0.0, 0)}, 0.0)
    with pytest.raises(InputError, match="no camera 'side'"):
        BlobTracker(scene, {"side": StaticBackground(bg)})


def test_time_stamps_must_increase():
    scene = make_scene(FRONT)
    bg = texture(0)
    tracker = BlobTracker(scene, {"front": StaticBackground(bg)})
    tracker.step({"front": Frame(bg, 1.0, 0)}, 1.0)
    with pytest.raises(InputError, match="time stamps must increase"):
        tracker.step({"front": Frame(bg, 1.0, 1)}, 1.0)


def test_missing_stone_soup_names_the_extra(monkeypatch):
    for name in [n for n in sys.modules if n == "stonesoup" or n.startswith("stonesoup.")]:
        monkeypatch.setitem(sys.modules, name, None)
    monkeypatch.setitem(sys.modules, "stonesoup", None)
    scene = make_scene(FRONT)
    with pytest.raises(InputError, match=r"needs Stone Soup: pip install 'worldtrack\[baseline\]'"):
        BlobTracker(scene, {"front": StaticBackground(texture(0))})
