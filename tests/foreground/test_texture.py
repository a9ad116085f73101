"""Texture test of shadow-like pixels: the per-pixel kernel against the box-filter reference, and
cast shadow vs dark cloth of the floor's colour."""

import numpy as np
import pytest

from worldtrack.foreground.background import UNSURE, StaticBackground
from worldtrack.foreground.texture import TEXTURE_WINDOW, grey, texture_at, texture_correlation


def wooden_floor(h=60, w=80, seed=0):
    """A brown floor with grain (vertical stripes of varying brightness) and sensor noise."""
    rng = np.random.default_rng(seed)
    grain = 25 * np.sin(np.arange(w) * 1.3)[None, :] + rng.normal(0, 6, (h, w))
    base = np.array([60, 100, 150], float)                                # BGR brown
    return np.clip(base * (1 + grain[..., None] / 150), 0, 255).astype(np.uint8)


def test_kernel_equals_the_box_filter_reference_also_at_the_border():
    rng = np.random.default_rng(3)
    bg = wooden_floor(seed=1)
    img = np.clip(bg * 0.7 + rng.normal(0, 8, bg.shape), 0, 255).astype(np.uint8)
    img[20:40, 30:50] = rng.integers(0, 255, (20, 20, 3))
    ncc, sd = texture_correlation(img, bg, TEXTURE_WINDOW)
    v, u = np.mgrid[0:bg.shape[0], 0:bg.shape[1]]
    vs, us = v.ravel(), u.ravel()
    k_ncc, k_sd = texture_at(grey(img), grey(bg), vs, us, TEXTURE_WINDOW)
    # float32 box filters vs float64 sums: equal to rounding, border rows and columns included
    np.testing.assert_allclose(k_sd, sd.ravel(), atol=2e-3)
    np.testing.assert_allclose(k_ncc, ncc.ravel(), atol=2e-3)
    assert ncc[25:35, 35:45].mean() < 0.3 < 0.8 < ncc[:10].mean()        # noise vs darkened floor


@pytest.mark.parametrize("with_texture", [False, True])
def test_dark_cloth_of_the_floor_colour_is_foreground_and_a_shadow_is_not(with_texture):
    bg = wooden_floor()
    img = bg.copy()
    img[5:25, 5:35] = (bg[5:25, 5:35] * 0.6).astype(np.uint8)           # cast shadow: grain darkened
    cloth = np.array([60, 100, 150]) * 0.6                               # the floor's colour, darker, plain
    rng = np.random.default_rng(1)
    img[30:55, 40:70] = np.clip(cloth + rng.normal(0, 3, (25, 30, 3)), 0, 255).astype(np.uint8)
    fg = StaticBackground(bg, 20.0, "colour", shadows=True, shadow_texture_ncc=0.0 if with_texture else None)
    labels = fg.labels(img)
    shadow, trousers = labels[7:23, 7:33], labels[32:53, 42:68]
    assert (shadow == UNSURE).mean() > 0.95                              # the grain shows through
    if with_texture:
        assert (trousers == 1).mean() > 0.4                              # pattern gone: cloth
        assert (shadow == 1).mean() < 0.02
    else:
        assert (trousers == UNSURE).mean() > 0.9                         # colour alone calls it shadow


def test_a_shadow_on_a_plain_floor_stays_unsure():
    # Where the background has no pattern, the test cannot tell: the label stays "unsure".
    bg = np.full((40, 40, 3), (150, 150, 150), np.uint8)
    rng = np.random.default_rng(2)
    img = np.clip(bg * 0.6 + rng.normal(0, 3, bg.shape), 0, 255).astype(np.uint8)
    labels = StaticBackground(bg, 20.0, "colour", shadows=True, shadow_texture_ncc=0.0).labels(img)
    assert (labels == UNSURE).mean() > 0.99


def test_relabel_kernel_equals_the_reference():
    from worldtrack.foreground.texture import relabel_cloth, relabel_cloth_reference
    rng = np.random.default_rng(5)
    bg = wooden_floor(seed=4)
    img = np.clip(bg * rng.uniform(0.5, 1.0, bg.shape[:2])[..., None] + rng.normal(0, 5, bg.shape), 0, 255)
    img = img.astype(np.uint8)
    img[20:40, 20:60] = rng.integers(0, 255, (20, 40, 3))                # cloth-like: no floor pattern
    labels = rng.integers(0, 3, bg.shape[:2]).astype(np.uint8)
    for max_ncc in (-0.2, 0.0, 0.3):
        ref = relabel_cloth_reference(labels, img, bg, max_ncc)
        fast = relabel_cloth(labels.copy(), img, grey(bg), max_ncc)
        assert (fast != ref).sum() <= 2                                   # float32 vs float64 at the threshold
        assert ((ref == 1) & (labels == 2)).sum() > 20                    # something was relabelled
        np.testing.assert_array_equal(fast[labels != 2], labels[labels != 2])


def test_judging_shadows_tells_cloth_shadow_and_unsure_as_the_reference_does():
    from worldtrack.foreground.texture import judge_shadows, judge_shadows_reference
    rng = np.random.default_rng(6)
    bg = wooden_floor(seed=4)
    img = np.clip(bg * 0.6 + rng.normal(0, 2, bg.shape), 0, 255).astype(np.uint8)   # a shadow: pattern shows
    img[20:40, 20:60] = rng.integers(0, 255, (20, 40, 3))                          # cloth: pattern gone
    labels = np.full(bg.shape[:2], 2, np.uint8)
    labels[:, :5] = 0                                                               # not candidates: untouched
    ref = judge_shadows_reference(labels, img, bg, 0.2, 0.5)
    fast = judge_shadows(labels.copy(), img, grey(bg), 0.2, 0.5)
    assert (fast != ref).sum() <= 2                                                # float32 vs exact sums
    assert (fast[25:35, 25:55] == 1).mean() > 0.8                                   # cloth
    assert (fast[50:70, 10:80] == 3).mean() > 0.8                                   # shadow over the pattern
    np.testing.assert_array_equal(fast[:, :5], 0)
    never = judge_shadows(labels.copy(), img, grey(bg), 0.2)                       # no shadow threshold
    assert not (never == 3).any() and ((never == 1) == (fast == 1)).all()
