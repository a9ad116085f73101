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

Measured (opt-in, not the default): on synthetic RGB-D faces with 1 mm depth steps λ rises to
0.99 and the rotation error falls (faces 0/1/5/8: 0.18–0.19° vs 0.24–0.26° at λ = 0.9); with 3 mm
noise λ ≈ 0.6–0.8, better on three faces of four; with 10 mm noise λ → 0.0–0.05 and it is worse
(one face lost): the depth differences then sit in Geman–McClure's flat part (σ > c′), where the
kernel already discounts them, and the quadratic-regime weight discounts them again. Real cube
(``benchmarks/pose_cube.py``): λ → 0.003–0.006, closer to the image-only and rolling-shutter checks,
further from the data's board truth in median millimetres. Body (held-out seed 3): level.

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


def term_spreads(cost: ColourDepthCost, T: np.ndarray) -> tuple[float, float]:
    """Robust spreads ``(s_C, s_D)`` of the colour and depth differences of ``cost`` at one pose.

    ``T``: (1, P, 3, 4) part transforms of the pose. Each spread is ``1.4826·median|d| / c`` over
    the points read (``c′`` for depth); NaN when a term has fewer than ``MIN_POINTS`` read points.
    """
    vals, _ = project_sample(cost.images, cost.intr, T, cost.colour)
    d = cost.colour_differences(vals[:, 0].astype(float))[0]
    d = d[np.isfinite(d)]
    s_c = MAD_TO_SIGMA * float(np.median(np.abs(d))) / cost.c if len(d) >= MIN_POINTS else np.nan
    if cost.depth is None:
        return s_c, np.nan
    zhat, z = project_sample(cost.depth_image, cost.intr, T, cost.depth, cost.depth_sampling)
    dd = (zhat[0, 0] - z).astype(float)
    dd = dd[np.isfinite(dd)]
    s_d = MAD_TO_SIGMA * float(np.median(np.abs(dd))) / cost.c_depth if len(dd) >= MIN_POINTS else np.nan
    return s_c, s_d


class NoiseWeightedLam:
    """λ from the spreads measured on the last ``window`` accepted frames (module docstring)."""

    def __init__(self, lam0: float, window: int = 10):
        self.lam0 = float(lam0)
        self.spreads: deque = deque(maxlen=int(window))

    def observe(self, cost: ColourDepthCost, T: np.ndarray) -> None:
        """Record the spreads of ``cost`` at an accepted pose (``T``: (1, P, 3, 4) part transforms)."""
        self.add(*term_spreads(cost, T))

    def add(self, s_colour: float, s_depth: float) -> None:
        """Record one accepted frame's spreads (ignored unless both terms were measured)."""
        if np.isfinite(s_colour) and np.isfinite(s_depth) and s_colour + s_depth > 0:
            self.spreads.append((float(s_colour), float(s_depth)))

    @property
    def lam(self) -> float:
        if not self.spreads:
            return self.lam0
        s = np.median(np.asarray(self.spreads), axis=0)
        return inverse_variance_lam(s[0], s[1])


class FixedLam:
    """λ = the configured share, whatever is observed (the paper's fixed weight)."""

    def __init__(self, lam: float):
        self.lam = float(lam)

    def observe(self, cost: ColourDepthCost, T: np.ndarray) -> None:
        """Nothing to learn: a fixed λ."""


def depth_share(mode: str, lam: float, window: int) -> FixedLam | NoiseWeightedLam:
    """The trackers' λ source for ``depth_weight`` ``mode``: "fixed" (``lam``) or "noise" (measured).

    >>> depth_share("fixed", 0.9, 10).lam
    0.9
    >>> depth_share("learnt", 0.9, 10)
    Traceback (most recent call last):
    ...
    worldtrack.errors.InputError: depth_weight: expected fixed or noise, got 'learnt'
    """
    if mode == "fixed":
        return FixedLam(lam)
    if mode == "noise":
        return NoiseWeightedLam(lam, window)
    raise InputError(f"depth_weight: expected fixed or noise, got {mode!r}")
