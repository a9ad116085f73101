"""The shadow labeller (foreground/shadows.py): cast shadows set apart from objects by colour and
texture, the compiled labels against the NumPy reference."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from worldtrack.foreground.shadows import hit_labels, hit_labels_reference

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "trackers"))
from _render import texture  # noqa: E402  (tests/trackers/_render.py)

H, W = 240, 320


def test_hit_labels_set_darkened_background_apart():
    bg = texture(0)
    img = bg.copy()
    img[100:140, 50:100] = (bg[100:140, 50:100] * 0.7).astype(np.uint8)    # a shadow
    img[100:140, 200:250] = (40, 30, 200)                                   # an object
    hit = hit_labels(img, bg, 25.0)
    assert np.mean(hit[100:140, 50:100] == 2) > 0.95 and np.mean(hit[100:140, 200:250] == 1) > 0.95
    assert np.all(hit[:90] == 0)
    # Shadows nowhere: every pixel with F > γ reads object, exactly the labels without shadows.
    where = np.zeros((H, W), bool)
    assert np.array_equal(hit_labels(img, bg, 25.0, where=where), (hit != 0).astype(np.uint8))


def test_hit_labels_tell_shadows_from_grey_clothes_by_texture():
    """Both regions are the background darkened without a change of colour; only the shadow keeps
    the background's texture. Over a plain background the test cannot tell: no evidence."""
    bg = texture(0)
    rng = np.random.default_rng(5)
    # A strongly textured floor patch (grey-level σ ≈ 25) and a plain one.
    floor = np.clip(128 + 25 * rng.standard_normal((80, 80)), 0, 255)[..., None] * np.ones(3)
    bg[140:220, 20:100] = floor.astype(np.uint8)
    bg[140:220, 200:280] = 128
    img = bg.copy()
    img[150:210, 30:60] = (bg[150:210, 30:60] * 0.7).astype(np.uint8)       # shadow on texture
    img[150:210, 60:90] = (0.7 * floor[10:70, 40:70].mean()).astype(np.uint8)  # plain grey cloth on texture
    img[150:210, 210:270] = 90                                              # darker over a plain floor
    hit = hit_labels(img, bg, 25.0, shadow=0)
    inner = (slice(153, 207),)
    assert np.mean(hit[inner[0], 33:57] == 0) > 0.9           # shadow: background
    # Cloth: object (the rest are pixels where the random floor happens to match the cloth, F ≤ γ).
    assert np.mean(hit[inner[0], 63:87] == 1) > 0.8 and np.all(hit[inner[0], 63:87] != 2)
    assert np.mean(hit[inner[0], 213:267] == 2) > 0.9         # cannot tell: no evidence
    # Without the texture test both darkened regions on the textured floor were shadows.
    old = hit_labels(img, bg, 25.0, shadow=0, texture=False)
    assert np.mean(old[inner[0], 63:87] == 1) < 0.05


def test_shadow_kernel_agrees_with_reference():
    rng = np.random.default_rng(3)
    bg = texture(1)
    img = np.clip(bg * rng.uniform(0.4, 1.1, (H, W, 1)) + rng.normal(0, 6, (H, W, 3)), 0, 255).astype(np.uint8)
    where = rng.random((H, W)) < 0.7
    # Shadows possible only inside the image, or only at a corner: the texture test then works on
    # the candidates' box alone, and must agree with the reference's whole image.
    inner, corner = np.zeros((H, W), bool), np.zeros((H, W), bool)
    inner[60:150, 100:220] = True
    corner[:40, -50:] = True
    for w in (None, where, inner, corner):
        a = hit_labels(img, bg, 25.0, where=w)
        b = hit_labels_reference(img, bg, 25.0, where=w)
        np.testing.assert_array_equal(a, b)
        if w is inner:
            assert 0.1 < np.mean(a[inner] == 2) < 0.9 and np.all(a[~inner] != 2)
    a = hit_labels(img, bg, 25.0, where=where)
    assert all(0.1 < np.mean(a == v) < 0.9 for v in (0, 1, 2))
    # A 3-pixel strip of shadow in a plain dark object: the texture windows of its pixels reach
    # into the object, which a box cut to the strip alone would miss (all shadow, not 84 of 120).
    floor = np.clip(128 + 25 * rng.standard_normal((H, W)), 0, 255)[..., None].repeat(3, 2).astype(np.uint8)
    img = np.full_like(floor, 60)
    img[100:140, 100:103] = (floor[100:140, 100:103] * 0.7).astype(np.uint8)
    strip = np.zeros((H, W), bool)
    strip[100:140, 100:103] = True
    a = hit_labels(img, floor, 25.0, where=strip, shadow=0)
    np.testing.assert_array_equal(a, hit_labels_reference(img, floor, 25.0, where=strip, shadow=0))
    assert 0 < np.sum(a[strip] == 2) < np.sum(a[strip] == 0)


# ---------------------------------------------------------------------------- leaving through an exit
