"""The depth share λ from each term's sandwich weight with correlated differences (sandwich_weight)."""

import numpy as np
import pytest

from worldtrack.pose.noise_weight import robust_spread
from worldtrack.pose.sandwich_weight import (SandwichWeightedLam, moved, own_fit, score_design_effect,
                                             term_values, with_neighbours)
from worldtrack.pose.tracker import RigidTracker, TrackerConfig
from worldtrack.synth.faces import face_model


def linear_differences(x0: np.ndarray, g: np.ndarray) -> np.ndarray:
    """(13, N) differences at a pose and its twelve neighbours for a term linear in the pose."""
    return np.r_[x0[None], x0 + g, x0 - g]


def test_design_effect_is_one_for_independent_and_the_cluster_size_for_repeated_differences():
    """Independent differences: D ≈ 1. Every difference and its slope repeated at m = 4 points a
    tenth of a pixel apart (the same information counted four times): D ≈ 4 — from the differences'
    own correlogram, with no block size given. Neighbours with alike slopes but independent
    differences are independent information: D ≈ 1."""
    rng = np.random.default_rng(5)
    n = 600
    uv = rng.uniform(0, 200, (n, 2))
    x0, g = rng.normal(0, 0.5, n), rng.normal(size=(6, n))
    assert 0.8 < score_design_effect(linear_differences(x0, g), uv) < 1.3
    m = 4
    centres = rng.uniform(0, 200, (n // m, 2))
    uv4 = np.repeat(centres, m, axis=0) + rng.uniform(-0.05, 0.05, (n, 2))
    x4, g4 = np.repeat(x0[: n // m], m), np.repeat(g[:, : n // m], m, axis=1)
    assert score_design_effect(linear_differences(x4, g4), uv4) == pytest.approx(m, rel=0.25)
    assert score_design_effect(linear_differences(x0, g4), uv4) < 1.3      # neighbours' slopes alike, their noise not
    x4[::2] = np.nan                                                   # unread points are left out
    assert score_design_effect(linear_differences(x4, g4), uv4) == pytest.approx(m / 2, rel=0.25)




def test_own_fit_measures_a_term_at_its_own_best_pose(rgbd_face, noisy):
    """From a pose 2 mm and 0.7° off, the depth term alone fitted returns to differences as small
    as at the true pose (the sensor's 4 mm noise), where read at the wrong pose they are much
    larger: a drifting estimate does not inflate the noise the weight is measured on."""
    face, seq, frames = rgbd_face
    f = frames[3]
    tr = RigidTracker(face_model(face), seq.intr, f.R, f.t, TrackerConfig(), cost="colour-depth")
    cost = tr.make_cost(f.image.mean(2).astype(np.float32), noisy(f.depth, 0.004, 2), tr.state)
    T = tr.space.transforms(tr.state[None])
    centre = T[0, 0, :3, 3]
    off = moved(T, centre, np.array([2.0, -1.0, 1.0, 4.0, -4.0, 3.0]))     # steps of 1 mm / 2 mrad
    spread = lambda X: robust_spread(term_values(cost, X, "depth")[0][np.isfinite(term_values(cost, X, "depth")[0])])
    s_true, s_off = spread(T), spread(off)
    x13, T_fit = own_fit(cost, off, "depth", centre)
    s_fit = robust_spread(x13[0][np.isfinite(x13[0])])
    assert s_off > 1.4 * s_true
    assert s_fit < 1.15 * s_true
    assert with_neighbours(T, centre).shape == (13,) + T.shape[1:]


def test_sandwich_weighted_tracking_keeps_the_depth_share_with_noisy_depth(track_rgbd_face):
    """With 10 mm depth noise the kernel weight's λ collapses towards colour (correlated colour
    differences counted as independent, and measured at a drifting pose); the sandwich weight keeps
    λ above it and tracks better. With quantised depth it gives the depth most of the weight."""
    runs = {(mode, sigma): track_rgbd_face(mode, sigma) for mode in ("fixed", "kernel", "sandwich") for sigma in (0.0, 0.010)}
    errors = {k: v[0] for k, v in runs.items()}
    lam = {k: v[1].lam for k, v in runs.items()}
    assert isinstance(runs["sandwich", 0.0][1], SandwichWeightedLam)
    assert lam["sandwich", 0.0] > 0.85
    assert lam["sandwich", 0.010] > 1.5 * lam["kernel", 0.010]
    assert errors["sandwich", 0.0] < 0.5
    assert errors["sandwich", 0.010] < errors["kernel", 0.010]
