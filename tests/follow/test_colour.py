"""Colour model: eq. 1 against OpenCV's compareHist, the gain undo, histograms of silhouettes."""

import cv2
import numpy as np
import pytest

from worldtrack.follow import FollowConfig
from worldtrack.follow.colour import (bhattacharyya, bhattacharyya_reference, grey_world_gains, histograms,
                                      n_bins, normalise_colour, undo_gains)


def test_vectorised_distance_equals_opencv_compare_hist():
    rng = np.random.default_rng(1)
    h = rng.random((5, 40)).astype(np.float32) ** 3
    h /= h.sum(axis=1, keepdims=True)
    t = rng.random((3, 40)).astype(np.float32)
    t /= t.sum(axis=1, keepdims=True)
    np.testing.assert_allclose(bhattacharyya(h, t), bhattacharyya_reference(h, t), atol=2e-6)
    # eq. 1 by hand for one pair
    expected = np.sqrt(1 - np.sum(np.sqrt(h[0] * t[0])))
    assert bhattacharyya(h[:1], t[:1])[0, 0] == pytest.approx(expected, abs=1e-6)
    assert bhattacharyya(h[:1], h[:1])[0, 0] == pytest.approx(0.0, abs=1e-3)


def test_gain_undo_inverts_the_camera_gains_where_nothing_saturated():
    rng = np.random.default_rng(2)
    raw = rng.integers(20, 120, (30, 40, 3)).astype(np.uint8)
    r, b = 700, 380
    recorded = np.clip(np.rint(raw * np.array([b / 512, 1, r / 512])), 0, 255).astype(np.uint8)
    back = undo_gains(recorded, (r, b)).astype(int)
    assert np.abs(back - raw.astype(int)).max() <= 1


def test_a_gain_jump_moves_the_histogram_unless_undone():
    cfg = FollowConfig(grey_bins=0)
    rng = np.random.default_rng(3)
    img = np.full((60, 60, 3), 128, np.uint8)
    img[10:50, 20:40] = (60, 90, 150)                                # a person in brown
    img = np.clip(img + rng.normal(0, 3, img.shape), 0, 255).astype(np.uint8)
    labels = np.zeros((60, 60), np.int32)
    labels[10:50, 20:40] = 1
    template = histograms(img, labels, 1, cfg)
    jumped = np.clip(np.rint(img * np.array([300 / 512, 1, 820 / 512])), 0, 255).astype(np.uint8)
    plain = histograms(jumped, labels, 1, cfg)
    undone = histograms(normalise_colour(jumped, (820, 300), "gains")[0], labels, 1, cfg)
    assert bhattacharyya(plain, template)[0, 0] > 0.5
    assert bhattacharyya(undone, template)[0, 0] < 0.2


def test_grey_world_balances_a_tinted_background_and_ignores_people():
    img = np.full((40, 40, 3), (100, 120, 150), np.uint8)           # warm light on a grey wall
    people = np.zeros((40, 40), bool)
    img[:, :10] = (200, 20, 20)                                      # a blue coat
    people[:, :10] = True
    r, b = grey_world_gains(img, people)
    assert r == pytest.approx(512 * 120 / 150, abs=1) and b == pytest.approx(512 * 120 / 100, abs=1)


def test_histograms_sum_to_one_and_dark_pixels_go_to_grey_bins():
    cfg = FollowConfig()
    img = np.zeros((10, 10, 3), np.uint8)
    img[:, 5:] = (0, 0, 255)
    labels = np.zeros((10, 10), np.int32)
    labels[:, :5], labels[:, 5:] = 1, 2
    h = histograms(img, labels, 3, cfg)
    assert h.shape == (3, n_bins(cfg))
    np.testing.assert_allclose(h[:2].sum(axis=1), 1.0, atol=1e-6)
    assert h[2].sum() == 0                                           # an empty silhouette
    grey = slice(cfg.hue_bins * cfg.sat_bins, None)
    assert h[0, grey].sum() == pytest.approx(1.0) and h[1, grey].sum() == 0
    hsv = cv2.cvtColor(np.uint8([[[0, 0, 255]]]), cv2.COLOR_BGR2HSV)[0, 0].astype(int)
    assert h[1, (hsv[0] * cfg.hue_bins // 180) * cfg.sat_bins + hsv[1] * cfg.sat_bins // 256] == pytest.approx(1.0)
