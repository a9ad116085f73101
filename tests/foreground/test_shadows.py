"""Cast shadows as a tracker reads them (foreground/shadows.py): a foreground model's shadow-like
pixels judged by where they are and by texture, the compiled test against the box-filter reference."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from worldtrack.foreground.background import StaticBackground
from worldtrack.foreground.shadows import read_shadows, read_shadows_reference

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "trackers"))
from _render import texture  # noqa: E402  (tests/trackers/_render.py)

H, W = 240, 320


def _labels(img, bg):
    return StaticBackground(bg, 25.0, "colour", shadows=True).labels(img)


def test_shadows_are_set_apart_only_on_the_floor():
    bg = texture(0)
    img = bg.copy()
    img[100:140, 50:100] = (bg[100:140, 50:100] * 0.7).astype(np.uint8)    # a shadow
    img[100:140, 200:250] = (40, 30, 200)                                   # an object
    labels = _labels(img, bg)
    hit = read_shadows(labels, img, bg, None, shadow_as=2)
    assert np.mean(hit[100:140, 50:100] != 1) > 0.95 and np.mean(hit[100:140, 200:250] == 1) > 0.95
    assert np.all(hit[:90] == 0)
    # No floor anywhere: shadows fall nowhere, every change reads object.
    nowhere = np.zeros((H, W), bool)
    assert np.array_equal(read_shadows(labels, img, bg, nowhere, shadow_as=0), (labels != 0).astype(np.uint8))


def test_shadows_and_grey_clothes_are_told_apart_by_texture():
    """Both regions are the background darkened without a change of colour; only the shadow keeps
    the background's texture. Over a plain background the test cannot tell: no evidence."""
    bg = texture(0)
    rng = np.random.default_rng(5)
    floor = np.clip(128 + 25 * rng.standard_normal((80, 80)), 0, 255)[..., None] * np.ones(3)
    bg[140:220, 20:100] = floor.astype(np.uint8)
    bg[140:220, 200:280] = 128
    img = bg.copy()
    img[150:210, 30:60] = (bg[150:210, 30:60] * 0.7).astype(np.uint8)       # shadow on texture
    img[150:210, 60:90] = (0.7 * floor[10:70, 40:70].mean()).astype(np.uint8)  # plain grey cloth on texture
    img[150:210, 210:270] = 90                                              # darker over a plain floor
    labels = _labels(img, bg)
    hit = read_shadows(labels, img, bg, None, shadow_as=0)
    rows = slice(153, 207)
    assert np.mean(hit[rows, 33:57] == 0) > 0.9                             # shadow: background
    # Cloth: object (the rest are pixels where the random floor happens to match the cloth, F ≤ γ).
    assert np.mean(hit[rows, 63:87] == 1) > 0.8 and np.all(hit[rows, 63:87] != 2)
    assert np.mean(hit[rows, 213:267] == 2) > 0.9                           # cannot tell: no evidence
    # The foreground alone calls both darkened regions on the texture shadow-like (unsure).
    assert np.mean(labels[rows, 63:87] == 2) > 0.8
    # Read as no evidence instead of background: the shadow then reads 2.
    assert np.mean(read_shadows(labels, img, bg, None, shadow_as=2)[rows, 33:57] == 2) > 0.9


def test_the_compiled_texture_test_agrees_with_the_reference():
    rng = np.random.default_rng(3)
    bg = texture(1)
    img = np.clip(bg * rng.uniform(0.4, 1.1, (H, W, 1)) + rng.normal(0, 6, (H, W, 3)), 0, 255).astype(np.uint8)
    labels = _labels(img, bg)
    where = rng.random((H, W)) < 0.7
    inner = np.zeros((H, W), bool)
    inner[60:150, 100:220] = True
    for w in (None, where, inner):
        for shadow_as in (0, 2):
            a = read_shadows(labels, img, bg, w, shadow_as)
            b = read_shadows_reference(labels, img, bg, w, shadow_as)
            assert (a != b).sum() <= 3                      # exact window sums against float32 box filters
            if w is inner:
                assert np.all(a[~inner] != 2)
    a = read_shadows(labels, img, bg, where, 0)
    assert all(0.05 < np.mean(a == v) < 0.9 for v in (0, 1, 2))
