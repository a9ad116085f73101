"""The depth share λ of eq. 18 from the two terms' measured noise (worldtrack's addition to seed 003).

The paper mixes the colour and depth terms with a fixed λ = 0.9. Here λ follows how noisy each
term actually is. At an accepted pose, each term's differences — colour ``d_i`` (eq. 16) in units
of its Geman–McClure scale ``c``, depth ``d′_i = Ẑ_i − Z_i`` (eq. 17) in units of ``c′`` — have a
robust spread ``s = 1.4826·median|d| / c`` (the MAD about zero: at the right pose a difference is
noise). Near zero ``ρ_c(d) ≈ d²/c²``, so the cost weighs a squared difference by ``(1 − λ)/c²``
(colour) and ``λ/c′²`` (depth); the maximum-likelihood weights of independent Gaussian noise are
``1/σ²``, which gives ``λ = s_C² / (s_C² + s_D²)`` — inverse-variance weighting, no tuned constant.
The spread of each term is the median over the last ``window`` accepted frames (robust to one bad
frame); until a frame is accepted the configured λ is used (a first frame's colour template read
from that very image would otherwise look noise-free).

Inverse variance is the ML weight only where the robust kernel is quadratic. ``"kernel"``
(:func:`kernel_weight`) uses each term's Godambe weight instead, ``E[ρ″]/E[ρ′²]`` of its own
differences — the expected curvature of the term at the right pose over its gradient's variance,
the weight that minimises an M-estimator's sandwich variance for independent residuals. It equals
inverse variance for small differences and gives a term whose differences reach Geman–McClure's
flat part several times more (it is discounted there already); no Gaussian assumption, no constant.

Measured (opt-in, not the default), synthetic RGB-D faces (faces 0/1/5/8, one sequence each),
mean rotation error: with 1 mm depth steps inverse variance (λ → 0.99) gives 0.16–0.19° vs
0.24–0.26° at λ = 0.9, the kernel weight (λ → 0.98) 0.16–0.19° as well; with 3 mm noise inverse variance (λ ≈ 0.6–0.8)
is better on three faces of four and worse on face 1 (1.34° vs 0.72°), the kernel weight (λ ≈ 0.62–0.75) is
better on all four (0.45–0.55° vs 0.72–1.25°); with 10 mm noise inverse variance (λ → 0.0–0.05)
is worse on all four and loses face 1, the kernel weight (λ ≈ 0.05–0.21) is better on three
(2.45–3.05° vs 2.92–3.76°) and worse on face 1 (7.0° vs 2.5°: its λ fell to 0.055). On held-out
faces 2/3/4/6/7 it is better at 3 mm on three of five (the other two within 0.07°) but at 10 mm it
is better on one only and loses faces 2 and 4 (λ → 0.04–0.05; face 7: λ → 0, 8.8°): the colour
differences of a face under changing light are not independent noise (one smooth shading error),
so the weight over-trusts colour; and a drifting pose inflates the depth differences it is
measured on, which lowers λ further (``"sandwich"``, :mod:`~worldtrack.pose.sandwich_weight`,
answers both: a design effect for correlated differences, each term measured at its own fit). Real cube
(``benchmarks/pose_cube.py``, 5 seeds): inverse variance λ → 0.003–0.006, worse than λ = 0.9 in
median mm against the data's board truth; the kernel weight λ → 0.015–0.02, better than λ = 0.9
against every truth of the benchmark. Body (held-out seed 3): both level with λ = 0.9.

>>> w = NoiseWeightedLam(0.9)
>>> w.lam                                     # nothing measured yet: the configured λ
0.9
>>> w.add(0.2, 0.4); round(w.lam, 3)          # depth twice as noisy (in units of c′) as colour
0.2
"""

from __future__ import annotations

from collections import deque

import numpy as np

from worldtrack.errors import InputError
from worldtrack.pose.cost import ColourDepthCost, project_sample

MAD_TO_SIGMA = 1.4826      # σ of a Gaussian = 1.4826 × its median absolute deviation
MIN_POINTS = 10            # a term with fewer read points is not measured on that frame


def inverse_variance_lam(s_colour: float, s_depth: float) -> float:
    """λ = s_C² / (s_C² + s_D²): the depth share that weighs each term by its inverse variance.

    ``s_colour``, ``s_depth``: the spreads of the colour and depth differences in units of their
    scales ``c`` and ``c′`` (dimensionless).

    >>> inverse_variance_lam(1.0, 1.0), round(inverse_variance_lam(0.1, 0.3), 6)
    (0.5, 0.1)
    """
    vc, vd = float(s_colour) ** 2, float(s_depth) ** 2
    return vc / (vc + vd) if vc + vd > 0 else 0.5


def term_differences(cost: ColourDepthCost, T: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """The colour and depth differences of ``cost`` at one pose, in units of ``c`` and ``c′``.

    ``T``: (1, P, 3, 4) part transforms of the pose. Returns the read points' ``d_i / c`` (eq. 16)
    and ``d′_i / c′`` (eq. 17; None without a depth term), unread points dropped.
    """
    vals, _ = project_sample(cost.images, cost.intr, T, cost.colour)
    d = cost.colour_differences(vals[:, 0].astype(float))[0]
    x_c = d[np.isfinite(d)] / cost.c
    if cost.depth is None:
        return x_c, None
    zhat, z = project_sample(cost.depth_image, cost.intr, T, cost.depth, cost.depth_sampling)
    dd = (zhat[0, 0] - z).astype(float)
    return x_c, dd[np.isfinite(dd)] / cost.c_depth


def term_spreads(cost: ColourDepthCost, T: np.ndarray) -> tuple[float, float]:
    """Robust spreads ``(s_C, s_D)`` of the colour and depth differences of ``cost`` at one pose.

    ``T``: (1, P, 3, 4) part transforms of the pose. Each spread is ``1.4826·median|d| / c`` over
    the points read (``c′`` for depth); NaN when a term has fewer than ``MIN_POINTS`` read points.
    """
    return tuple(robust_spread(x) if x is not None and len(x) >= MIN_POINTS else np.nan
                 for x in term_differences(cost, T))


def robust_spread(x: np.ndarray) -> float:
    """``1.4826·median|x|``: the spread of differences about zero (a Gaussian's σ)."""
    return MAD_TO_SIGMA * float(np.median(np.abs(x)))


def kernel_weight(x: np.ndarray) -> float:
    """``E[ρ″(x)] / E[ρ′(x)²]`` of Geman–McClure ``ρ(x) = x²/(1 + x²)`` over differences ``x`` (units of c).

    The Godambe (sandwich) weight of one M-estimator term: the cost's expected curvature at the
    right pose over the variance of its gradient. In ``c``'s units the scale cancels, so terms
    measured in grey levels and in metres compare directly. For small Gaussian noise of spread
    ``s`` it is ``1/(2s²)`` (inverse variance); for ``s ≫ 1`` it is ~``4/s²``, not ``1/(2s²)``:
    the kernel's flat part already discounts the large differences, and the weight says so.
    0 when the expected curvature is not positive (a term that does not pin the pose).

    >>> round(kernel_weight(np.array([-0.1, 0.1])), 1)   # two points at ±0.1: ≈ 1/(2·0.1²)
    49.0
    """
    x2 = np.asarray(x, float) ** 2
    q = 1.0 + x2
    curvature = float(np.mean(2.0 * (1.0 - 3.0 * x2) / q ** 3))
    variance = float(np.mean(4.0 * x2 / q ** 4))
    return max(curvature, 0.0) / variance if variance > 0 else np.inf


def kernel_share(w_colour: float, w_depth: float) -> float:
    """λ = w_D / (w_C + w_D) from the two terms' :func:`kernel_weight` (0.5 if both are 0)."""
    return w_depth / (w_colour + w_depth) if w_colour + w_depth > 0 else 0.5


class MeasuredLam:
    """λ from one number per term measured at each accepted pose (``per_term`` of its differences
    in units of its scale), the median over the last ``window`` frames turned into λ by ``share``;
    the configured ``lam0`` until a frame is accepted."""

    def __init__(self, lam0: float, window: int, per_term, share):
        self.lam0, self.per_term, self.share = float(lam0), per_term, share
        self.measured: deque = deque(maxlen=int(window))

    def observe(self, cost: ColourDepthCost, T: np.ndarray) -> None:
        """Measure both terms of ``cost`` at an accepted pose (``T``: (1, P, 3, 4) part transforms)."""
        x_c, x_d = term_differences(cost, T)
        if x_d is not None and min(len(x_c), len(x_d)) >= MIN_POINTS:
            self.add(self.per_term(x_c), self.per_term(x_d))

    def add(self, colour: float, depth: float) -> None:
        """Record one accepted frame's two numbers (ignored unless both are finite and one is positive)."""
        if np.isfinite(colour) and np.isfinite(depth) and colour + depth > 0:
            self.measured.append((float(colour), float(depth)))

    @property
    def lam(self) -> float:
        if not self.measured:
            return self.lam0
        return float(self.share(*np.median(np.asarray(self.measured), axis=0)))


class NoiseWeightedLam(MeasuredLam):
    """λ by inverse variance of the terms' robust spreads (:func:`term_spreads`, module docstring)."""

    def __init__(self, lam0: float, window: int = 10):
        super().__init__(lam0, window, robust_spread, inverse_variance_lam)


class KernelWeightedLam(MeasuredLam):
    """λ from each term's Godambe weight (:func:`kernel_weight`, :func:`kernel_share`)."""

    def __init__(self, lam0: float, window: int = 10):
        super().__init__(lam0, window, kernel_weight, kernel_share)


class FixedLam:
    """λ = the configured share, whatever is observed (the paper's fixed weight)."""

    def __init__(self, lam: float):
        self.lam = float(lam)

    def observe(self, cost: ColourDepthCost, T: np.ndarray) -> None:
        """Nothing to learn: a fixed λ."""


def depth_share(mode: str, lam: float, window: int) -> FixedLam | MeasuredLam:
    """The trackers' λ source for ``depth_weight`` ``mode``: "fixed" (``lam``), "noise" (inverse
    variance), "kernel" (:func:`kernel_weight`) or "sandwich" (the kernel weight over the score's
    design effect, each term at its own fit: :mod:`worldtrack.pose.sandwich_weight`).

    >>> depth_share("fixed", 0.9, 10).lam
    0.9
    >>> depth_share("learnt", 0.9, 10)
    Traceback (most recent call last):
    ...
    worldtrack.errors.InputError: depth_weight: expected fixed, noise, kernel or sandwich, got 'learnt'
    """
    if mode == "fixed":
        return FixedLam(lam)
    if mode == "noise":
        return NoiseWeightedLam(lam, window)
    if mode == "kernel":
        return KernelWeightedLam(lam, window)
    if mode == "sandwich":
        from worldtrack.pose.sandwich_weight import SandwichWeightedLam   # it builds on this module
        return SandwichWeightedLam(lam, window)
    raise InputError(f"depth_weight: expected fixed, noise, kernel or sandwich, got {mode!r}")
