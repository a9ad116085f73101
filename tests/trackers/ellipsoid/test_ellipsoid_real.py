"""The ternary real image (paper 000 §4): the compiled octagon ring against OpenCV's dilations."""

import numpy as np
import pytest

from worldtrack.trackers.ellipsoid.real import ternary_real, ternary_real_reference, within_l1, within_l1_reference


@pytest.mark.parametrize("ring", [1, 5, 20])
def test_ternary_real_dilating_the_foreground_box_equals_the_whole_frame(ring):
    rng = np.random.default_rng(ring)
    for trial in range(12):
        H, W = rng.integers(20, 130), rng.integers(20, 170)
        labels = np.zeros((H, W), np.uint8)
        if trial == 0:
            pass                                                         # no foreground at all
        elif trial % 3 == 0:
            labels[rng.random((H, W)) < 0.01] = 1                        # scattered pixels
        else:
            for _ in range(rng.integers(1, 4)):
                y, x = rng.integers(0, H), rng.integers(0, W)
                labels[y:y + rng.integers(1, 25), x:x + rng.integers(1, 25)] = 1
        if trial % 2:
            labels[0, rng.integers(0, W)] = labels[rng.integers(0, H), W - 1] = 1   # blobs on the border
        labels[rng.random((H, W)) < 0.05] = 2                            # unsure pixels stay 0
        out = ternary_real(labels, ring)
        np.testing.assert_array_equal(out, ternary_real_reference(labels, ring))
        assert out.dtype == np.int8 and (out == -1).any() == (labels == 1).any()


@pytest.mark.parametrize("radius", [0, 1, 2, 7, 26])
def test_within_l1_equals_the_iterated_cross_dilation(radius):
    rng = np.random.default_rng(radius)
    for trial in range(8):
        H, W = int(rng.integers(1, 90)), int(rng.integers(1, 120))
        fg = (rng.random((H, W)) < rng.choice([0.0, 0.002, 0.02, 0.3])).astype(np.uint8)
        if trial % 2:
            fg[0, rng.integers(0, W)] = fg[rng.integers(0, H), W - 1] = 1    # on the border
        out = within_l1(fg, radius)
        np.testing.assert_array_equal(out, within_l1_reference(fg, radius))
        assert out.dtype == np.uint8 and out.shape == (H, W)
    # One pixel: exactly the diamond |du| + |dv| <= radius around it.
    fg = np.zeros((61, 61), np.uint8)
    fg[30, 30] = 1
    v, u = np.mgrid[0:61, 0:61]
    np.testing.assert_array_equal(within_l1(fg, radius), (np.abs(u - 30) + np.abs(v - 30) <= radius).astype(np.uint8))
