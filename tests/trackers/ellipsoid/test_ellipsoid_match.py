"""How the matching steps combine cameras: :func:`held_scores` and its NumPy reference."""

import numpy as np
import pytest

from worldtrack.trackers.ellipsoid.match import held_scores, held_scores_reference


def test_cameras_are_weighed_as_at_the_current_place():
    # Two cameras, three candidates; candidate 0 is where the person is now.
    num = np.array([[6.0, 8.0, 3.0],
                    [1.0, 0.5, 0.0]])
    den = np.array([[10.0, 10.0, 5.0],
                    [10.0, 2.0, 0.0]])           # candidate 2 has left camera 2's view
    e = held_scores(num, den, 0)
    assert e[0] == pytest.approx(7.0 / 20.0)      # at the current place: Σ num / Σ den
    assert e[1] == pytest.approx((10 * 0.8 + 10 * 0.25) / 20.0)
    assert e[2] == pytest.approx((10 * 0.6 + 10 * 0.1) / 20.0)  # camera 2 counts as it was
    # Σ num / Σ den would rank candidate 2 (3/5 = 0.6) above staying (0.35): it gains by
    # leaving the camera that fits badly. Held weights rank it level with staying's camera-2 ratio.
    assert (num[:, 2].sum() / den[:, 2].sum()) > e[0] and e[2] == pytest.approx(e[0])


def test_one_camera_gives_num_over_den_and_unseen_candidates_no_score():
    num = np.array([[3.0, 2.0, 0.0]])
    den = np.array([[4.0, 8.0, 0.0]])
    np.testing.assert_allclose(held_scores(num, den, 0), [0.75, 0.25, -np.inf])
    # A camera that shows nothing at the current place does not count; nobody seeing it: −inf.
    num2 = np.array([[3.0, 2.0], [0.0, 5.0]])
    den2 = np.array([[4.0, 8.0], [0.0, 5.0]])
    np.testing.assert_allclose(held_scores(num2, den2, 0), [0.75, 0.25])
    assert np.all(held_scores(np.zeros((2, 3)), np.zeros((2, 3)), 1) == -np.inf)


def test_compiled_held_scores_equal_the_reference():
    rng = np.random.default_rng(0)
    for _ in range(300):
        c, j = rng.integers(1, 4), rng.integers(1, 12)
        den = rng.uniform(0, 50, (c, j)) * (rng.random((c, j)) > 0.3)
        num = rng.uniform(-0.3, 1.0, (c, j)) * den
        ref = int(rng.integers(0, j))
        np.testing.assert_allclose(held_scores(num, den, ref), held_scores_reference(num, den, ref), rtol=1e-12)
