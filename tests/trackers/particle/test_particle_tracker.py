"""The particle tracker end to end on small rendered scenes with exact ground truth.

Accuracy bound. An ellipsoid's silhouette is exactly what the height column tests, so the column
is sharp here; what remains is the pixel grid (one image row at the feet spans 0.03–0.08 m of floor
at 3–6 m in this 320×240, 70° view), the column's 0.1 m steps and the particles' spread. The
tracker reaches 0.02–0.04 m mean error on a walker here; 0.10 m is asserted.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from worldtrack.errors import InputError
from worldtrack.foreground.background import StaticBackground, colour_distance
from worldtrack.trackers import make_tracker
from worldtrack.trackers.base import Frame
from worldtrack.trackers.particle import ParticleTracker
from worldtrack.trackers.particle.likelihood import (CameraLikelihood, ReadAs, occluder_layers, owner_image,
                                                     top_edge_terms_reference)
from worldtrack.trackers.particle.likelihood.models import FrameView, Readers

from particle_scenes import hit_image  # noqa: E402
from particle_scenes import (CAM, CAM2, FPS, HEIGHT, WIDTH, H, W, clouds, config, make_scene, render, run, texture,
                             tracker_for, walker)



def test_walker_is_tracked_within_bounds():
    scene = make_scene()
    tracker, bgs = tracker_for(scene)
    out = run(tracker, scene, bgs, walker, 40)
    ids = {tr.id for _, _, tracks in out for tr in tracks}
    assert ids == {1}
    first = next(k for k, (_, _, tracks) in enumerate(out) if tracks)
    assert first <= 3
    err, inside, vx = [], [], []
    for t, truth, tracks in out[first + 5:]:
        (tr,) = tracks
        x, y = truth[0]
        err.append(np.hypot(tr.x - x, tr.y - y))
        inside.append(abs(tr.x - x) <= tr.extra["sx"] + 0.02 and abs(tr.y - y) <= tr.extra["sy"] + 0.02
                      and abs(tr.extra["z"] - HEIGHT / 2) <= tr.extra["sz"])
        vx.append(tr.vx)
    assert np.mean(err) < 0.10 and np.max(err) < 0.25
    assert np.mean(inside) > 0.5
    # The region's floor size is at least the body's (a disc of the person's width: σ = width/4).
    assert tracks[0].extra["sx"] >= 0.25 * WIDTH and tracks[0].extra["sy"] >= 0.25 * WIDTH
    assert np.median(vx) == pytest.approx(1.0, abs=0.25)        # m/s, from real time stamps
    assert tracks[0].height == pytest.approx(HEIGHT, abs=0.25)


def test_detection_fires_on_entry_and_not_on_empty_frames():
    scene = make_scene()
    tracker, bgs = tracker_for(scene)
    empty = run(tracker, scene, bgs, lambda t: [], 15)
    assert all(not tracks for _, _, tracks in empty)
    rng = np.random.default_rng(5)
    found = None
    for k in range(15, 30):
        t = k / FPS
        img = render(scene.cameras["cam"], bgs["cam"], [(-2.3, 3.0)], rng)
        if tracker.step({"cam": img}, t):
            found = k
            break
    assert found is not None and found - 15 <= 3


def test_person_outside_the_entry_region_is_not_detected():
    scene = make_scene()
    tracker, bgs = tracker_for(scene)
    out = run(tracker, scene, bgs, lambda t: [(1.5, 3.0)], 15)
    assert all(not tracks for _, _, tracks in out)
    tracker, bgs = tracker_for(scene, detection__births="anywhere")
    out = run(tracker, scene, bgs, lambda t: [(1.5, 3.0)], 15)
    assert out[-1][2] and np.hypot(out[-1][2][0].x - 1.5, out[-1][2][0].y - 3.0) < 0.15


def test_tracking_filter_ends_after_the_person_leaves():
    scene = make_scene()
    tracker, bgs = tracker_for(scene, tracking__end_after_s=0.0)
    out = run(tracker, scene, bgs, lambda t: [(-2.3 + 1.0 * t, 3.0)] if t < 2.0 else [], 30)
    assert out[19][2]
    assert all(not tracks for _, _, tracks in out[21:])


def test_a_track_walking_behind_another_person_is_held():
    """One person stands 2.2 m from the camera, another walks across behind them at 4.2 m. Reading
    the near person's box as occlusion, the far track coasts through and is found again; reading
    it as background (the explaining away alone) pushes the far track off."""
    def paths(t):
        return [(0.0, 2.2), (-1.5 + 1.0 * t, 4.2)]

    worst = {}
    for occlusion in (True, False):
        scene = make_scene(entry=False)
        tracker, bgs = tracker_for(scene, detection__births="none", explain__occlusion=occlusion)
        tracker.init_track(0.0, 2.2, track_id=1)
        tracker.init_track(-1.5, 4.2, track_id=2)
        errors = []
        for _, truth, tracks in run(tracker, scene, bgs, paths, 31):
            far = {tr.id: tr for tr in tracks}.get(2)
            errors.append(np.inf if far is None else np.hypot(far.x - truth[1][0], far.y - truth[1][1]))
        worst[occlusion] = max(errors)
        if occlusion:
            assert np.mean(errors) < 0.2 and errors[-1] < 0.15
    assert worst[True] < 0.7 < 1.0 < worst[False]


def test_same_seed_gives_the_same_tracks_and_another_seed_does_not():
    def tracks(seed):
        scene = make_scene()
        tracker, bgs = tracker_for(scene, seed=seed)
        return [(tr.id, tr.x, tr.y, tr.extra["sz"]) for _, _, trs in run(tracker, scene, bgs, walker, 12) for tr in trs]

    a, b, c = tracks(3), tracks(3), tracks(4)
    assert a == b and a != c


def test_two_cameras_multiply_likelihoods():
    scene = make_scene(cameras=(CAM, CAM2))
    tracker, bgs = tracker_for(scene, detection__births="anywhere")
    out = run(tracker, scene, bgs, lambda t: [(0.5, 3.5)], 10)
    assert len(out[-1][2]) == 1 and np.hypot(out[-1][2][0].x - 0.5, out[-1][2][0].y - 3.5) < 0.1
    rng = np.random.default_rng(0)
    images = {cid: hit_image(StaticBackground(bgs[cid], 30.0, "colour").difference(
        render(cam, bgs[cid], [(0.5, 3.5)], rng)), 30.0) for cid, cam in scene.cameras.items()}
    xyz = np.column_stack([rng.uniform(-1, 2, 200), rng.uniform(2, 5, 200), np.zeros(200)])
    both = tracker.likelihood(xyz, None, FrameView(images), Readers.one(200))[0]
    one = [tracker.likelihood(xyz, None, FrameView({cid: img}), Readers.one(200))[0] for cid, img in images.items()]
    np.testing.assert_allclose(both, one[0] + one[1])


def test_short_objects_need_lower_height_limits():
    """A 0.6 m object (a small child): below the default min_height, tracked with lower limits."""
    scene = make_scene()
    child = lambda t: [(-2.3 + 0.5 * t, 3.0, 0.6)]
    tracker, bgs = tracker_for(scene)
    assert not any(tracks for _, _, tracks in run(tracker, scene, bgs, child, 12))
    tracker, bgs = tracker_for(scene, column__min_height_m=0.4, column__max_height_m=1.0, column__dz_m=0.05)
    out = run(tracker, scene, bgs, child, 12)
    (tr,) = out[-1][2]
    x, y, _ = out[-1][1][0]
    assert np.hypot(tr.x - x, tr.y - y) < 0.15 and tr.height == pytest.approx(0.6, abs=0.15)


def test_paper_preset_column_beats_point():
    """The method as published (weights ∝ count, line column, no extensions) against its baseline:
    both spread along the line of sight, the column much less (the paper's claim)."""
    scene = make_scene()
    bg = texture(0)
    err = {}
    for likelihood in ("column-count", "point"):
        tracker = make_tracker("particle", scene, {"cam": StaticBackground(bg, 30.0, "colour")}, preset="paper",
                               overrides={"likelihood.model": likelihood})
        assert not tracker.config.split.enabled and not tracker.likelihood.ratio
        out = run(tracker, scene, {"cam": bg}, walker, 25)
        err[likelihood] = np.mean([np.hypot(trs[0].x - truth[0][0], trs[0].y - truth[0][1])
                                   for _, truth, trs in out[10:]])
    assert err["column-count"] < 0.7 and err["point"] > err["column-count"] + 0.4


def test_batched_likelihood_equals_one_call_per_filter():
    """``step`` reads all tracking filters in one likelihood call: the same values as one call per
    filter with its own box, occluder index and colours (three people who stood apart long enough
    for each filter to learn its colours; then the third stands behind the second)."""
    scene = make_scene(entry=False)
    apart = [(-1.5, 3.0), (0.0, 2.5), (1.5, 3.5)]
    tracker, bgs = tracker_for(scene, detection__births="none")
    for i, (x, y) in enumerate(apart, start=1):
        tracker.init_track(x, y, track_id=i)
    run(tracker, scene, bgs, lambda t: apart, 6)
    fs = clouds(tracker)
    assert len(fs) == 3 and all(f.colours["cam"].hist is not None for f in fs)
    people = apart[:2] + [(0.0, 4.5)]
    fs[2].xyz = fs[2].xyz + [-1.5, 1.0, 0.0]
    frame = tracker.labels.read({"cam": Frame(render(scene.camera("cam"), bgs["cam"], people,
                                                     np.random.default_rng(7)), 1.0, 10)})
    centres = [f.xyz[:, :2].mean(axis=0) for f in fs]
    boxes = tracker.explainer.boxes(centres, [tracker.position_map[f.person] for f in fs])
    owners = {"cam": owner_image((H, W), boxes["cam"])}
    occluders = {"cam": occluder_layers((H, W), boxes["cam"], scene.camera("cam").floor_rays(np.array(centres))[1])}
    xyz, h = np.concatenate([f.xyz for f in fs]), np.concatenate([f.h for f in fs])
    which = np.repeat(np.arange(3), [len(f.xyz) for f in fs])
    view = FrameView(frame.images, owners, boxes, occluders, frame.colour)
    batched = tracker.likelihood(xyz, h, view, Readers(which, [0, 1, 2], [f.colours for f in fs]))
    for i, f in enumerate(fs):
        one = tracker.likelihood(f.xyz, f.h, FrameView(frame.images, owners, {"cam": [boxes["cam"][i]]}, occluders,
                                                       frame.colour),
                                 Readers(np.zeros(len(f.xyz), dtype=np.int64), [i], [f.colours]))
        for a, b in zip(batched, one):
            np.testing.assert_array_equal(a[which == i], b)
    u0, u1, v0, v1 = boxes["cam"][2]
    assert occluders["cam"].depth_for(2)[v0:v1, u0:u1].min() < 4.0      # the third is behind the second
    # Each filter's own colours and box count: swapping either changes the values.
    colours = [f.colours for f in fs]
    swapped_boxes = FrameView(frame.images, owners, {"cam": boxes["cam"][::-1]}, occluders, frame.colour)
    for swapped in (tracker.likelihood(xyz, h, view, Readers(which, [0, 1, 2], colours[::-1])),
                    tracker.likelihood(xyz, h, swapped_boxes, Readers(which, [2, 1, 0], colours))):
        assert not np.array_equal(swapped[0], batched[0])


def test_tracking_likelihood_adds_the_weighted_top_edge_terms():
    """The column ratio with ``top_edge=True`` (tracking filters) adds ``height.edge_weight`` times the
    kernel's terms at the particles' own heights, with the configured offsets; without it, or with
    ``edge_weight=0``, nothing."""
    scene = make_scene()
    cam = scene.cameras["cam"]
    rng = np.random.default_rng(12)
    labels = (cv2.GaussianBlur(rng.random((H, W)).astype(np.float32), (0, 0), 3) > 0.5).astype(np.uint8)
    n = 400
    xyz = np.column_stack([rng.uniform(-2.5, 2.5, n), rng.uniform(1.0, 6.0, n), np.zeros(n)])
    h = rng.uniform(1.4, 1.9, n)
    fgs = {"cam": StaticBackground(texture(0), 30.0, "colour")}
    edge = dict(height__edge_weight=0.7, height__edge_step_m=0.04, height__edge_samples=3)
    tracker = ParticleTracker(scene, fgs, config(**edge))
    view, one = FrameView({"cam": labels}), Readers.one(n)
    plain, _, _ = tracker.likelihood(xyz, h, view, one)
    edged, _, _ = tracker.likelihood(xyz, h, view, one, top_edge=True)
    on, off = np.log(0.6 / 0.05), np.log(0.4 / 0.95)
    terms = top_edge_terms_reference(cam, labels, xyz, h, [-0.12, -0.08, -0.04, 0.04, 0.08, 0.12], on, off, 0.7)
    finite = np.isfinite(plain)
    assert finite.sum() > 300 and np.count_nonzero(terms[finite]) > 100
    np.testing.assert_allclose(edged[finite], plain[finite] + terms[finite], rtol=0, atol=1e-9)
    np.testing.assert_array_equal(np.isfinite(edged), finite)
    off_tracker = ParticleTracker(scene, fgs, config(height__edge_weight=0.0))
    np.testing.assert_array_equal(off_tracker.likelihood(xyz, h, view, one, top_edge=True)[0], plain)
    # With another object's box over the image: raw labels by default, the column's reading with
    # edge_explain.
    boxes = [(0, W // 2, 0, H), None]
    owners = {"cam": owner_image((H, W), boxes)}
    second = np.ones(n, dtype=np.int64)                     # every particle is filter 1's
    boxed, readers = FrameView({"cam": labels}, owners, {"cam": list(boxes)}), Readers(second, [0, 1])
    for explain in (False, True):
        tr = ParticleTracker(scene, fgs, config(**edge, height__edge_explain=explain))
        base = tr.likelihood(xyz, h, boxed, readers)[0]
        got = tr.likelihood(xyz, h, boxed, readers, top_edge=True)[0]
        reading = ReadAs(owners["cam"], boxes, [0, 1], second) if explain else None
        want = top_edge_terms_reference(cam, labels, xyz, h, [-0.04, -0.08, -0.12, 0.04, 0.08, 0.12], on, off, 0.7,
                                        reading)
        ok = np.isfinite(base)
        np.testing.assert_allclose(got[ok], base[ok] + want[ok], rtol=0, atol=1e-9)
    assert not np.allclose(want, terms)                     # the box changed the terms


def test_stacked_rows_follow_the_filters_arrays():
    """The tracking filters' per-particle arrays are kept as rows of one array between frames; the
    tracker reads that array only while every filter still holds its row, else it stacks afresh."""
    scene = make_scene(entry=False)
    tracker, bgs = tracker_for(scene, detection__births="none")
    people = [(-1.0, 3.0), (1.0, 3.5)]
    for x, y in people:
        tracker.init_track(x, y)
    run(tracker, scene, bgs, lambda t: people, 3)
    fs = clouds(tracker)
    assert len(fs) == 2
    stack = tracker.stack
    kept = stack.stacked(fs, "xyz")
    assert all(f.xyz.base is kept for f in fs)                      # rows of the kept array
    np.testing.assert_array_equal(kept, np.stack([f.xyz for f in fs]))
    fs[1].xyz = fs[1].xyz + 1.0                                     # a filter given a new array
    fresh = stack.stacked(fs, "xyz")
    assert fresh is not kept
    np.testing.assert_array_equal(fresh, np.stack([f.xyz for f in fs]))
    np.testing.assert_array_equal(fresh[1], kept[1] + 1.0)
    np.testing.assert_array_equal(stack.stacked(fs[::-1], "xyz"), np.stack([fs[1].xyz, fs[0].xyz]))  # other order





def test_user_mistakes_are_input_errors():
    scene = make_scene()
    fgs = {"cam": StaticBackground(texture(0), 30.0, "colour")}
    with pytest.raises(InputError, match="particle.no_such_option: unknown setting"):
        make_tracker("particle", scene, fgs, no_such_option=1)
    with pytest.raises(InputError, match="births='entry' but scene 'particle-test' has no entry regions"):
        ParticleTracker(make_scene(entry=False), fgs, config(detection__births="entry"))
    with pytest.raises(InputError, match="entry\\+lost"):
        ParticleTracker(make_scene(entry=False), fgs, config(detection__births="entry+lost"))
    with pytest.raises(InputError, match="expected a ParticleConfig"):
        ParticleTracker(scene, fgs, {"seed": 1})
    tracker = ParticleTracker(scene, fgs)
    tracker.init_track(0.0, 3.0, track_id=4)
    with pytest.raises(InputError, match="track id 4 is taken already"):
        tracker.init_track(1.0, 3.0, track_id=4)
    tracker.step({"cam": texture(0)}, 1.0)
    with pytest.raises(InputError, match="time went backwards"):
        tracker.step({"cam": texture(0)}, 0.5)
    with pytest.raises(InputError, match="cam: frame is 10x10 but the camera is 320x240"):
        tracker.step({"cam": np.zeros((10, 10, 3), np.uint8)}, 2.0)


def test_tracks_csv_gets_the_object_region_columns(tmp_path):
    from worldtrack.io.sources import ArraySource
    from worldtrack.io.tracks import read_tracks
    from worldtrack.pipeline import run_tracking

    scene = make_scene()
    tracker, bgs = tracker_for(scene)
    rng = np.random.default_rng(0)
    images = [{"cam": render(scene.cameras["cam"], bgs["cam"], walker(k / FPS), rng)} for k in range(8)]
    run_tracking(scene, ArraySource(images, fps=FPS), tracker, tmp_path, write_video=False, progress=False)
    table = read_tracks(tmp_path / "tracks.csv")
    assert len(table) >= 5 and {"z", "sx", "sy", "sz", "sigma"} <= set(table.columns)
    assert np.all(table.column("sz") > 0)


def test_feet_below_the_image_cost_the_true_column_less():
    """A person stands at (0.4, 0.7) with the lower 0.5 m out of view. Along the line of sight, a
    column farther away (its samples packed into the visible body) scores best in both modes; read
    as background, the samples out of view cost the true column ``off`` each and leave it far
    behind that best column, read as no evidence they cost nothing and the gap shrinks to well
    under half.

    (On the tracker itself the effect is smaller than this gap suggests: started on the truth, a
    filter settles ~0.24 m away from the camera with ``unknown`` and ~0.27 m with ``background``
    — the packing of samples, not the out-of-view term, is most of the drift.)"""
    scene = make_scene(entry=False)
    tracker, bgs = tracker_for(scene, detection__births="none")
    cam = scene.cameras["cam"]
    img = render(cam, bgs["cam"], [(0.4, 0.7)], np.random.default_rng(0))
    hit = hit_image(colour_distance(img, bgs["cam"]), 25.0)     # the scenes' foreground threshold
    ys = np.arange(0.7, 1.31, 0.05)
    xy = np.column_stack([np.full(len(ys), 0.4), ys])
    gap = {}
    for unknown in (True, False):
        spec = tracker.likelihood.spec._replace(outside_unknown=unknown)
        _, ratio, _, seen, _ = CameraLikelihood(cam).column(hit, xy, spec, tops=np.full(len(ys), HEIGHT))
        assert seen.all()
        gap[unknown] = ratio.max() - ratio[0]
    assert gap[False] > 5.0
    assert gap[True] < 0.5 * gap[False]


def test_the_foreground_threshold_decides_what_the_tracker_sees():
    # Issue 33: the tracker read its own γ and ignored the run's foreground (--threshold 10 and 60
    # gave identical tracks). A threshold above every colour change (the RGB distance is at most
    # 255·√3 ≈ 442) leaves it nothing to detect; the same frames at 25 give the walker.
    scene = make_scene()
    bgs = {cid: texture(i) for i, cid in enumerate(scene.cameras)}
    found = {}
    for threshold in (25.0, 450.0):
        fgs = {cid: StaticBackground(bg, threshold, "colour", shadows=True) for cid, bg in bgs.items()}
        tracker = ParticleTracker(scene, fgs, config(column__surface_offset_m=0.0))
        out = run(tracker, scene, bgs, walker, 15)
        found[threshold] = {tr.id for _, _, tracks in out for tr in tracks}
    assert found[25.0] == {1} and found[450.0] == set()
