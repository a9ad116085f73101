"""The feet anchor on one camera: the person stands where a foot model's lowest image point says (``feet.footprint``)."""

import numpy as np
import pytest
from _line_of_sight import anchored_shift, line_of_sight_frame

from worldtrack.trackers.ellipsoid.anchor_footprint import (FOOT_HALF_HEIGHT_SHARE, REACH_SHARE, grazing_shortfall_m,
                                                            standing_point)
from worldtrack.trackers.ellipsoid.config import FeetConfig
from worldtrack.trackers.ellipsoid.feet import feet_weight


@pytest.fixture(scope="module")
def seen():
    return line_of_sight_frame()


def _brute_force_shortfall(cam_h: float, d: float, h: float) -> float:
    """The same quantity found another way: every point of the filled section (a dense grid), the
    one seen lowest in the image (largest depression), back-projected along its ray to the floor."""
    reach, half = REACH_SHARE * h, FOOT_HALF_HEIGHT_SHARE * h
    x, z = np.meshgrid(np.linspace(d - reach, d + reach, 801), np.linspace(0.0, 2 * half, 401))
    inside = ((x - d) / reach) ** 2 + ((z - half) / half) ** 2 <= 1.0
    slope = ((cam_h - z) / x)[inside]
    return d - cam_h / slope.max()


@pytest.mark.parametrize("cam_h, d", [(2.85, 5.0), (2.85, 9.0), (7.6, 20.0), (12.0, 4.0)])
def test_the_shortfall_is_where_the_grazing_ray_meets_the_floor(cam_h, d):
    assert grazing_shortfall_m(cam_h, d, 1.7) == pytest.approx(_brute_force_shortfall(cam_h, d, 1.7), abs=0.002)


def test_a_flatter_view_sees_the_toe_farther_away_and_a_steep_one_sees_it_where_it_is():
    reach = REACH_SHARE * 1.7
    near, far = grazing_shortfall_m(2.85, 4.0, 1.7), grazing_shortfall_m(2.85, 12.0, 1.7)
    assert far < near < reach
    # From high above, the lowest image point is the toe at the floor: the whole reach.
    assert grazing_shortfall_m(50.0, 3.0, 1.7) == pytest.approx(reach, abs=0.005)
    assert grazing_shortfall_m(2.85, 7.0, 1.9) > grazing_shortfall_m(2.85, 7.0, 1.5)   # bigger feet
    assert grazing_shortfall_m(0.05, 7.0, 1.7) == 0.0                                  # camera below the feet' top


def test_the_standing_point_lies_beyond_the_feet_along_the_line_of_sight():
    centre = np.array([1.0, 2.0, 2.85])
    feet = np.array([4.0, 6.0])                       # 5 m away along (0.6, 0.8)
    stands = standing_point(feet, centre, 1.7)
    step = stands - feet
    assert step[0] * 0.8 - step[1] * 0.6 == pytest.approx(0.0, abs=1e-9)
    assert float(step @ np.array([0.6, 0.8])) == pytest.approx(grazing_shortfall_m(2.85, 5.0 + np.hypot(*step), 1.7),
                                                               abs=1e-4)   # drawn at the standing point


def test_the_footprint_moves_the_anchored_person_beyond_the_feet_by_its_shortfall(seen):
    tracker, labels, instance, truth = seen
    cam = tracker.scene.cameras["cam"]
    shift, ray, xy = anchored_shift(tracker, labels, truth, FeetConfig(anchor=True),
                                    FeetConfig(anchor=True, footprint=True))
    expected = grazing_shortfall_m(float(cam.centre[2]), float(np.hypot(*(xy - cam.centre[:2]))), truth["height"])
    assert 0.05 < expected < 0.12
    assert float(shift @ ray) == pytest.approx(feet_weight(0.3, 0.1) * expected, abs=0.01)
    assert abs(float(shift[0] * ray[1] - shift[1] * ray[0])) < 0.003
