"""The depth share λ of eq. 18 from each term's sandwich weight, with correlated differences, each
term measured at its own best fit (worldtrack's addition to seed 003; ``depth_weight="sandwich"``).

:class:`~worldtrack.pose.noise_weight.KernelWeightedLam` weighs each term by ``E[ρ″]/E[ρ′²]``, the
weight that minimises an M-estimator's sandwich variance ``H⁻¹VH⁻¹`` when the differences are
independent. Two things break that on real images (issue 36i):

1. **Correlated differences.** The colour differences of a face under changing light, or of a cube
   whose shading the template does not model, are one smooth field: a point's score correlates
   +0.96 with its neighbour's. The variance of the pose's score ``S = Σ ψ_i g_i`` (``ψ = ρ′(x)``,
   ``g_i = ∂x_i/∂pose``) is then ``Σ_ij Cov(ψ_i g_i, ψ_j g_j)``, not ``Σ_i``. The **design effect**
   ``D = 1 + Σ_{i≠j near} s_iᵀH⁻¹s_j / Σ_i s_iᵀH⁻¹s_i`` (``s_i = ψ_i g_i``, ``H = Σ g_i g_iᵀ``) is how
   many times larger it is, measured along the pose's own directions; a term's weight becomes
   ``E[ρ″]/(D·E[ρ′²])`` — its points count as ``N/D`` independent ones. "Near" is read off the
   differences' own correlogram: pairs are binned by image distance in steps of the template's
   median nearest-neighbour spacing and summed out to the first bin whose summed product is not
   positive (the "initial positive sequence" rule of time-series variance estimation) — no block
   size is chosen.
2. **Feedback through the pose.** Measured at the tracker's estimate, a pose that drifts inflates
   the depth differences, which lowers λ, which lets the pose drift further (faces 2 and 4 at 10 mm
   depth noise were lost so). Here each term is measured at **its own best fit**: a few robust
   Gauss–Newton steps of that term alone, from the accepted pose, over the six rigid motions of the
   whole model (central differences of ``FD_STEP_M`` / ``FD_STEP_RAD``). Its differences there are
   its noise, not the other term's pull; the six fitted parameters are few against 128–1024 points.

The median over the last ``window`` accepted frames is used, λ = w_D/(w_C + w_D).

Measured (opt-in, not the default; synthetic RGB-D faces, 20 frames, mean rotation error against
λ = 0.9): with quantised depth better on 4 faces of 4 (λ → 0.99); with 3 mm noise better on 7 of 9
(faces 1 and 6 worse: 0.91 vs 0.72°, 0.77 vs 0.55°); with 10 mm noise better on 6 of 9, mostly by
half (e.g. 1.52 vs 2.92°, λ ≈ 0.3–0.7), worse on faces 1 and 7, and face 2 is lost (15.5°; λ = 0.9:
3.9°) — not through λ (it stays ≈ 0.7) but through the colour template, drawn at the tracker's own
drifting pose, whose differences stay small there. The kernel weight lost faces 2 and 4 at 10 mm.
Real cube (``benchmarks/pose_cube.py``, 5 seeds): level with the kernel weight in mm, a little better
in degrees (0.95 / 2.26° against the data's truth, 0.63 / 1.34° against the rolling-shutter board);
~30 ms more per frame there (the own fits).

>>> import numpy as np
>>> rng = np.random.default_rng(0)
>>> uv = rng.uniform(0, 100, (400, 2)); g = rng.normal(size=(6, 400))
>>> x13 = np.r_[rng.normal(0, 0.3, (1, 400)), 0.5 * g, -0.5 * g]     # independent differences
>>> 0.8 < score_design_effect(x13, uv) < 1.3
True
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy.spatial.distance import pdist, squareform

from worldtrack.pose.cost import ColourDepthCost, camera_points, project_sample
from worldtrack.pose.noise_weight import MIN_POINTS, MeasuredLam, kernel_share, kernel_weight

FD_STEP_M = 1e-3        # central-difference step of the rigid translations (m)
FD_STEP_RAD = 2e-3      # ... and rotations (rad); both well inside one LM step of the tracker
OWN_FIT_STEPS = 3       # robust Gauss–Newton steps of a term alone (each must lower its cost)


def moved(T: np.ndarray, centre: np.ndarray, step: np.ndarray) -> np.ndarray:
    """Part transforms ``T`` (K, P, 3, 4) moved rigidly by ``step`` (6,): translation in units of
    ``FD_STEP_M`` along the camera axes, rotation in units of ``FD_STEP_RAD`` about ``centre`` (3,)."""
    step = np.asarray(step, float)
    Rd = cv2.Rodrigues(step[3:] * FD_STEP_RAD)[0]
    out = np.array(T, float)
    out[..., :3, :3] = Rd @ T[..., :3, :3]
    out[..., :3, 3] = (Rd @ (T[..., :3, 3] - centre)[..., None])[..., 0] + centre + step[:3] * FD_STEP_M
    return out


def with_neighbours(T: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """(13, P, 3, 4): ``T`` (1, P, 3, 4), then one step + along each of the six rigid motions, then −."""
    unit = np.eye(6)
    return np.concatenate([T] + [moved(T, centre, s * e) for s in (1.0, -1.0) for e in unit])


def term_values(cost: ColourDepthCost, T: np.ndarray, term: str) -> np.ndarray:
    """(K, N) differences of the ``"colour"`` (eq. 16, units of c) or ``"depth"`` term (eq. 17, units
    of c′) under K candidate transforms ``T`` (K, P, 3, 4); NaN where a point is not read."""
    if term == "colour":
        vals, _ = project_sample(cost.images, cost.intr, T, cost.colour)
        return cost.colour_differences(vals[:, 0].astype(float)) / cost.c
    zhat, z = project_sample(cost.depth_image, cost.intr, T, cost.depth, cost.depth_sampling)
    return (zhat[:, 0] - z) / cost.c_depth


def _gm(x: np.ndarray) -> float:
    return float(np.nansum(x * x / (1.0 + x * x)))


def own_fit(cost: ColourDepthCost, T: np.ndarray, term: str, centre: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One term alone fitted from ``T`` (1, P, 3, 4): up to ``OWN_FIT_STEPS`` Gauss–Newton steps on
    its Geman–McClure residuals ``x/√(1+x²)`` (eqs. 5–7), each kept only if it lowers the term's cost.
    Returns its differences at the fit and at the twelve neighbours (13, N), and the fitted ``T``."""
    x13 = term_values(cost, with_neighbours(T, centre), term)
    for _ in range(OWN_FIT_STEPS):
        ok = np.all(np.isfinite(x13), 0)
        x, g = x13[0, ok], (x13[1:7, ok] - x13[7:13, ok]) / 2.0
        J = g * (1.0 + x * x) ** -1.5
        A = J @ J.T
        if len(x) < MIN_POINTS or not np.isfinite(A).all():
            break
        step = -np.linalg.solve(A + 1e-6 * np.trace(A) / 6 * np.eye(6), J @ (x / np.sqrt(1.0 + x * x)))
        T2 = moved(T, centre, step)
        x2 = term_values(cost, with_neighbours(T2, centre), term)
        if _gm(x2[0]) >= _gm(x13[0]):
            break
        T, x13 = T2, x2
    return x13, T


def score_design_effect(x13: np.ndarray, uv: np.ndarray) -> float:
    """How many times the variance of a term's pose score exceeds that of independent differences.

    ``x13`` (13, N): the differences at a pose and at its twelve neighbours (:func:`with_neighbours`);
    ``uv`` (N, 2): the points' image positions (px). With ``s_i = ρ′(x_i)·g_i`` and ``H = Σ g_i g_iᵀ``,
    ``D = 1 + Σ_{i≠j near} s_iᵀH⁻¹s_j / Σ_i s_iᵀH⁻¹s_i``, "near" out to the first distance bin (of the
    median nearest-neighbour spacing) whose summed product is not positive. At least 1.
    """
    ok = np.all(np.isfinite(x13), 0)
    x13, uv = x13[:, ok], np.asarray(uv, float)[ok]
    if len(uv) < MIN_POINTS:
        return 1.0
    x, g = x13[0], (x13[1:7] - x13[7:13]) / 2.0
    s = 2.0 * x / (1.0 + x * x) ** 2 * g                                # ρ′(x_i)·g_i, (6, N)
    Q = s.T @ np.linalg.pinv(g @ g.T) @ s                               # s_iᵀ H⁻¹ s_j
    own = float(np.trace(Q))
    dist = squareform(pdist(uv))
    spacing = float(np.median(np.sort(dist, axis=1)[:, 1]))
    if own <= 0 or spacing <= 0:
        return 1.0
    bins = np.floor(dist / spacing).astype(np.int64)
    np.fill_diagonal(bins, -1)
    pair = bins >= 0
    summed = np.bincount(bins[pair], Q[pair])
    counted = np.bincount(bins[pair], minlength=len(summed))
    stop = np.nonzero((summed <= 0) & (counted > 0))[0]
    return max(1.0 + float(summed[: stop[0] if len(stop) else len(summed)].sum()) / own, 1.0)


def image_positions(cost: ColourDepthCost, T: np.ndarray, term: str) -> np.ndarray:
    """(N, 2) image positions (px, principal point at 0) of a term's template points under ``T`` (1, P, 3, 4)."""
    P = camera_points(T, cost.colour if term == "colour" else cost.depth)[0]
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.c_[cost.intr.fx * P[:, 0] / P[:, 2], cost.intr.fy * P[:, 1] / P[:, 2]]


def sandwich_weight(cost: ColourDepthCost, T: np.ndarray, term: str, centre: np.ndarray) -> float:
    """One term's weight: :func:`kernel_weight` of its differences at its own fit, over its
    :func:`score_design_effect` there. NaN if fewer than ``MIN_POINTS`` points are read."""
    x13, T_fit = own_fit(cost, T, term, centre)
    x = x13[0][np.isfinite(x13[0])]
    if len(x) < MIN_POINTS:
        return np.nan
    return kernel_weight(x) / score_design_effect(x13, image_positions(cost, T_fit, term))


class SandwichWeightedLam(MeasuredLam):
    """λ from each term's :func:`sandwich_weight` (module docstring); ``depth_weight="sandwich"``."""

    def __init__(self, lam0: float, window: int = 10):
        super().__init__(lam0, window, None, kernel_share)

    def observe(self, cost: ColourDepthCost, T: np.ndarray) -> None:
        """Measure both terms of ``cost`` from an accepted pose (``T``: (1, P, 3, 4) part transforms)."""
        if cost.depth is None:
            return
        T = np.asarray(T, float)
        centre = camera_points(T, cost.colour)[0].mean(0)
        self.add(sandwich_weight(cost, T, "colour", centre), sandwich_weight(cost, T, "depth", centre))
