"""Articulated bodies: sizes, proportions, gait tied to speed, sitting."""

import numpy as np
import pytest

from worldtrack.synth.bodies import (HEAD, HEIGHT_RANGE, L_SHANK, L_UPPER_ARM, NOSE, PELVIS, R_UPPER_ARM,
                                     SHOULDER_RANGE, BodyShape, body_parts, draw_body_shape)
from worldtrack.synth.joints import JointAngles, gait_amplitude, posed


def test_drawn_heights_and_shoulder_widths_stay_in_range():
    rng = np.random.default_rng(0)
    shapes = [draw_body_shape(rng) for _ in range(400)]
    h = np.array([s.height for s in shapes])
    w = np.array([s.shoulder_width for s in shapes])
    assert h.min() >= HEIGHT_RANGE[0] and h.max() <= HEIGHT_RANGE[1]
    assert w.min() >= SHOULDER_RANGE[0] and w.max() <= SHOULDER_RANGE[1]
    assert h.max() - h.min() > 0.3 and w.max() - w.min() > 0.1     # really drawn per person
    assert len({s.top for s in shapes}) > 50                        # clothes vary


def test_camouflage_makes_some_clothes_close_to_the_background():
    rng = np.random.default_rng(1)
    bg = np.array([[150.0, 160.0, 165.0]])
    shapes = [draw_body_shape(rng, camouflage=bg, p_camouflage=0.5) for _ in range(200)]
    d = [min(np.abs(np.array(s.top) - bg[0]).max(), np.abs(np.array(s.bottom) - bg[0]).max()) for s in shapes]
    assert 0.3 < np.mean(np.array(d) < 30) < 0.7


@pytest.mark.parametrize("H, W", [(1.50, 0.35), (1.72, 0.45), (1.95, 0.55)])
def test_standing_body_is_height_tall_and_shoulder_width_wide(H, W):
    shape = BodyShape(H, W)
    ja = JointAngles.neutral([[1.0, 2.0]], [0.3])
    parts = body_parts([shape], ja)
    assert parts.head_top[0, 2] == pytest.approx(H, abs=2e-3)
    # Breadth across the upper arms at shoulder level, measured along the body's lateral axis.
    lateral = np.array([-np.sin(0.3), np.cos(0.3), 0.0])
    ends = []
    for k in (L_UPPER_ARM, R_UPPER_ARM):
        a = parts.centre[k]
        ends.append(a @ lateral + np.sign(a @ lateral - np.array([1.0, 2.0, 0]) @ lateral) * parts.radius[k])
    assert abs(ends[0] - ends[1]) == pytest.approx(W, abs=1e-9)
    # Nothing below the floor, feet on it.
    S = parts.shape_matrices()
    ell = parts.kind == 0
    lowest = parts.centre[ell, 2] - np.sqrt(S[ell, 2, 2])
    assert lowest.min() == pytest.approx(0.0, abs=2e-3)


def test_standing_legs_do_not_swing_walking_legs_do():
    shape = [BodyShape(1.75, 0.45)]
    xy, yaw = [[0.0, 0.0]], [0.0]
    still = [body_parts(shape, posed(xy, yaw, ph, gait_amplitude(0.0), 0.0)) for ph in np.linspace(0, 2 * np.pi, 7)]
    for p in still[1:]:
        np.testing.assert_allclose(p.centre, still[0].centre, atol=1e-12)
        np.testing.assert_allclose(p.end, still[0].end, atol=1e-12)
    walk = [body_parts(shape, posed(xy, yaw, ph, gait_amplitude(1.3), 0.0)) for ph in (0.0, np.pi / 2, np.pi)]
    ankle_x = [p.end[L_SHANK, 0] for p in walk]
    assert max(ankle_x) - min(ankle_x) > 0.3                        # the left foot swings ~0.4 m


def test_sitting_lowers_the_head_and_keeps_the_ground_point():
    shape = [BodyShape(1.75, 0.45)]
    stand = body_parts(shape, posed([[0, 0]], [0.0], 0.0, 0.0, 0.0))
    sit = body_parts(shape, posed([[0, 0]], [0.0], 0.0, 0.0, 1.0))
    assert stand.head_top[0, 2] - sit.head_top[0, 2] > 0.35
    np.testing.assert_allclose(sit.centre[PELVIS, :2], [0.0, 0.0], atol=0.05)
    assert sit.end[L_SHANK, 0] > 0.3                                 # feet in front of the pelvis


def test_gait_amplitude_is_zero_at_rest_and_grows_with_speed():
    a = gait_amplitude([0.0, 0.5, 1.0, 1.3, 3.0])
    assert a[0] == 0.0 and np.all(np.diff(a) >= 0) and a[3] == pytest.approx(1.0)


def test_head_points_along_the_heading():
    parts = body_parts([BodyShape(1.7, 0.45)], JointAngles.neutral([[0, 0]], [np.pi / 2]))
    nose = parts.centre[NOSE] - parts.centre[HEAD]
    assert nose[1] > 0.08 and abs(nose[0]) < 1e-9
