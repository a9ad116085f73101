"""The feet anchor on one camera: the person stands beyond the toe their silhouette ends at (``feet.centre_offset_m``)."""

import numpy as np
import pytest
from _line_of_sight import line_of_sight_frame, misplaced

from worldtrack.trackers.ellipsoid.config import FeetConfig, HeightConfig
from worldtrack.trackers.ellipsoid.feet import anchor_to_feet, feet_weight
from worldtrack.trackers.ellipsoid.toes import beyond_toes


@pytest.fixture(scope="module")
def seen():
    return line_of_sight_frame()


def test_the_feet_found_move_beyond_the_toes_along_the_line_of_sight(seen):
    tracker, labels, instance, truth = seen
    cam = tracker.scene.cameras["cam"]
    placed = {}
    for offset in (0.0, 0.08):
        p, xy = misplaced(tracker, truth, 0.6)
        moved = anchor_to_feet([p], tracker.views, {"cam": labels}, tracker.walkable,
                               FeetConfig(anchor=True, centre_offset_m=offset), HeightConfig())
        assert moved == 1
        placed[offset] = np.array([p.x, p.y])
    ray = (xy - cam.centre[:2]) / np.hypot(*(xy - cam.centre[:2]))
    shift = placed[0.08] - placed[0.0]
    # The same feet, 8 cm farther: the anchor's share of it, along the ray and not across it.
    assert float(shift @ ray) == pytest.approx(feet_weight(0.3, 0.1) * 0.08, abs=0.005)
    assert abs(float(shift[0] * ray[1] - shift[1] * ray[0])) < 0.003


def test_beyond_toes_is_exact_and_zero_is_the_identity():
    feet = np.array([3.0, 4.0])
    assert beyond_toes(feet, np.zeros(2), 0.0) is feet
    assert np.allclose(beyond_toes(feet, np.zeros(2), 0.5), [3.3, 4.4])
    assert np.allclose(beyond_toes(feet, np.array([3.0, 0.0]), 0.1), [3.0, 4.1])
