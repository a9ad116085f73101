"""The feet's σ along the line of sight holds the floor span of the pixels at the feet (``feet.pixel_sigma_px``)."""

import numpy as np
import pytest
from _line_of_sight import line_of_sight_frame, misplaced

from worldtrack.trackers.ellipsoid.config import FeetConfig, HeightConfig
from worldtrack.trackers.ellipsoid.feet import anchor_to_feet, feet_weight
from worldtrack.trackers.ellipsoid.feet_pixel import feet_sigma_m, metres_per_pixel, pixel_sigma_m


@pytest.fixture(scope="module")
def seen():
    return line_of_sight_frame()


def _down(cam, xy):
    """The image's down direction (2,) at floor point ``xy``: towards the camera's foot along the floor."""
    a = cam.project(np.array([[xy[0], xy[1], 0.0]]))[0]
    toward = xy + 0.01 * (cam.centre[:2] - xy) / np.hypot(*(cam.centre[:2] - xy))
    b = cam.project(np.array([[toward[0], toward[1], 0.0]]))[0]
    return (b - a) / np.hypot(*(b - a))


def test_one_pixel_spans_the_floor_as_the_geometry_says(seen):
    tracker, _, _, truth = seen
    cam = tracker.scene.cameras["cam"]
    xy = np.array([truth["x"], truth["y"]])
    d, h = float(np.hypot(*(xy - cam.centre[:2]))), float(cam.centre[2])
    f = float(cam.K[1, 1])
    pixel = cam.project(np.array([[xy[0], xy[1], 0.0]]))[0]
    span = metres_per_pixel(cam, pixel, _down(cam, xy))
    # ds/dv = (d² + H²) / (H f) for a pixel below the image centre row (to within the tilt's share).
    assert span == pytest.approx((d * d + h * h) / (h * f), rel=0.25)
    farther = xy + 3.0 * (xy - cam.centre[:2]) / d
    far_pixel = cam.project(np.array([[farther[0], farther[1], 0.0]]))[0]
    assert metres_per_pixel(cam, far_pixel, _down(cam, farther)) > 1.5 * span


def test_zero_keeps_the_fixed_sigma_and_more_pixels_weigh_the_feet_less(seen):
    tracker, _, _, truth = seen
    cam = tracker.scene.cameras["cam"]
    xy = np.array([truth["x"], truth["y"]])
    assert feet_sigma_m(cam, xy, _down(cam, xy), 0.1, 0.0) == 0.1
    one, three = (feet_sigma_m(cam, xy, _down(cam, xy), 0.1, n) for n in (1.0, 3.0))
    assert 0.1 < one < three
    assert pixel_sigma_m(0.1, 3.0, 0.0) == 0.1


def test_the_anchor_pulls_less_when_the_pixels_at_the_feet_are_uncertain(seen):
    tracker, labels, _, truth = seen
    cam = tracker.scene.cameras["cam"]
    back = {}
    for n in (0.0, 3.0):
        p, xy = misplaced(tracker, truth, 0.6)
        assert anchor_to_feet([p], tracker.views, {"cam": labels}, tracker.walkable,
                              FeetConfig(anchor=True, pixel_sigma_px=n), HeightConfig()) == 1
        ray = (xy - cam.centre[:2]) / np.hypot(*(xy - cam.centre[:2]))
        back[n] = 0.6 - float((np.array([p.x, p.y]) - xy) @ ray)
    sigma = feet_sigma_m(cam, np.array([truth["x"], truth["y"]]), _down(cam, np.array([truth["x"], truth["y"]])), 0.1, 3.0)
    # The share of the way back to the feet is σ_e² / (σ_e² + σ_f²) with the larger σ of the feet.
    assert back[3.0] < back[0.0] - 0.05
    assert back[3.0] / back[0.0] == pytest.approx(feet_weight(0.3, sigma) / feet_weight(0.3, 0.1), abs=0.08)
