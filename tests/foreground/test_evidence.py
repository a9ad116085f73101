"""Shadow or cloth by pooled evidence (``foreground.shadow_test = "evidence"``): patches whose answer
is known — a shadow on a textured floor is not foreground, grey cloth on the grey floor is."""

import numpy as np
import pytest

from worldtrack.config import from_mapping
from worldtrack.errors import InputError
from worldtrack.foreground import FOREGROUNDS, ForegroundConfig, StaticBackground
from worldtrack.foreground.background import UNSURE
from worldtrack.foreground.evidence import (ABOVE_FEET, EvidenceSettings, brightness_ratio, judge_by_evidence,
                                            judge_by_evidence_reference, texture_evidence, texture_evidence_reference)

SHADOW = 3


def tiled_floor(h=80, w=120, seed=0, grey_level=130.0, tile=8):
    """A grey tiled floor: tiles of ±10 % brightness, dark grout lines, fine specks (no noise)."""
    rng = np.random.default_rng(seed)
    tiles = 1 + rng.uniform(-0.1, 0.1, (h // tile + 1, w // tile + 1))
    f = np.kron(tiles, np.ones((tile, tile)))[:h, :w] * (1 + rng.normal(0, 0.04, (h, w)))
    f[::tile, :] *= 0.7
    f[:, ::tile] *= 0.7
    return np.clip(grey_level * f[..., None] * np.array([0.97, 1.0, 1.03]), 0, 255).astype(np.uint8)


def noisy(img, rng, sd=2.0):
    return np.clip(img + rng.normal(0, sd, img.shape), 0, 255).astype(np.uint8)


def scene(seed=1):
    """The floor, a frame with a cast shadow (rows 5–35, columns 5–55) and grey cloth of the floor's
    colour, shaded darker (rows 40–75, columns 65–115), and the labels the colour test gives them."""
    rng = np.random.default_rng(seed)
    bg = tiled_floor()
    img = bg.copy()
    img[5:35, 5:55] = bg[5:35, 5:55] * 0.6                                 # shadow: the tiles, darker
    cloth = 130.0 * np.array([0.97, 1.0, 1.03]) * 0.6                       # the floor's grey, in shade
    fabric = 1 + 0.03 * np.sin(np.arange(35) * 2.1)[:, None, None]          # its own weave, not the tiles'
    img[40:75, 65:115] = np.clip(cloth * fabric, 0, 255)
    img = noisy(img, rng)
    labels = np.zeros(bg.shape[:2], np.uint8)
    labels[5:35, 5:55] = UNSURE
    labels[40:75, 65:115] = UNSURE
    return bg, img, labels


def test_the_evidence_is_the_log_likelihood_ratio_of_slope_r_against_slope_0():
    b = np.tile(np.array([100, 140], np.uint8), (9, 5))[:, :9]              # stripes, var(b) = 400
    # The stripes at half brightness, exactly: β = r = 0.5, nothing left over, s² = 1e-6.
    assert texture_evidence((b // 2).astype(np.uint8), b)[4, 4] == pytest.approx((0.5 - 0.25) * 0.5 / 1e-6, rel=1e-3)
    # Flat at 60: β = 0, r = 60 / mean(b) over the 5 × 5 window, nothing left over.
    r = 60 / np.mean(b[2:7, 2:7])
    assert texture_evidence(np.full_like(b, 60), b)[4, 4] == pytest.approx(-0.5 * r * r / 1e-6, rel=1e-3)
    # Stripes of their own, opposite in phase: β = −0.5, the residual is 0 again.
    assert texture_evidence((240 - b) // 2, b)[4, 4] < 0


def test_a_shadow_on_a_textured_floor_is_not_foreground_and_grey_cloth_is():
    bg, img, labels = scene()
    out = judge_by_evidence(labels, img, bg, candidate=UNSURE, cloth=1, shadow=SHADOW)
    assert np.all(out[5:35, 5:55] == SHADOW)                               # every shadow pixel
    assert np.all(out[40:75, 65:115] == 1)                                 # every cloth pixel
    assert np.all(out[labels == 0] == 0)                                   # nothing else touched


def test_without_texture_nothing_is_decided_but_cloth_darker_than_the_frames_shadows_is_foreground():
    rng = np.random.default_rng(4)
    bg = tiled_floor()
    bg[:, 60:] = 130                                                       # the right half: a plain floor
    img = bg.copy()
    img[5:35, 5:55] = bg[5:35, 5:55] * 0.6                                 # a shadow on the tiles (sure)
    img[45:75, 65:90] = bg[45:75, 65:90] * 0.6                             # a shadow on the plain floor
    img[45:75, 95:115] = bg[45:75, 95:115] * 0.45                          # cloth, darker than any shadow
    img = noisy(img, rng)
    labels = np.zeros(bg.shape[:2], np.uint8)
    for rows, cols in ((slice(5, 35), slice(5, 55)), (slice(45, 75), slice(65, 90)), (slice(45, 75), slice(95, 115))):
        labels[rows, cols] = UNSURE
    out = judge_by_evidence(labels, img, bg)
    assert np.all(out[5:35, 5:55] == SHADOW)
    assert np.all(out[45:75, 65:90] == UNSURE)                             # plain floor, the shadows' darkness
    assert np.all(out[45:75, 95:115] == 1)                                 # 0.45 < 0.6 − 0.06
    # Without enough sure shadows the frame's shadow darkness is not known: all unsure on the plain floor.
    few = judge_by_evidence(labels, img, bg, EvidenceSettings(min_sure_px=10 ** 6))
    assert np.all(few[45:75, 65:115][labels[45:75, 65:115] == UNSURE] == UNSURE)
    sure = np.zeros(labels.shape, bool)
    sure[5:35, 5:55] = True
    assert float(np.median(brightness_ratio(img, bg, sure))) == pytest.approx(0.6, abs=0.01)


def test_the_kernel_equals_the_box_filter_reference_also_at_the_border():
    rng = np.random.default_rng(5)
    bg = tiled_floor(50, 70, seed=2)[..., 1]
    img = np.clip(bg * rng.uniform(0.3, 1.0, bg.shape) + rng.normal(0, 5, bg.shape), 0, 255).astype(np.uint8)
    for window, samples in ((5, 0.25), (7, 1.0)):
        ref = texture_evidence_reference(img, bg, window, samples)
        np.testing.assert_allclose(texture_evidence(img, bg, window, samples), ref, rtol=1e-6, atol=1e-6)
    where = rng.random(bg.shape) < 0.3
    part = texture_evidence(img, bg, where=where)
    np.testing.assert_allclose(part[where], texture_evidence_reference(img, bg)[where], rtol=1e-6, atol=1e-6)
    assert np.all(part[~where] == 0)


def test_the_cropped_judge_equals_the_whole_image_reference():
    rng = np.random.default_rng(7)
    bg = tiled_floor(120, 160, seed=3)
    img = noisy(bg * rng.uniform(0.4, 1.0, bg.shape[:2])[..., None], rng, 6.0)
    labels = np.zeros(bg.shape[:2], np.uint8)
    labels[30:70, 40:110] = rng.integers(0, 3, (40, 70))                   # candidates near no border
    labels[0:12, 150:160] = UNSURE                                          # and at a corner
    for settings in (EvidenceSettings(), EvidenceSettings(window=7, spread=9, min_sure_px=10)):
        fast = judge_by_evidence(labels, img, bg, settings)
        ref = judge_by_evidence_reference(labels, img, bg, settings)
        assert np.array_equal(fast, ref)
    assert np.array_equal(judge_by_evidence(np.zeros_like(labels), img, bg), np.zeros_like(labels))


def test_static_background_with_the_evidence_test_and_its_setting():
    bg, img, _ = scene()
    colour = StaticBackground(bg, 20.0, "colour", shadows=True).labels(img)
    evidence = StaticBackground(bg, 20.0, "colour", shadows=True, shadow_test="evidence").labels(img)
    cloth_colour, cloth_evidence = colour[40:75, 65:115], evidence[40:75, 65:115]
    assert (cloth_colour == UNSURE).mean() > 0.9 > 0.02 > (cloth_colour == 1).mean()  # colour alone: shadow-like
    assert np.all(cloth_evidence[cloth_colour == UNSURE] == 1)             # (the grout it matches stays 0)
    assert np.all(evidence[7:33, 7:53] == UNSURE)                           # judged shadows stay unsure
    assert np.array_equal(evidence[colour != UNSURE], colour[colour != UNSURE])
    background = StaticBackground(bg, 20.0, "colour", shadows=True, shadow_test="evidence-background").labels(img)
    assert np.all(background[7:33, 7:53] == 0)                              # judged shadows: background
    changed = background != evidence
    assert np.all(evidence[changed] == UNSURE) and np.all(background[changed] == 0)   # and nothing else
    with pytest.raises(InputError, match="shadow test: expected one of 'colour', 'evidence', "
                                         "'evidence-background', 'evidence-sure', 'evidence-above-feet', "
                                         "got 'texture'"):
        StaticBackground(bg, 20.0, "colour", shadows=True, shadow_test="texture")
    assert ForegroundConfig().shadow_test is None                           # the method's own (a run fills it in)
    assert ForegroundConfig().resolved_shadow_test() == "colour"
    assert ForegroundConfig(shadow_test="evidence").resolved_shadow_test() == "evidence"
    for kind in ("grey", "colour"):                                          # the registry passes it on
        assert FOREGROUNDS[kind](bg, 20.0, True, None, "evidence").shadow_test == "evidence"
    with pytest.raises(InputError, match="foreground.shadow_test"):
        from_mapping(ForegroundConfig, {"shadow_test": "texture"}, root="foreground")


def test_the_sure_test_leaves_weak_evidence_unsure_and_still_calls_plain_cloth_foreground():
    """A shade that shows the floor's pattern at about half the shadow's contrast (pooled evidence
    about −2.4, between the two tests' thresholds: what a compressed real shadow looks like) is
    mostly cloth to "evidence" and mostly unsure to "evidence-sure"; plain cloth of the floor's
    colour is foreground to both."""
    bg = tiled_floor()
    img = bg.astype(float)
    patch = img[20:60, 30:90].copy()
    img[20:60, 30:90] = 0.6 * (0.488 * patch + 0.512 * patch.mean(axis=(0, 1)))   # weak: β ≈ 0.29 for r = 0.6
    img[62:78, 30:90] = 0.6 * img[62:78, 30:90].mean(axis=(0, 1))                 # plain cloth: β = 0
    img = noisy(img, np.random.default_rng(1))
    def labels(test):
        return StaticBackground(bg, 20.0, "colour", shadows=True, shadow_test=test).labels(img)
    colour, evidence, sure = labels("colour"), labels("evidence"), labels("evidence-sure")
    weak = colour[20:60, 30:90] == UNSURE
    assert weak.mean() > 0.9
    assert (evidence[20:60, 30:90][weak] == 1).mean() > 0.7                     # 0.79 measured
    assert (sure[20:60, 30:90][weak] == 1).mean() < 0.4                         # 0.13 measured (±3: 0.40)
    plain = colour[66:74, 36:84] == UNSURE                                      # (away from the weak patch's pooling)
    assert plain.mean() > 0.9 and np.all(sure[66:74, 36:84][plain] == 1)
    assert np.array_equal(sure[colour != UNSURE], colour[colour != UNSURE])
    assert ForegroundConfig(shadow_test="evidence-sure").resolved_shadow_test() == "evidence-sure"


def test_above_the_feet_no_contact_shadow_becomes_cloth_and_the_trousers_above_still_do():
    """A person: a red top (rows 10-40), trousers of the floor's grey in shade (40-70), dark shoes
    (70-74), and under them a contact shadow that lost the floor's pattern (74-86: plain, as on
    compressed video). "evidence-sure" calls trousers and shadow cloth; "evidence-above-feet" the
    trousers only (the lowest tenth of the silhouette and below it stay unsure), and a plain shade
    with no body at all stays unsure too."""
    bg = tiled_floor(h=100)
    img = bg.astype(float)
    grey_shade = 0.6 * img.mean(axis=(0, 1))
    img[10:40, 40:60] = (40, 40, 200)                                   # red top (BGR)
    img[40:70, 42:58] = grey_shade                                      # floor-coloured trousers
    img[70:74, 40:60] = 20                                              # shoes
    img[74:86, 30:70] = grey_shade                                      # contact shadow, pattern lost
    img[60:90, 95:115] = grey_shade                                     # a plain shade, nobody above
    img = noisy(img, np.random.default_rng(2))
    def labels(test):
        return StaticBackground(bg, 20.0, "colour", shadows=True, shadow_test=test).labels(img)
    colour, sure, above = labels("colour"), labels("evidence-sure"), labels("evidence-above-feet")
    trousers, shadow, lone = (slice(42, 64), slice(44, 56)), (slice(76, 86), slice(32, 68)), \
        (slice(62, 88), slice(97, 113))
    for part in (trousers, shadow, lone):
        assert (colour[part] == UNSURE).mean() > 0.9
        assert (sure[part] == 1).mean() > 0.9
    assert (above[trousers] == 1).mean() > 0.9
    for part in (shadow, lone):                                         # no shade turned cloth
        assert not np.any((above[part] == 1) & (colour[part] == UNSURE))
    assert np.array_equal(above[colour != UNSURE], colour[colour != UNSURE])
    same = judge_by_evidence(colour, img, bg, ABOVE_FEET)
    assert np.array_equal(same, judge_by_evidence_reference(colour, img, bg, ABOVE_FEET))
    assert ForegroundConfig(shadow_test="evidence-above-feet").resolved_shadow_test() == "evidence-above-feet"
