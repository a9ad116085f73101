"""The feet anchor on one camera: the person stands beyond the toe their silhouette ends at (``feet.centre_offset_m``)."""

import numpy as np
import pytest
from _line_of_sight import anchored_shift, line_of_sight_frame

from worldtrack.trackers.ellipsoid.config import FeetConfig
from worldtrack.trackers.ellipsoid.feet import feet_weight
from worldtrack.trackers.ellipsoid.toes import beyond_toes


@pytest.fixture(scope="module")
def seen():
    return line_of_sight_frame()


def test_the_feet_found_move_beyond_the_toes_along_the_line_of_sight(seen):
    tracker, labels, instance, truth = seen
    shift, ray, _ = anchored_shift(tracker, labels, truth, FeetConfig(anchor=True, centre_offset_m=0.0),
                                   FeetConfig(anchor=True, centre_offset_m=0.08))
    # The same feet, 8 cm farther: the anchor's share of it, along the ray and not across it.
    assert float(shift @ ray) == pytest.approx(feet_weight(0.3, 0.1) * 0.08, abs=0.005)
    assert abs(float(shift[0] * ray[1] - shift[1] * ray[0])) < 0.003


def test_beyond_toes_is_exact_and_zero_is_the_identity():
    feet = np.array([3.0, 4.0])
    assert beyond_toes(feet, np.zeros(2), 0.0) is feet
    assert np.allclose(beyond_toes(feet, np.zeros(2), 0.5), [3.3, 4.4])
    assert np.allclose(beyond_toes(feet, np.array([3.0, 0.0]), 0.1), [3.0, 4.1])
