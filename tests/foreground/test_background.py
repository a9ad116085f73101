"""Foreground models: the fused colour kernel against its reference, shadows, thresholds."""

import numpy as np
import pytest

from worldtrack.errors import InputError
from worldtrack.foreground.background import UNSURE, StaticBackground
from worldtrack.foreground.kernels import colour_labels, colour_labels_reference


def scene_pair(seed=0):
    rng = np.random.default_rng(seed)
    bg = rng.integers(40, 220, (60, 80, 3), dtype=np.uint8)
    img = np.clip(bg.astype(int) + rng.normal(0, 4, bg.shape), 0, 255).astype(np.uint8)
    img[10:30, 10:20] = (20, 200, 40)                                   # a green shirt
    img[35:50, 40:70] = (bg[35:50, 40:70] * 0.6).astype(np.uint8)       # a cast shadow
    img[5:15, 50:60] = np.clip(bg[5:15, 50:60] * 1.5, 0, 255).astype(np.uint8)  # brighter: not a shadow
    return bg, img


@pytest.mark.parametrize("shadows", [False, True])
def test_kernel_equals_reference(shadows):
    for seed in range(3):
        bg, img = scene_pair(seed)
        n2 = np.maximum(np.einsum("hwc,hwc->hw", bg.astype(np.float32), bg.astype(np.float32)), 1.0).astype(np.float32)
        fast = colour_labels(img, bg, n2, 20.0, shadows, 0.45, 0.08)
        ref = colour_labels_reference(img, bg, 20.0, shadows, 0.45, 0.08)
        # float32 rounding may flip a pixel exactly at a threshold; nothing more
        assert (fast != ref).sum() <= 2


def test_shadow_is_unsure_and_shirt_is_foreground():
    bg, img = scene_pair()
    fg = StaticBackground(bg, 20, "colour", shadows=True)
    lab = fg.labels(img)
    assert (lab[10:30, 10:20] == 1).mean() > 0.99
    assert (lab[35:50, 40:70] == UNSURE).mean() > 0.95
    assert (lab[5:15, 50:60] == 1).mean() > 0.95          # brighter than the background: not shadow
    assert (lab[55:, :5] == 0).all()                        # untouched background
    plain = StaticBackground(bg, 20, "colour", shadows=False).labels(img)
    assert (plain[35:50, 40:70] == 1).mean() > 0.95         # without the test the shadow is foreground
    np.testing.assert_array_equal(fg.mask(img), (lab == 1).astype(np.uint8))



def test_grey_mode_with_shadows_labels_the_cast_shadow_unsure():
    bg, img = scene_pair()
    lab = StaticBackground(bg, 20, "grey", shadows=True).labels(img)
    shadow = np.zeros(lab.shape, bool)
    shadow[35:50, 40:70] = True
    assert (lab[shadow] == UNSURE).mean() > 0.95 and not (lab[shadow] == 1).any()
    assert not (lab[~shadow] == UNSURE).any()               # nothing else is shadow-like
    assert (lab[5:15, 50:60] == 1).mean() > 0.95            # brighter than the background: not shadow
    plain = StaticBackground(bg, 20, "grey", shadows=False).labels(img)
    assert (plain[shadow] == 1).mean() > 0.95               # without the test the shadow is foreground

def test_grey_mode_misses_equal_brightness_colour():
    bg = np.full((10, 10, 3), 120, np.uint8)
    img = bg.copy()
    img[2:5, 2:5] = (30, 165, 120)      # grey level ≈ 120·0.299 + … : same brightness, other colour
    grey = StaticBackground(bg, 25, "grey").mask(img)
    colour = StaticBackground(bg, 25, "colour").mask(img)
    assert grey[2:5, 2:5].sum() == 0 and colour[2:5, 2:5].all()


def test_wrong_frame_size_is_a_clear_error():
    bg, img = scene_pair()
    with pytest.raises(InputError, match="frame is 40x30 but the background is 80x60"):
        StaticBackground(bg, 20, "colour").mask(img[:30, :40])
