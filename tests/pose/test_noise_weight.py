"""The depth share λ from the measured noise of the colour and depth terms (noise_weight)."""

import numpy as np
import pytest

from worldtrack.errors import InputError
from scipy import integrate

from worldtrack.pose.noise_weight import (KernelWeightedLam, NoiseWeightedLam, inverse_variance_lam, kernel_weight,
                                          term_spreads)
from worldtrack.pose.tracker import RigidTracker, TrackerConfig
from worldtrack.synth.faces import face_model




def test_inverse_variance_lam_and_its_running_median():
    assert inverse_variance_lam(0.3, 0.1) == pytest.approx(0.9)           # depth 3× less noisy: λ = 9/10
    assert inverse_variance_lam(0.1, 0.3) == pytest.approx(0.1)
    w = NoiseWeightedLam(0.7, window=3)
    assert w.lam == 0.7                                                   # nothing measured yet
    w.add(0.1, np.nan)                                                    # a frame without depth: ignored
    assert w.lam == 0.7
    for s in [(0.1, 0.1), (0.1, 0.3), (0.1, 0.3), (0.1, 0.3)]:           # the first falls out of the window
        w.add(*s)
    assert w.lam == pytest.approx(0.1)


def gaussian_kernel_weight(s: float) -> float:
    """E[ρ″]/E[ρ′²] of Geman–McClure (c = 1) under N(0, s²), by quadrature: the value to estimate."""
    pdf = lambda x: np.exp(-0.5 * (x / s) ** 2) / (s * np.sqrt(2 * np.pi))
    curv = integrate.quad(lambda x: 2 * (1 - 3 * x * x) / (1 + x * x) ** 3 * pdf(x), -12 * s, 12 * s, limit=200)[0]
    var = integrate.quad(lambda x: 4 * x * x / (1 + x * x) ** 4 * pdf(x), -12 * s, 12 * s, limit=200)[0]
    return curv / var


def test_kernel_weight_is_the_godambe_weight_of_geman_mcclure():
    """From samples it estimates the expected curvature over the gradient's variance; inverse
    variance 1/(2s²) where the kernel is quadratic, several times more where it is flat (σ > c)."""
    rng = np.random.default_rng(3)
    for s in (0.05, 0.5, 2.0):
        assert kernel_weight(rng.normal(0, s, 200_000)) == pytest.approx(gaussian_kernel_weight(s), rel=0.03)
    assert gaussian_kernel_weight(0.05) == pytest.approx(1 / (2 * 0.05 ** 2), rel=0.02)
    assert gaussian_kernel_weight(2.0) > 3.0 / (2 * 2.0 ** 2)
    assert kernel_weight(np.array([30.0, -50.0, 40.0])) == 0.0             # all outliers: no curvature, no weight
    w = KernelWeightedLam(0.9, window=2)
    assert w.lam == 0.9
    w.add(np.inf, 1.0)                                                     # an unmeasurable frame: ignored
    assert w.lam == 0.9
    w.add(3.0, 1.0), w.add(1.0, 1.0), w.add(1.0, 3.0)                      # the window keeps the last two
    assert w.lam == pytest.approx(2.0 / 3.0)


def test_measured_depth_spread_follows_the_noise_set(rgbd_face, noisy):
    """At the true pose, the depth spread in units of c′ is the depth noise σ / c′ (read at the
    nearest pixel: bilinear reading would average the pixels' independent noise)."""
    face, seq, frames = rgbd_face
    f = frames[0]
    tr = RigidTracker(face_model(face), seq.intr, f.R, f.t, TrackerConfig(depth_sampling="nearest"), cost="colour-depth")
    T = tr.space.transforms(tr.state[None])
    grey = f.image.mean(2).astype(np.float32)
    s0 = term_spreads(tr.make_cost(grey, f.depth, tr.state), T)[1]        # the 1 mm steps and the model's own
    assert s0 < 0.15
    lams = []
    for sigma_mm in (2.0, 5.0, 12.0):
        s_c, s_d = term_spreads(tr.make_cost(grey, noisy(f.depth, sigma_mm / 1000, 1), tr.state), T)
        assert s_d == pytest.approx(np.hypot(s0, sigma_mm / 5.0), rel=0.2)     # c′ = 5 mm; 128 points
        lams.append(inverse_variance_lam(s_c, s_d))
    assert lams[0] > lams[1] > lams[2]                                    # noisier depth, less weight


def test_noise_weighted_tracking_is_no_worse_at_the_fixed_weights_noise(track_rgbd_face):
    """Depth as in the paper's simulation (quantised, no added noise — what λ = 0.9 was chosen for):
    λ from the noise, and from the kernel weight, rises above 0.85 and tracks at least as well. With
    10 mm noise the inverse-variance λ gives the depth little weight and the kernel weight more
    (Geman–McClure's flat part already discounts large differences), and it tracks better than the
    inverse-variance λ there."""
    runs = {(mode, sigma): track_rgbd_face(mode, sigma) for mode in ("fixed", "noise", "kernel") for sigma in (0.0, 0.010)}
    errors = {k: v[0] for k, v in runs.items()}
    lam = {k: v[1].lam for k, v in runs.items()}
    assert lam["noise", 0.0] > 0.85 and lam["noise", 0.010] < 0.3
    assert lam["kernel", 0.0] > 0.85 and 2 * lam["noise", 0.010] < lam["kernel", 0.010] < 0.5
    for mode in ("noise", "kernel"):
        assert errors[mode, 0.0] <= errors["fixed", 0.0] + 0.05
        assert errors[mode, 0.0] < 0.5
    assert errors["kernel", 0.010] < errors["noise", 0.010]


def test_unknown_depth_weight_is_an_input_error(rgbd_face):
    face, seq, frames = rgbd_face
    with pytest.raises(InputError, match="depth_weight"):
        RigidTracker(face_model(face), seq.intr, frames[0].R, frames[0].t, TrackerConfig(depth_weight="auto"),
                     cost="colour-depth")
