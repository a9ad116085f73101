"""Floor regions: uniform samples inside a rasterised region, and distances to a polygon."""

from __future__ import annotations

import numpy as np
import pytest

from worldtrack.trackers.particle.floor import FloorRegion, polygon_distance


def test_floor_region_samples_uniformly_inside():
    ring = np.array([[0, 0], [2, 0], [2, 1], [0, 1]], float)
    reg = FloorRegion.rasterise("r", (0, 2, 0, 1), 0.02, lambda xy: polygon_distance(xy, ring) == 0)
    pts = reg.sample(20000, np.random.default_rng(0))
    assert reg.contains(pts).all() and reg.area == pytest.approx(2.0, rel=0.01)
    assert np.mean(pts[:, 0] < 1) == pytest.approx(0.5, abs=0.02)
    np.testing.assert_allclose(polygon_distance([[3, 0.5], [1, 0.5], [1, -0.5]], ring), [1, 0, 0.5])
