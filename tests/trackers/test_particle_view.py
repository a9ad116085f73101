"""The particle tracker's column outside the image (``ParticleConfig.out_of_view``).

Uses the small rendered scene of ``test_particle.py``: one camera 3 m up, ellipsoid people over a
smooth random texture. A person standing 0.7 m in front of the camera's foot line has the lower
0.5 m of the body below the image's edge.
"""

from __future__ import annotations

import numpy as np
import pytest

from worldtrack.errors import InputError
from worldtrack.foreground.background import colour_distance
from worldtrack.trackers.particle import ParticleConfig
from worldtrack.trackers.particle.likelihood import CameraLikelihood, column_counts_reference, hit_image

from test_particle import CAM, HEIGHT, H, W, make_scene, render, tracker_for

ON, OFF = 2.77, -1.56


def _column(cl, hit, xy, outside_unknown):
    heights = np.arange(20) * 0.1
    return cl.column(hit, xy, heights, on=ON, off=OFF, k_min=8, outside_unknown=outside_unknown)


def test_samples_below_the_image_read_nothing_instead_of_background():
    """A column at y = 0.7 m (feet at v ≈ 260, below the 240-row image) over an image that is
    object everywhere: with ``outside_unknown`` its ratio is ``on`` times the samples in view and
    the samples out of view add nothing; without, each adds ``off``."""
    cam = make_scene().cameras["cam"]
    cl = CameraLikelihood(cam)
    hit = np.ones((H, W), dtype=np.uint8)
    xy = np.array([[0.0, 0.7]])
    z = np.arange(20) * 0.1
    inside = cam.in_image(cam.project(np.column_stack([np.zeros(20), np.full(20, 0.7), z])))
    n_in = int(inside.sum())
    assert 3 <= 20 - n_in <= 10                       # the test needs a column partly out of view
    counts, ratio, top, seen = _column(cl, hit, xy, True)
    assert counts[0] == n_in and seen[0] and top[0] == 19
    assert ratio[0] == pytest.approx(ON * n_in)
    counts, ratio, top, seen = _column(cl, hit, xy, False)
    assert counts[0] == n_in
    assert ratio[0] == pytest.approx(ON * n_in + OFF * (20 - n_in))


@pytest.mark.parametrize("radius", [0.0, 0.1])
def test_kernel_agrees_with_reference_for_columns_leaving_the_image(radius):
    cam = make_scene(cameras=(dict(CAM, distortion=[-0.2, 0.05, 0.001, -0.002, 0.0]),)).cameras["cam"]
    rng = np.random.default_rng(3)
    hit = rng.integers(0, 3, (H, W)).astype(np.uint8)
    # Floor positions round the image's bottom and side edges, so many columns leave the image.
    xy = np.column_stack([rng.uniform(-4.0, 4.0, 2000), rng.uniform(-0.5, 2.5, 2000)])
    heights = np.concatenate([[-0.2, -0.1], np.arange(20) * 0.1, [2.0, 2.1]])
    args = dict(on=ON, off=OFF, k_min=10, radius=radius, below=-ON, n_below=2, n_above=2, outside_unknown=True)
    counts, ratio, top, seen = CameraLikelihood(cam).column(hit, xy, heights, **args)
    r_counts, r_ratio, r_top, r_seen = column_counts_reference(cam, hit, xy, heights, **args)
    np.testing.assert_array_equal(counts, r_counts)
    np.testing.assert_array_equal(seen, r_seen)
    np.testing.assert_allclose(ratio, r_ratio, rtol=0, atol=1e-9)
    assert (top == r_top).mean() > 0.999
    partly = seen & (counts < 20)
    assert partly.sum() > 200                          # the test exercises columns partly in view


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
    tracker, bgs = tracker_for(scene, births="none")
    cam = scene.cameras["cam"]
    img = render(cam, bgs["cam"], [(0.4, 0.7)], np.random.default_rng(0))
    hit = hit_image(colour_distance(img, bgs["cam"]), tracker.config.gamma)
    ys = np.arange(0.7, 1.31, 0.05)
    xy = np.column_stack([np.full(len(ys), 0.4), ys])
    gap = {}
    for unknown in (True, False):
        _, ratio, _, seen = CameraLikelihood(cam).column(
            hit, xy, tracker._column, tracker._on, tracker._off, tracker._k_min, tracker.config.column_radius,
            -tracker._on, tracker._n_below, tracker._n_above, tops=np.full(len(ys), HEIGHT),
            top_sigma=tracker._top_sigma, outside_unknown=unknown)
        assert seen.all()
        gap[unknown] = ratio.max() - ratio[0]
    assert gap[False] > 5.0
    assert gap[True] < 0.5 * gap[False]


def test_paper_preset_reads_out_of_view_as_background():
    assert ParticleConfig.paper().out_of_view == "background"
    assert ParticleConfig().out_of_view == "unknown"                  # the documented default
    with pytest.raises(InputError):
        ParticleConfig(out_of_view="object")
