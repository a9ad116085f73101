"""Kalman filter with real time steps, eqs. 2-3, the decision, templates and the joint assignment."""

import numpy as np
import pytest

from worldtrack.follow import kalman
from worldtrack.follow.dissimilarity import (decide, dissimilarity, illumination_weight, position_error,
                                             wb_change)
from worldtrack.follow.others import assign
from worldtrack.follow.templates import Templates


def test_kalman_follows_a_walker_with_uneven_time_steps():
    rng = np.random.default_rng(0)
    times = np.cumsum(rng.uniform(0.05, 0.2, 80))                   # frames at uneven times
    truth = np.column_stack([1.0 + 1.2 * times, 2.0 - 0.5 * times])  # 1.2 and -0.5 m/s
    x, P = kalman.initial_state(truth[:1] + rng.normal(0, 0.02, (1, 2)), 0.02)
    t_prev = times[0]
    for t, z in zip(times[1:], truth[1:]):
        x, P = kalman.predict(x, P, t - t_prev, accel_sigma=0.5)
        x, P = kalman.update(x, P, (z + rng.normal(0, 0.02, 2))[None], 0.02)
        t_prev = t
    np.testing.assert_allclose(x[0, 2:], [1.2, -0.5], atol=0.1)
    np.testing.assert_allclose(x[0, :2], truth[-1], atol=0.04)
    assert np.allclose(P[0], P[0].T) and np.all(np.linalg.eigvalsh(P[0]) > 0)


def test_prediction_uses_the_real_time_step():
    x, P = kalman.initial_state(np.array([[0.0, 0.0]]), 0.1)
    x[0, 2:] = (1.0, 2.0)
    one, _ = kalman.predict(x, P, 0.5, 1.0)
    two, _ = kalman.predict(*kalman.predict(x, P, 0.25, 1.0), 0.25, 1.0)
    np.testing.assert_allclose(one[0, :2], [0.5, 1.0])
    np.testing.assert_allclose(two[0, :2], one[0, :2])


def test_equation_2_3_and_the_illumination_weight():
    E = position_error(np.array([[1.0, 0.0], [0.0, 2.0]]), np.array([[0.0, 0.0]]), k=1.0)
    np.testing.assert_allclose(E[:, 0], [1.0, 2.0])
    assert wb_change((600, 400), (512, 512)) == 200
    alpha = illumination_weight(np.array([0.0, 70.0, 224.0, 1000.0]), p=0.25, wb_unit=70.0)
    np.testing.assert_allclose(alpha, [0.0, 0.25, 0.8, 1.0])
    assert illumination_weight(10.0, 0.25, 70.0, floor=0.5) == 0.5
    assert illumination_weight(500.0, 0.25, 70.0, weighting="colour") == 0.0
    rb, e = np.array([0.3, 0.3]), np.array([0.1, 0.1])
    d = dissimilarity(rb, e, np.array([0.5, 0.8]), alpha_th=0.8)
    np.testing.assert_allclose(d, [0.2, 0.1])                      # at α_th colour is ignored: D = E


def test_the_decision_takes_the_smallest_d_under_the_threshold():
    assert decide(np.array([0.4, 0.2, 0.3]), 0.5) == 1
    assert decide(np.array([0.6, 0.7]), 0.5) == -1
    assert decide(np.array([0.4, 0.2]), 0.5, allowed=np.array([True, False])) == 0
    assert decide(np.zeros(0), 0.5) == -1


def test_joint_assignment_lets_each_person_keep_their_own_candidate():
    # The target's D alone would take candidate 1 (0.15 < 0.2), but candidate 1 is clearly the
    # other person's (0.05) and candidate 0 is good enough for the target.
    cost = np.array([[0.2, 0.15], [0.9, 0.05]])
    np.testing.assert_array_equal(assign(cost, 0.5), [0, 1])
    np.testing.assert_array_equal(assign(np.array([[0.7, np.inf]]), 0.5), [-1])
    # Leaving someone unassigned costs the threshold: better than a forced poor pair for both.
    np.testing.assert_array_equal(assign(np.array([[0.1, 0.45], [0.45, np.inf]]), 0.5), [0, -1])
    np.testing.assert_array_equal(assign(np.zeros((0, 2)), 0.5), [])


def test_templates_learn_slowly_and_the_paper_rule_refreshes_only_when_the_light_changed():
    tpl = Templates(np.array([1.0, 0.0]), (512, 512), short_term_tau=2.0)
    tpl.learn(np.array([0.0, 1.0]), (600, 512), dt=0.1)
    assert tpl.short[1] == pytest.approx(1 - np.exp(-0.05))
    assert tpl.rbhat(np.array([[1.0, 0.0]]))[0] == pytest.approx(0.0, abs=1e-6)   # the long-term still matches
    new = np.array([0.5, 0.5])
    for _ in range(9):
        assert not tpl.paper_update(new, (900, 512), 0.9, 0.1, 0.8, 0.3, 10)
    assert not tpl.paper_update(new, (900, 512), 0.5, 0.1, 0.8, 0.3, 10)   # α < α_th: no refresh
    for _ in range(9):
        tpl.paper_update(new, (900, 512), 0.9, 0.1, 0.8, 0.3, 10)
    assert tpl.paper_update(new, (900, 512), 0.9, 0.1, 0.8, 0.3, 10)
    np.testing.assert_allclose(tpl.long, new)
    assert tpl.registered_wb == (900, 512)
