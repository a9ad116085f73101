"""The tracking cost: template residuals, Geman–McClure, and the per-sensor terms (seed 003).

* Eq. 3: ``ε = Σ ρ_c(d_i)``, ``ρ_c(x) = x² / (c² + x²)`` (Geman–McClure).
* Eq. 5: as least-squares residuals ``r_i = d_i / sqrt(c² + d_i²)`` so that ``ε = rᵀr``.
* Eq. 4 / §3.1 (face): ``d = (Φ̃Φ̃⁺ − I)·V`` — the part of the sampled input ``V`` that the
  illumination eigen-template ``Φ̃ = [Φ v̄]`` cannot explain (:class:`EigenTemplateCost`).
* Eq. 16 (colour): ``d_i = β·Î_i − α·I_i``, ``α = 1 / Σ I_i``, ``β = α·Σ I_i² / Σ I_i·Î_i``,
  ``c = 0.5 / N``; eq. 17 (depth): ``d′_i = Ẑ_i − Z_i``, ``c′ = 5 mm``; eq. 18–19:
  ``ε = (1 − λ)·ε_C + λ·ε_D`` as residuals ``[√(1−λ)·r_C, √λ·r_D]`` (:class:`ColourDepthCost`).

Every candidate is evaluated in one pass: :func:`project_sample` projects the template points of
all K candidates and reads the image under them (compiled; :func:`project_sample_reference` is the
NumPy version the tests compare it with). A template point that falls outside the image, or on a
pixel without depth, counts as an outlier (``ρ`` = its maximum, 1).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from worldtrack.pose.render import Intrinsics

BILINEAR, NEAREST_POSITIVE, DEPTH_BILINEAR = 0, 1, 2
DEPTH_SAMPLING = {"bilinear": 2, "nearest": 1}     # configuration names of the depth readings
DEPTH_EDGE = 0.03      # m: four depth pixels further apart than this straddle an edge (DEPTH_BILINEAR)


def geman_mcclure(d: np.ndarray, c: float) -> np.ndarray:
    """ρ_c(d) = d² / (c² + d²) (eq. 3)."""
    d = np.asarray(d, float)
    return d * d / (c * c + d * d)


def robust_residual(d: np.ndarray, c: float) -> np.ndarray:
    """r = d / sqrt(c² + d²) (eq. 5), so that r² = ρ_c(d); NaN (no reading) → 1."""
    d = np.asarray(d, float)
    return np.where(np.isnan(d), 1.0, d / np.sqrt(c * c + np.nan_to_num(d) ** 2))


class SparseTemplate(NamedTuple):
    """Template points: ``points`` (N, 3) m in their part's frame, ``part`` (N,) int part index,
    ``value`` (N,) float — grey level (colour/eigen terms) or depth (m) at the previous pose."""

    points: np.ndarray
    part: np.ndarray
    value: np.ndarray


@njit(cache=True, fastmath=True)
def _project_sample_kernel(images, intr4, T, X, part, mode, max_step, vals, zout):  # pragma: no cover
    # One pass over candidates × points: transform, project, read (bilinear, nearest-positive, or
    # bilinear depth: bilinear where the four pixels all hold depth within max_step of each other,
    # else the nearest positive pixel). The part's 3×4 transform is held in locals while
    # consecutive points share a part. fastmath is safe here: NaN only comes in through the image
    # (depth holes are tested as > 0).
    n_ch, h, w = images.shape
    fx, fy, cx, cy = intr4[0], intr4[1], intr4[2], intr4[3]
    for k in range(T.shape[0]):
        p_prev = -1
        r00 = r01 = r02 = t0 = r10 = r11 = r12 = t1 = r20 = r21 = r22 = t2 = 0.0
        for i in range(X.shape[0]):
            p = part[i]
            if p != p_prev:
                r00, r01, r02, t0 = T[k, p, 0, 0], T[k, p, 0, 1], T[k, p, 0, 2], T[k, p, 0, 3]
                r10, r11, r12, t1 = T[k, p, 1, 0], T[k, p, 1, 1], T[k, p, 1, 2], T[k, p, 1, 3]
                r20, r21, r22, t2 = T[k, p, 2, 0], T[k, p, 2, 1], T[k, p, 2, 2], T[k, p, 2, 3]
                p_prev = p
            a0 = X[i, 0]
            a1 = X[i, 1]
            a2 = X[i, 2]
            z = r20 * a0 + r21 * a1 + r22 * a2 + t2
            zout[k, i] = z
            inv = 1.0 / max(z, 1e-6)
            u = fx * (r00 * a0 + r01 * a1 + r02 * a2 + t0) * inv + cx
            v = fy * (r10 * a0 + r11 * a1 + r12 * a2 + t1) * inv + cy
            if mode != 1:
                if z <= 1e-6 or not (u >= 0.0 and v >= 0.0 and u <= w - 1.0 and v <= h - 1.0):
                    for ch in range(n_ch):
                        vals[k, ch, i] = np.nan
                    continue
                u0 = min(int(u), w - 2)
                v0 = min(int(v), h - 2)
                a = u - u0
                b = v - v0
                for ch in range(n_ch):
                    q00, q01 = images[ch, v0, u0], images[ch, v0, u0 + 1]
                    q10, q11 = images[ch, v0 + 1, u0], images[ch, v0 + 1, u0 + 1]
                    if mode == 2:
                        lo = min(min(q00, q01), min(q10, q11))
                        hi = max(max(q00, q01), max(q10, q11))
                        if not (lo > 0.0 and hi - lo <= max_step):             # a hole or an edge:
                            q = images[ch, v0 + int(b >= 0.5), u0 + int(a >= 0.5)]    # the nearest pixel
                            vals[k, ch, i] = q if q > 0.0 else np.nan
                            continue
                    top = q00 + a * (q01 - q00)
                    bot = q10 + a * (q11 - q10)
                    vals[k, ch, i] = top + b * (bot - top)
            else:
                uu = int(np.floor(u + 0.5))
                vv = int(np.floor(v + 0.5))
                for ch in range(n_ch):
                    if z <= 1e-6 or uu < 0 or vv < 0 or uu >= w or vv >= h or not images[ch, vv, uu] > 0:
                        vals[k, ch, i] = np.nan
                    else:
                        vals[k, ch, i] = images[ch, vv, uu]


@njit(cache=True, fastmath={"reassoc", "contract", "nsz", "arcp"})
def _eigen_epsilon_kernel(V, Q, c):  # pragma: no cover - compiled
    # ε_k = Σ_i ρ_c(d_i), d = (Q·Qᵀ − I)·V per candidate; an unread point (NaN) counts ρ = 1.
    # Sums may be reordered (vectorised); NaN and inf keep their meaning (no "nnan"/"ninf" flags).
    K, N = V.shape
    B = Q.shape[1]
    eps = np.zeros(K)
    coef = np.zeros(B)
    c2 = c * c
    for k in range(K):
        miss = 0
        coef[:] = 0.0
        for i in range(N):
            x = V[k, i]
            if np.isnan(x):
                miss += 1
                continue
            for b in range(B):
                coef[b] += Q[i, b] * x
        total = float(miss)
        for i in range(N):
            x = V[k, i]
            if np.isnan(x):
                continue
            d = -x
            for b in range(B):
                d += Q[i, b] * coef[b]
            total += d * d / (c2 + d * d)
        eps[k] = total
    return eps


@njit(cache=True)
def _colour_depth_epsilon_kernel(vals, I, alpha, c, zhat, z, c_depth, lam):  # pragma: no cover - compiled
    # ε_k = (1 − λ)·Σ ρ_c(β_k Î − α I) + λ·Σ ρ_c′(Ẑ − Z) (eqs. 16–18), an unread point counting ρ = 1:
    # ColourDepthCost.residuals summed, without the (K, N) temporaries.
    K, N = vals.shape
    eps = np.zeros(K)
    c2, cd2 = c * c, c_depth * c_depth
    for k in range(K):
        num = 0.0
        den = 0.0
        miss = 0
        for i in range(N):
            x = vals[k, i]
            if np.isnan(x):
                miss += 1
            else:
                num += I[i] * I[i]
                den += I[i] * x
        beta = alpha * num / max(den, 1e-9)
        total = float(miss)
        for i in range(N):
            x = vals[k, i]
            if not np.isnan(x):
                d = beta * x - alpha * I[i]
                total += d * d / (c2 + d * d)
        e = (1.0 - lam) * total
        if zhat.shape[0] > 0:
            td = 0.0
            for i in range(zhat.shape[1]):
                x = zhat[k, i]
                if np.isnan(x):
                    td += 1.0
                else:
                    d = x - z[k, i]
                    td += d * d / (cd2 + d * d)
            e += lam * td
        eps[k] = e
    return eps


def project_sample(images: np.ndarray, intr: Intrinsics, T: np.ndarray, template: SparseTemplate,
                   mode: int = BILINEAR, max_step: float = DEPTH_EDGE) -> tuple[np.ndarray, np.ndarray]:
    """Project template points under K candidate poses and read the images there.

    Parameters
    ----------
    images : (C, H, W) float32 — e.g. grey level and its gradients; or depth (m) with ``mode``
        ``NEAREST_POSITIVE`` (nearest pixel; 0 = no measurement → NaN) or ``DEPTH_BILINEAR``
        (bilinear where the four pixels hold depth within ``max_step`` m of each other — on one
        surface — else the nearest pixel: no depth invented across an edge or a hole)
    T : (K, P, 3, 4) float — part → camera transform of each of the P parts, per candidate
    template : SparseTemplate

    Returns
    -------
    values : (K, C, N) float32, NaN outside the image / behind the camera / no depth
    z : (K, N) float64 — the points' camera depth (m) under each candidate
    """
    images = np.ascontiguousarray(images, np.float32)
    if images.ndim == 2:
        images = images[None]
    T = np.ascontiguousarray(T, np.float64)
    K, N = T.shape[0], len(template.points)
    vals = np.empty((K, images.shape[0], N), np.float32)
    z = np.empty((K, N))
    _project_sample_kernel(images, np.array([intr.fx, intr.fy, intr.cx, intr.cy]), T,
                           np.ascontiguousarray(template.points, np.float64),
                           np.ascontiguousarray(template.part, np.int64), int(mode), float(max_step), vals, z)
    return vals, z


def camera_points(T: np.ndarray, template: SparseTemplate) -> np.ndarray:
    """(K, N, 3) camera-frame template points under each candidate."""
    Tp = np.asarray(T, float)[:, template.part]                 # (K, N, 3, 4)
    return (Tp[..., :3] @ np.asarray(template.points, float)[..., None])[..., 0] + Tp[..., 3]


def project_sample_reference(images: np.ndarray, intr: Intrinsics, T: np.ndarray, template: SparseTemplate,
                             mode: int = BILINEAR, max_step: float = DEPTH_EDGE) -> tuple[np.ndarray, np.ndarray]:
    """:func:`project_sample` in NumPy (cv2-free bilinear interpolation)."""
    images = np.asarray(images, np.float32)
    if images.ndim == 2:
        images = images[None]
    C, H, W = images.shape
    P = camera_points(T, template)
    z = P[..., 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        u = intr.fx * P[..., 0] / z + intr.cx
        v = intr.fy * P[..., 1] / z + intr.cy
    front = z > 1e-6
    if mode in (BILINEAR, DEPTH_BILINEAR):
        ok = front & (u >= 0) & (v >= 0) & (u <= W - 1) & (v <= H - 1)
        u0 = np.minimum(np.where(ok, u, 0).astype(int), W - 2)
        v0 = np.minimum(np.where(ok, v, 0).astype(int), H - 2)
        a, b = np.where(ok, u - u0, 0), np.where(ok, v - v0, 0)
        q = images[:, v0, u0], images[:, v0, u0 + 1], images[:, v0 + 1, u0], images[:, v0 + 1, u0 + 1]
        vals = (1 - a) * (1 - b) * q[0] + a * (1 - b) * q[1] + (1 - a) * b * q[2] + a * b * q[3]
        if mode == DEPTH_BILINEAR:
            lo, hi = np.minimum.reduce(q), np.maximum.reduce(q)
            near = images[:, v0 + (b >= 0.5), u0 + (a >= 0.5)]
            vals = np.where((lo > 0) & (hi - lo <= max_step), vals, near)
            ok = ok[None] & (vals > 0)
    else:
        uu, vv = np.floor(np.nan_to_num(u) + 0.5).astype(int), np.floor(np.nan_to_num(v) + 0.5).astype(int)
        ok = front & (uu >= 0) & (vv >= 0) & (uu < W) & (vv < H)
        vals = images[:, np.where(ok, vv, 0), np.where(ok, uu, 0)]
        ok = ok[None] & (vals > 0)
    vals = np.where(ok, vals, np.nan).astype(np.float32)          # (C, K, N)
    return np.moveaxis(vals, 0, 1), z


class EigenTemplateCost:
    """Face cost with the illumination eigen-template (§3.1): ``d = (Φ̃Φ̃⁺ − I)·V``.

    Parameters
    ----------
    template : SparseTemplate (one part), values unused
    basis : (N, B) float — ``Φ̃ = [Φ v̄]`` restricted to the template points
    grey : (H, W) float32 input image; intr : Intrinsics; c : float, grey levels
    """

    def __init__(self, template: SparseTemplate, basis: np.ndarray, grey: np.ndarray, intr: Intrinsics,
                 c: float = 10.0):
        self.template = template
        self.basis = np.asarray(basis, float)
        self.Q = np.linalg.qr(self.basis)[0]                         # Φ̃Φ̃⁺ = Q·Qᵀ
        self.images = np.ascontiguousarray(grey, np.float32)[None]
        self.intr, self.c = intr, float(c)

    @property
    def size(self) -> int:
        return len(self.template.points)

    def differences(self, V: np.ndarray) -> np.ndarray:
        """``d = (Q·Qᵀ − I)·V`` for samples V (K, N); missing samples (NaN) stay NaN."""
        miss = np.isnan(V)
        V0 = np.where(miss, 0.0, V)
        d = (V0 @ self.Q) @ self.Q.T - V0
        return np.where(miss, np.nan, d)

    def residuals(self, T: np.ndarray) -> np.ndarray:
        """(K, N) residuals ``r`` (eq. 5) of K candidates."""
        vals, _ = project_sample(self.images, self.intr, T, self.template)
        return robust_residual(self.differences(vals[:, 0].astype(float)), self.c)

    def epsilon(self, T: np.ndarray) -> np.ndarray:
        """(K,) ε = Σ ρ_c(d_i) (eq. 3) of K candidates, without forming the residual matrix."""
        vals, _ = project_sample(self.images, self.intr, T, self.template)
        return _eigen_epsilon_kernel(vals[:, 0], self.Q, self.c)

    def subset(self, n: int) -> "EigenTemplateCost":
        """The same cost on the first ``n`` template points (the strongest extrema come first)."""
        t = self.template
        sub = EigenTemplateCost(SparseTemplate(t.points[:n], t.part[:n], t.value[:n]), self.basis[:n],
                                self.images[0], self.intr, self.c)
        return sub


class ColourDepthCost:
    """Colour (eq. 16, brightness normalised) and depth (eq. 17) terms mixed by λ (eqs. 18–19).

    Parameters
    ----------
    colour, depth : SparseTemplate — grey levels, and depths (m) of the depth template points
        at the pose they were taken
    grey : (H, W) float32; depth_image : (H, W) float32 metres, 0 = no measurement (or None)
    c : float or None — colour scale on the normalised differences; None = 0.5 / N (the paper's)
    c_depth : float, metres (5 mm); lam : λ, the depth share (0.9)
    depth_sampling : ``DEPTH_BILINEAR`` (default: the depth image read bilinearly on a surface, so
        the cost changes smoothly with the pose and LM's central differences see a slope) or
        ``NEAREST_POSITIVE`` (the nearest pixel: piecewise constant in the pose, flat within a pixel)
    """

    def __init__(self, colour: SparseTemplate, depth: SparseTemplate | None, grey: np.ndarray,
                 depth_image: np.ndarray | None, intr: Intrinsics, c: float | None = None,
                 c_depth: float = 0.005, lam: float = 0.9, depth_sampling: int = DEPTH_BILINEAR):
        self.colour, self.depth, self.depth_sampling = colour, depth, int(depth_sampling)
        self.images = np.ascontiguousarray(grey, np.float32)[None]
        self.depth_image = None if depth_image is None else np.ascontiguousarray(depth_image, np.float32)[None]
        if self.depth_image is None or depth is None or len(depth.points) == 0:
            lam, self.depth = 0.0, None
        n = max(len(colour.points), 1)
        self.intr, self.c, self.c_depth, self.lam = intr, (0.5 / n if c is None else float(c)), float(c_depth), float(lam)
        I = np.asarray(colour.value, float)
        self.alpha = 1.0 / max(I.sum(), 1e-9)                         # α = 1 / Σ I_i

    @property
    def size(self) -> int:
        return len(self.colour.points) + (0 if self.depth is None else len(self.depth.points))

    def colour_differences(self, vals: np.ndarray) -> np.ndarray:
        """Eq. 16 for samples Î (K, N): ``d = β·Î − α·I`` with β per candidate; NaN where unread."""
        I = np.asarray(self.colour.value, float)
        ok = ~np.isnan(vals)
        Ih = np.where(ok, vals, 0.0)
        num = self.alpha * ((I * I)[None] * ok).sum(1)                # α Σ I_i² over read points
        den = (I[None] * Ih).sum(1)                                   # Σ I_i Î_i
        beta = num / np.maximum(den, 1e-9)
        return np.where(ok, beta[:, None] * Ih - self.alpha * I[None], np.nan)

    def residuals(self, T: np.ndarray) -> np.ndarray:
        """(K, N + N′) residuals ``[√(1−λ)·r_C, √λ·r_D]`` (eq. 19)."""
        vals, _ = project_sample(self.images, self.intr, T, self.colour)
        r = np.sqrt(1.0 - self.lam) * robust_residual(self.colour_differences(vals[:, 0].astype(float)), self.c)
        if self.depth is None:
            return r
        zhat, z = project_sample(self.depth_image, self.intr, T, self.depth, self.depth_sampling)
        rd = np.sqrt(self.lam) * robust_residual(zhat[:, 0] - z, self.c_depth)   # d′ = Ẑ − Z
        return np.concatenate([r, rd], 1)

    def epsilon(self, T: np.ndarray) -> np.ndarray:
        """(K,) ε = (1 − λ)·ε_C + λ·ε_D (eq. 18), compiled (equal to ``(residuals(T)**2).sum(1)``)."""
        vals, _ = project_sample(self.images, self.intr, T, self.colour)
        if self.depth is None:
            zhat, z = np.zeros((0, 0), np.float32), np.zeros((0, 0))
        else:
            zhat, z = project_sample(self.depth_image, self.intr, T, self.depth, self.depth_sampling)
            zhat = zhat[:, 0]
        return _colour_depth_epsilon_kernel(vals[:, 0], np.asarray(self.colour.value, float), self.alpha, self.c,
                                            zhat, z, self.c_depth, self.lam)

    def subset(self, n: int) -> "ColourDepthCost":
        """The same cost on the first ``n`` colour and depth points (strongest extrema first)."""
        c, d = self.colour, self.depth
        sub = ColourDepthCost(SparseTemplate(c.points[:n], c.part[:n], c.value[:n]),
                              None if d is None else SparseTemplate(d.points[:n], d.part[:n], d.value[:n]),
                              self.images[0], None if self.depth_image is None else self.depth_image[0], self.intr,
                              self.c * len(c.points) / max(min(n, len(c.points)), 1), self.c_depth, self.lam,
                              self.depth_sampling)
        return sub
