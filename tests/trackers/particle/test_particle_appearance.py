"""The particle tracker's colour model: bins, learning, the penalty, and where a filter learns."""

from __future__ import annotations

import math

import numpy as np
import pytest

from worldtrack.scene import scene_from_dict
from worldtrack.trackers.base import Frame
from worldtrack.trackers.particle.appearance import (column_bins, column_bins_reference, column_penalties,
                                                     learn_columns)
from worldtrack.trackers.particle.colour import (EPSILON, GREY_BINS, HUE_BINS, MIN_LEARN_SAMPLES, N_BINS, SAT_BINS,
                                                 ColourModel, colour_bins, colour_bins_compiled, colour_bins_reference,
                                                 colour_log_ratio)
from worldtrack.trackers.particle.likelihood import CameraLikelihood
from worldtrack.trackers.particle.likelihood.models import Readers
from worldtrack.trackers.particle.likelihood.boxes import boxes_apart

from particle_scenes import CAM, COLOURS, DISTORTION, FLOOR, H, W, clouds, make_scene, render, run, tracker_for


def bgr(*colours) -> np.ndarray:
    return np.array([colours], dtype=np.uint8)


def test_colour_bins_tell_hues_and_greys_apart():
    red, green, blue = (0, 0, 255), (0, 255, 0), (255, 0, 0)
    black, white, mid_grey = (0, 0, 0), (255, 255, 255), (128, 128, 128)
    b = colour_bins(bgr(red, green, blue, black, white, mid_grey))[0]
    # Full saturation: the top saturation bin of hue 0° (red), 120° (green, OpenCV hue 60), 240° (blue, 120).
    assert b[0] == 0 * SAT_BINS + SAT_BINS - 1
    assert b[1] == (60 * HUE_BINS // 180) * SAT_BINS + SAT_BINS - 1
    assert b[2] == (120 * HUE_BINS // 180) * SAT_BINS + SAT_BINS - 1
    # Greys go by value: black the first grey bin, white the last, mid grey in between.
    assert b[3] == HUE_BINS * SAT_BINS
    assert b[4] == N_BINS - 1
    assert b[5] == HUE_BINS * SAT_BINS + 128 * GREY_BINS // 256
    assert len(set(b.tolist())) == 6
    assert b.max() < N_BINS


def test_colour_model_learns_a_running_average():
    m = ColourModel()
    assert not m.learn(np.full(MIN_LEARN_SAMPLES - 1, 3), 0.1)          # too few samples
    assert m.hist is None and m.frames == 0
    assert m.learn(np.array([3] * 6 + [-1] * 10), 0.1)                   # −1 (not object) ignored
    np.testing.assert_allclose(m.hist[3], 1.0)
    assert m.learn(np.array([5] * 8), 0.25)
    assert m.hist[3] == pytest.approx(0.75) and m.hist[5] == pytest.approx(0.25)
    assert m.hist.sum() == pytest.approx(1.0) and m.frames == 2


def test_colour_penalty_hits_foreign_colours_only():
    m = ColourModel()
    assert np.all(m.log_ratio(np.array([[1, 2, -1]])) == 0.0)          # nothing learnt: no term
    m.learn(np.array([3] * 10), 1.0)
    rows = np.array([[3, 3, 3], [7, 7, -1], [3, 7, -1], [-1, -1, -1]])
    lr = m.log_ratio(rows)
    absent = math.log(EPSILON / (1 + EPSILON))
    np.testing.assert_allclose(lr, [0.0, 2 * absent, absent, 0.0])       # own colour: 0, never a reward
    assert np.all(lr <= 0.0)


def test_colour_log_ratio_of_several_models_is_each_models():
    rng = np.random.default_rng(2)
    models = [ColourModel(), None, ColourModel(), ColourModel()]
    models[0].learn(rng.integers(0, 6, 50), 1.0)
    models[2].learn(rng.integers(20, N_BINS, 50), 1.0)                  # models[3]: nothing learnt
    bins = rng.integers(-1, N_BINS, (400, 6))
    which = rng.integers(0, 4, 400)
    batched = colour_log_ratio(models, bins, which)
    for f, m in enumerate(models):
        expected = m.log_ratio(bins[which == f]) if m is not None else 0.0
        np.testing.assert_array_equal(batched[which == f], expected)
    assert batched[which == 0].min() < 0 and batched[which == 2].min() < 0 and np.all(batched[which == 1] == 0)
    assert not np.array_equal(colour_log_ratio(models[::-1], bins, which), batched)


def test_column_bins_read_the_colour_of_object_pixels_on_the_column():
    scene = make_scene(entry=False)
    cam = scene.camera("cam")
    hit = np.zeros((cam.height, cam.width), dtype=np.uint8)
    image = np.full((cam.height, cam.width, 3), 128, dtype=np.uint8)
    xy = np.array([[0.0, 3.0], [1.5, 3.0]])
    heights = np.array([0.5, 1.0, 2.5])
    uv = cam.project(np.array([[0.0, 3.0, 0.5], [0.0, 3.0, 1.0]]))
    for u, v in np.round(uv).astype(int):
        hit[v, u] = 1
        image[v, u] = (0, 0, 255)
    red = int(colour_bins(bgr((0, 0, 255)))[0, 0])
    out = column_bins(CameraLikelihood(cam), image, hit, xy, heights)
    assert out.shape == (2, 3)
    np.testing.assert_array_equal(out[0], [red, red, -1])                # object, object, background
    np.testing.assert_array_equal(out[1], [-1, -1, -1])                  # a column on background


def test_colour_bins_lookup_agrees_with_arithmetic():
    img = np.random.default_rng(5).integers(0, 256, (60, 80, 3)).astype(np.uint8)
    np.testing.assert_array_equal(colour_bins(img), colour_bins_reference(img))


@pytest.mark.parametrize("dist", [None, DISTORTION])
def test_column_bins_kernel_agrees_with_reference(dist):
    scene = scene_from_dict({"name": "t", "cameras": [{**CAM, **({"distortion": dist} if dist else {})}], "floor": FLOOR})
    cam = scene.camera("cam")
    rng = np.random.default_rng(3)
    hit = rng.integers(0, 3, (cam.height, cam.width)).astype(np.uint8)
    image = rng.integers(0, 256, (cam.height, cam.width, 3)).astype(np.uint8)
    xy = np.column_stack([rng.uniform(-4, 4, 400), rng.uniform(0.2, 7, 400)])    # some outside the view
    fast, slow = column_bins(CameraLikelihood(cam), image, hit, xy), column_bins_reference(cam, image, hit, xy)
    assert fast.dtype == slow.dtype and (slow >= 0).sum() > 100 and (slow < 0).sum() > 100
    np.testing.assert_array_equal(fast, slow)


def test_compiled_colour_bins_agree_with_opencv_on_every_colour():
    """The kernels' own HSV (OpenCV's fixed-point arithmetic) gives the bin OpenCV's conversion does,
    for all 2^24 BGR colours."""
    c = np.arange(1 << 24, dtype=np.uint32)
    img = np.stack([c >> 16, (c >> 8) & 255, c & 255], axis=-1).astype(np.uint8).reshape(4096, 4096, 3)
    fast = colour_bins_compiled(img)
    np.testing.assert_array_equal(fast, colour_bins(img))
    assert len(np.unique(fast)) == N_BINS                               # every bin occurs


@pytest.mark.parametrize("dist", [None, DISTORTION])
def test_column_penalties_agree_with_bins_and_log_ratio(dist):
    """The fused penalty kernel: each particle's colour log-ratio of its column under its own
    filter's model, 0 where the model is None or has learnt nothing — as column_bins_reference then
    colour_log_ratio."""
    scene = scene_from_dict({"name": "t", "cameras": [{**CAM, **({"distortion": dist} if dist else {})}], "floor": FLOOR})
    cam = scene.camera("cam")
    rng = np.random.default_rng(4)
    hit = rng.integers(0, 3, (cam.height, cam.width)).astype(np.uint8)
    image = rng.integers(0, 256, (cam.height, cam.width, 3)).astype(np.uint8)
    models = [ColourModel(), None, ColourModel(), ColourModel()]
    models[0].learn(rng.integers(0, 6, 50), 1.0)
    models[2].learn(rng.integers(20, N_BINS, 50), 1.0)                  # models[3]: nothing learnt
    n = 600
    xy = np.column_stack([rng.uniform(-4, 4, n), rng.uniform(0.2, 7, n)])      # some outside the view
    which = rng.integers(0, 4, n)
    fast = column_penalties(CameraLikelihood(cam), image, hit, xy, models, which)
    slow = colour_log_ratio(models, column_bins_reference(cam, image, hit, xy), which)
    learnt = np.isin(which, [0, 2])
    np.testing.assert_array_equal(fast[learnt], slow[learnt])
    assert np.all(fast[~learnt] == 0.0)
    assert (fast[which == 0] < 0).sum() > 50 and (fast[which == 2] < 0).sum() > 50
    none = column_penalties(CameraLikelihood(cam), image, hit, xy, [None, ColourModel()], which % 2)
    assert np.all(none == 0.0)


def test_filters_learn_colours_only_while_their_boxes_are_apart():
    """Two people 1.5 m apart across the view: each filter learns its own person's colour. Two
    people on one line of sight (boxes overlapping): nobody learns."""
    def apart(t):
        return [(-1.0, 3.0), (1.0, 3.0)]

    def behind(t):
        return [(0.0, 2.5), (0.0, 4.5)]

    for paths, learns in ((apart, True), (behind, False)):
        scene = make_scene(entry=False)
        tracker, bgs = tracker_for(scene, detection__births="none")
        people = paths(0.0)
        for i, (x, y) in enumerate(people, start=1):
            tracker.init_track(x, y, track_id=i)
        run(tracker, scene, bgs, paths, 5)
        models = [c.colours.get("cam") for c in clouds(tracker)]
        if not learns:
            assert all(m is None or m.hist is None for m in models)
            continue
        # Each learnt histogram peaks on its own person's colour bin (particle_scenes.COLOURS).
        own = [int(colour_bins(bgr(COLOURS[k]))[0, 0]) for k in range(2)]
        assert own[0] != own[1]
        for k, m in enumerate(models):
            assert m is not None and m.frames >= 4
            assert int(np.argmax(m.hist)) == own[k] and m.hist[own[1 - k]] < 0.05


def test_likelihood_penalises_particles_on_another_persons_colours():
    """With person 1's learnt colours, particles on person 2 lose the colour penalty; particles on
    person 1 lose nothing; without colours both read the same column terms as before."""
    scene = make_scene(entry=False)
    tracker, bgs = tracker_for(scene, detection__births="none")
    people = [(-1.0, 3.0), (1.0, 3.0)]
    for i, (x, y) in enumerate(people, start=1):
        tracker.init_track(x, y, track_id=i)
    run(tracker, scene, bgs, lambda t: people, 5)
    first = clouds(tracker)[0]
    assert first.colours["cam"].hist is not None
    frame = render(scene.camera("cam"), bgs["cam"], people, np.random.default_rng(9))
    view = tracker.labels.read({"cam": Frame(frame, 1.0, 10)})
    xyz = np.array([[-1.0, 3.0, 0.8], [1.0, 3.0, 0.8]])
    plain, _, _ = tracker.likelihood(xyz, None, view, Readers.one(2))
    coloured, _, _ = tracker.likelihood(xyz, None, view, Readers.one(2, first.colours))
    assert coloured[0] == pytest.approx(plain[0])                        # own colours: no change
    absent = math.log(EPSILON / (1 + EPSILON))
    assert coloured[1] - plain[1] < 3 * absent                           # ≥ 3 samples of a foreign colour


def test_colour_learning_kernel_agrees_with_numpy():
    rng = np.random.default_rng(10)
    fast, slow = ColourModel(), ColourModel()
    for frame in range(30):
        bins = rng.integers(-1, N_BINS, (3, 6)).astype(np.int16)
        if frame % 7 == 3:
            bins[:] = -1
            bins[0, :MIN_LEARN_SAMPLES - 1] = 2                  # too few to learn from
        assert fast.learn(bins, 0.1) == slow.learn_reference(bins, 0.1)
        np.testing.assert_array_equal(fast.hist, slow.hist)
        assert fast.frames == slow.frames
    assert fast.frames > 20 and abs(fast.hist.sum() - 1) < 1e-12
    with pytest.raises(ValueError, match="below"):
        fast.learn(np.full(10, N_BINS), 0.1)


def test_learn_columns_equals_the_calls_one_by_one():
    """Colour learning in one compiled call: the same models (histograms, frames) as box_array,
    boxes_apart, beside, column_bins and ColourModel.learn one after the other; filters whose boxes
    overlap another's, or that are not learners, are not taught."""
    cam = make_scene().cameras["cam"]
    cl = CameraLikelihood(cam)
    rng = np.random.default_rng(23)
    hit = (rng.random((H, W)) < 0.7).astype(np.uint8)
    image = rng.integers(0, 256, (H, W, 3)).astype(np.uint8)
    centres = np.array([[-2.0, 3.0], [0.0, 2.5], [0.2, 2.6], [2.0, 4.0], [1.0, 5.5], [-1.0, 5.0]])
    widths, heights = np.full(6, 0.45), np.array([1.7, 1.6, 1.8, 1.7, 1.75, 1.7])
    learners = np.array([True, True, True, True, False, True])
    old = ColourModel()
    old.learn(rng.integers(0, N_BINS, 30), 1.0)
    for trial in range(2):
        models = [ColourModel() if i % 2 else None for i in range(6)]
        models[3] = old if trial else models[3]
        ref = [None if m is None else ColourModel() for m in models]
        for a, b in zip(models, ref):                     # the same models, for the calls one by one
            if a is not None and a.hist is not None:
                b.hist, b.frames = a.hist.copy(), a.frames
        given = [m if m is not None else ColourModel() for m in models]
        taught = learn_columns(cl, image, hit, centres, widths, heights, learners, 0.05, 0.14, given, 0.1)
        boxes = cl.box_array(centres, widths, heights, 0.05)
        idx = np.flatnonzero(learners & boxes_apart(boxes))
        np.testing.assert_array_equal(np.flatnonzero(taught), idx)
        bins = column_bins(cl, image, hit, cl.beside(centres[idx], 0.14, 0.25 * widths[idx])).reshape(len(idx), -1)
        want = [r if r is not None else ColourModel() for r in ref]
        for i, b in zip(idx, bins):
            want[i].learn(b, 0.1)
        for a, b in zip(given, want):
            assert a.frames == b.frames
            assert (a.hist is None) == (b.hist is None)
            if a.hist is not None:
                np.testing.assert_array_equal(a.hist, b.hist)
        assert 1 not in idx and 2 not in idx and 4 not in idx and 3 in idx   # overlapping, not a learner
    assert old.frames == 2                                # learnt once more, blending into its histogram
