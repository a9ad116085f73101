"""The top edge at each particle's own height: the kernel against its reference, and where the
terms peak (the true height and depth of a flat figure)."""

from __future__ import annotations

import cv2
import numpy as np

from worldtrack.trackers.particle.likelihood import (CameraLikelihood, ReadAs, edge_spec, occluder_layers,
                                                     owner_image, top_edge_terms_reference)

from particle_scenes import CAM, DISTORTION, H, W, make_scene


def _top_edge(cl, hit, xy, tops, offsets, on, off, weight, out=None, **reading):
    """CameraLikelihood.top_edge for particles read with ``reading`` (ReadAs' owner, box, ...)."""
    out = np.zeros(len(xy)) if out is None else out
    cl.top_edge(cl.reading(hit, len(xy), ReadAs(**reading)), xy, tops, edge_spec(offsets, weight, on, off), out)
    return out


def test_top_edge_kernel_agrees_with_reference():
    """Random labels (object, background, no evidence), particles in and out of view, heights up to
    where the samples leave the image; with and without lens distortion; plain, and with other
    objects' boxes (background) and nearer ones (no evidence) over the samples."""
    rng = np.random.default_rng(11)
    labels = rng.integers(0, 3, (H, W)).astype(np.uint8)
    n = 3000
    xyz = np.column_stack([rng.uniform(-4, 4, n), rng.uniform(-0.5, 8.0, n), np.zeros(n)])
    tops = rng.uniform(0.5, 4.0, n)
    offsets = np.array([-0.06, -0.03, 0.03, 0.06])
    boxes = [(40, 160, 0, 140), (120, 260, 20, 200), None, (0, W, 0, 60)]
    depths = [2.0, 5.0, 3.0, 4.0]
    which = rng.integers(0, 4, n)
    explained = dict(owner=owner_image((H, W), boxes), box=boxes, me=[0, 1, 2, 3], which=which,
                     occluders=occluder_layers((H, W), boxes, depths), margin=0.3)
    for dist in ([0, 0, 0, 0, 0], DISTORTION):
        cam = make_scene(cameras=(dict(CAM, distortion=dist) if any(dist) else CAM,)).cameras["cam"]
        cl = CameraLikelihood(cam)
        for reading in ({}, explained):
            out = _top_edge(cl, labels, xyz, tops, offsets, 2.5, -0.9, 0.7, out=np.full(n, 0.5), **reading)
            ref = 0.5 + top_edge_terms_reference(cam, labels, xyz, tops, offsets, 2.5, -0.9, 0.7, ReadAs(**reading))
            np.testing.assert_allclose(out, ref, rtol=0, atol=1e-12)
            assert len(np.unique(np.round(out, 9))) > 10       # every kind of term exercised
            assert (out == 0.5).sum() > 50                      # some particles wholly out of view
        plain = top_edge_terms_reference(cam, labels, xyz, tops, offsets, 2.5, -0.9, 0.7)
        assert (out - 0.5 != plain).sum() > 300                 # the boxes changed many particles' terms


def test_top_edge_peaks_at_the_true_height_and_depth():
    """A flat figure 0.5 m wide and 1.6 m tall facing the camera 4 m in front of it: with the place
    known the edge terms are best within a step (and a pixel) of the true height; with the height
    known, within the depth that step spans along the line of sight (0.03 m / 0.28, the head ray's
    slope). A height 0.1 m off (the column's grid) loses everything: too tall reads two misses, too
    short has object above its top."""
    cam = make_scene().cameras["cam"]
    cl = CameraLikelihood(cam)
    truth = np.array([0.0, 4.0])
    corners = np.array([[-0.25, 4.0, 0.0], [0.25, 4.0, 0.0], [0.25, 4.0, 1.6], [-0.25, 4.0, 1.6]])
    labels = np.zeros((H, W), dtype=np.uint8)
    cv2.fillConvexPoly(labels, np.round(cam.project(corners)).astype(np.int32), 1)
    offsets = np.array([-0.06, -0.03, 0.03, 0.06])
    on, off = 2.5, -0.9

    def terms(xy, tops):
        return _top_edge(cl, labels, np.asarray(xy, dtype=float), np.asarray(tops, dtype=float), offsets, on, off, 1.0)

    heights = np.arange(1.3, 1.9, 0.005)
    by_height = terms(np.repeat(truth[None], len(heights), 0), heights)
    best = heights[by_height == by_height.max()]
    assert by_height.max() == 2 * on
    assert best.min() >= 1.6 - 0.03 - 0.02 and best.max() <= 1.6 + 0.03 + 0.02
    depths = np.arange(3.0, 5.0, 0.01)
    along = terms(np.column_stack([np.zeros(len(depths)), depths]), np.full(len(depths), 1.6))
    good = depths[along == along.max()]
    assert along.max() == 2 * on and good.min() >= 4.0 - 0.15 and good.max() <= 4.0 + 0.15
    assert terms([truth], [1.7])[0] == 2 * off and terms([truth], [1.5])[0] == 0.0
