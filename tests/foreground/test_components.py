"""connected_components (Grana's algorithm) against OpenCV's default labelling."""

import cv2
import numpy as np
import pytest

from worldtrack.foreground.components import connected_components


@pytest.mark.parametrize("seed", range(5))
def test_same_labels_and_stats_as_the_default_algorithm(seed):
    rng = np.random.default_rng(seed)
    # Blobs of many sizes and shapes, touching diagonally in places (8-connectivity matters).
    noise = cv2.GaussianBlur(rng.random((240, 320)).astype(np.float32), (0, 0), 1 + seed)
    mask = (noise > np.quantile(noise, 0.7)).astype(np.uint8)
    n, labels, stats, cent = connected_components(mask)
    n0, labels0, stats0, cent0 = cv2.connectedComponentsWithStats(mask, connectivity=8)
    assert n == n0 > 3
    np.testing.assert_array_equal(labels, labels0)
    np.testing.assert_array_equal(stats, stats0)
    np.testing.assert_allclose(cent, cent0)


def test_two_diagonal_pixels_are_one_component_and_stats_are_exact():
    mask = np.zeros((6, 8), np.uint8)
    mask[1, 1] = mask[2, 2] = 1          # diagonal neighbours: one component
    mask[4, 5:8] = 1                     # a 3-pixel bar at the right border
    n, labels, stats, cent = connected_components(mask)
    assert n == 3
    assert labels[1, 1] == labels[2, 2] != labels[4, 6]
    np.testing.assert_array_equal(stats[labels[1, 1]], [1, 1, 2, 2, 2])
    np.testing.assert_array_equal(stats[labels[4, 6]], [5, 4, 3, 1, 3])
    np.testing.assert_allclose(cent[labels[4, 6]], [6.0, 4.0])
