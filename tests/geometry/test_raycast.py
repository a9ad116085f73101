"""Ray intersections: analytic cases and properties checked against an independent computation."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from worldtrack.geometry.raycast import ray_box, ray_capsule, ray_ellipsoid, ray_plane_z, ray_quad


def _unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _segment_distance(p, a, b):
    ab = b - a
    t = np.clip(((p - a) @ ab) / (ab @ ab), 0.0, 1.0)
    return np.linalg.norm(p - (a + t[:, None] * ab), axis=1)


def test_capsule_side_cap_and_miss():
    a, b, r = np.array([0.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0]), 0.1
    o = np.array([1.0, 0.0, 0.5])
    d = _unit([[-1.0, 0.0, 0.0],      # side: hits at x = 0.1
               [1.0, 0.0, 0.0],       # away: miss
               [-0.95, 0.0, 0.55]])   # towards the top cap
    s = ray_capsule(o, d, a, b, r)
    assert s[0] == pytest.approx(0.9)
    assert np.isinf(s[1])
    assert np.isfinite(s[2])
    hit = o + s[2] * d[2]
    assert hit[2] > 1.0  # on the cap, above the end plane
    assert _segment_distance(hit[None], a, b)[0] == pytest.approx(r, abs=1e-9)


def test_capsule_ray_along_axis_hits_the_near_cap():
    a, b, r = np.array([0.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0]), 0.2
    s = ray_capsule(np.array([0.0, 0.0, 3.0]), _unit([[0.0, 0.0, -1.0]]), a, b, r)
    assert s[0] == pytest.approx(3.0 - 1.0 - 0.2)


def test_capsule_per_ray_origins():
    a, b, r = np.array([0.0, 0.0, 0.0]), np.array([1.0, 0.0, 0.0]), 0.1
    o = np.array([[0.5, 0.0, 1.0], [0.5, 0.0, -1.0]])
    d = _unit([[0.0, 0.0, -1.0], [0.0, 0.0, 1.0]])
    np.testing.assert_allclose(ray_capsule(o, d, a, b, r), [0.9, 0.9])


vec = st.tuples(*[st.floats(-1.0, 1.0, allow_nan=False)] * 3)


@settings(max_examples=150, deadline=None)
@given(vec, vec, vec, vec, st.floats(0.02, 0.4))
def test_capsule_against_sampling(o_off, d_raw, a_raw, b_raw, r):
    a = np.array(a_raw)
    b = np.array(b_raw) + np.array([0.0, 0.0, 0.3])
    o = np.array(o_off) * 3 + np.array([0.0, -4.0, 0.0])
    if np.linalg.norm(d_raw) < 1e-3:
        return
    d = _unit([d_raw])
    if _segment_distance(o[None], a, b)[0] <= r:
        return  # origin inside: not the case the renderer uses
    s = ray_capsule(o, d, a, b, r)[0]
    t = np.linspace(0.0, 12.0, 24001)
    inside = _segment_distance(o + t[:, None] * d[0], a, b) <= r
    if np.isfinite(s):
        hit = o + s * d[0]
        assert _segment_distance(hit[None], a, b)[0] == pytest.approx(r, abs=1e-7)
        # No sample before the hit is inside (up to the sampling step).
        assert not np.any(inside[t < s - 1e-3])
    else:
        assert not np.any(inside)


def test_ellipsoid_rotated_matches_sphere_when_round():
    o = np.array([0.0, -5.0, 1.0])
    d = _unit([[0.0, 1.0, 0.0], [0.05, 1.0, 0.0]])
    R = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    s1 = ray_ellipsoid(o, d, [0, 0, 1], [0.3, 0.3, 0.3], R)
    s2 = ray_ellipsoid(o, d, [0, 0, 1], [0.3, 0.3, 0.3])
    np.testing.assert_allclose(s1, s2)
    assert s1[0] == pytest.approx(4.7)


def test_box_quad_plane_basics():
    o = np.array([0.0, 0.0, 2.0])
    d = _unit([[0.0, 0.0, -1.0], [1.0, 0.0, 0.0]])
    np.testing.assert_allclose(ray_plane_z(o, d, 0.0), [2.0, np.inf])
    s = ray_box(o, d, [0, 0, 0.5], [1, 1, 1])
    assert s[0] == pytest.approx(1.0) and np.isinf(s[1])
    quad = np.array([[-1, -1, 0.5], [1, -1, 0.5], [1, 1, 0.5], [-1, 1, 0.5]], dtype=float)
    s = ray_quad(o, d, quad)
    assert s[0] == pytest.approx(1.5) and np.isinf(s[1])
