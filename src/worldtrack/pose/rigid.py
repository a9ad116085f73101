"""Rigid 6-DoF pose: the pose space, the face's eigen-template and its analytic Jacobian (§3).

* :class:`RigidSpace` — states ``(t, q)`` and increments ``(δt/L, q1, q2, q3)`` (eqs. 8–9, see
  :mod:`worldtrack.pose.models`).
* :func:`shading_basis` — the eigen-template ``Φ̃ = [Φ v̄]`` (§3.1): the model's appearance under
  many lights, reduced by PCA to its mean and leading eigenvectors, per model point.
* :func:`face_jacobian` — ``J = W·(Φ̃Φ̃⁺ − I)·N`` (eq. 10): ``W = diag(c²(d_i² + c²)^(−3/2))``,
  ``n_i = ∇I(u_i)·∂u_i/∂p`` (Fig. 5), evaluated at the increment ``q = 0``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numba import njit

from worldtrack.pose.cost import EigenTemplateCost, project_sample
from worldtrack.pose.models import retract, state_pose


@dataclass
class RigidSpace:
    """The rigid pose space of one object.

    Parameters
    ----------
    length : float, metres — translation unit of an increment (about the object's radius, so that a
        unit step in translation and in rotation move the image alike)
    fd_step : (6,) central-difference steps (eq. 20) in increment units
    """

    length: float = 0.1
    fd_step: np.ndarray = field(default_factory=lambda: np.array([1e-3] * 3 + [5e-4] * 3))
    dim: int = 6

    def retract(self, X: np.ndarray, delta: np.ndarray) -> np.ndarray:
        return retract(X, delta, self.length)

    def transforms(self, X: np.ndarray) -> np.ndarray:
        R, t = state_pose(X)
        return np.concatenate([R, t[..., None]], -1)[:, None]        # (K, 1, 3, 4)

    def increment_sigma(self, sigma_mm: tuple, sigma_deg: tuple) -> np.ndarray:
        """PF noise on increments from σ in mm (translation) and degrees (rotation about x, y, z):
        a rotation by θ about axis j has ``q_j = sin(θ/2)``."""
        return np.concatenate([np.asarray(sigma_mm, float) / 1000.0 / self.length,
                               np.sin(np.radians(np.asarray(sigma_deg, float)) / 2)])


def shading_basis(normals: np.ndarray, n_lights: int = 96, n_vectors: int = 6, seed: int = 0) -> np.ndarray:
    """Per-point illumination functions Ψ (M, n_vectors + 1) for the eigen-template (§3.1).

    The surface is lit by ``n_lights`` distant lights (ambient 0.2–0.8 and a direct light, 0–1
    strong, from the half of the sphere the surface faces; Lambert with attached shadows); the
    shading images are reduced to their mean and leading eigenvectors. The eigen-template of
    points with albedo ``a`` is ``Φ̃ = diag(a)·Ψ`` (an image is albedo × shading), so it follows
    the template's albedo as drawn at each frame.
    """
    rng = np.random.default_rng(seed)
    n = np.asarray(normals, float)
    mean_normal = n.mean(0)
    mean_normal /= max(np.linalg.norm(mean_normal), 1e-9)
    L = rng.normal(size=(n_lights, 3))
    L /= np.linalg.norm(L, axis=1, keepdims=True)
    L = np.where((L @ mean_normal)[:, None] < 0, -L, L)            # lights on the side the surface faces
    ambient = rng.uniform(0.2, 0.8, n_lights)
    direct = rng.uniform(0.0, 1.0, n_lights)
    shading = ambient[None] + direct[None] * np.maximum(n @ L.T, 0.0)        # (M, lights)
    mean = shading.mean(1)
    U, _, _ = np.linalg.svd(shading - mean[:, None], full_matrices=False)
    return np.column_stack([U[:, :n_vectors], mean / max(np.linalg.norm(mean), 1e-9)])


def gradient_images(grey: np.ndarray) -> np.ndarray:
    """(3, H, W) float32: the image and its x, y derivatives (grey levels per pixel, Sobel / 8)."""
    import cv2

    g = np.asarray(grey, np.float32)
    return np.stack([g, cv2.Sobel(g, cv2.CV_32F, 1, 0, ksize=3, scale=0.125),
                     cv2.Sobel(g, cv2.CV_32F, 0, 1, ksize=3, scale=0.125)])


def face_jacobian(cost: EigenTemplateCost, space: RigidSpace, grads: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Analytic ``J`` (K, N, 6) of the eigen-template residuals at increment 0 (eq. 10).

    ``grads`` is :func:`gradient_images` of the input. For a point ``x_c = R·M + t`` in the camera,
    ``∂x_c/∂δt = L·I`` and ``∂x_c/∂q_j = 2·e_j × (R·M)`` (``R(q) ≈ I + 2[q]×`` at ``q = 0``, so
    ``q0 = 1`` and Fig. 5's last block reduces to this); ``∂(u, v)/∂x_c`` is the pinhole's.
    """
    intr = cost.intr
    T = space.transforms(X)
    vals, _ = project_sample(grads, intr, T, cost.template)        # (K, 3, N): I, Ix, Iy
    V = vals[:, 0].astype(float)
    d = cost.differences(V)
    miss = np.isnan(d)
    R, t = state_pose(X)
    RM = cost.template.points @ np.swapaxes(R, 1, 2)             # (K, N, 3) = R·M
    xc = RM + t[:, None]
    x, y, z = xc[..., 0], xc[..., 1], np.maximum(xc[..., 2], 1e-6)
    Ix, Iy = np.nan_to_num(vals[:, 1]), np.nan_to_num(vals[:, 2])
    # ∇I·∂(u,v)/∂x_c: (Ix·fx/z, Iy·fy/z, −(Ix·fx·x + Iy·fy·y)/z²)
    g = np.stack([Ix * intr.fx / z, Iy * intr.fy / z, -(Ix * intr.fx * x + Iy * intr.fy * y) / z ** 2], -1)
    n_t = g * space.length                                          # ∂V/∂δt
    n_q = 2.0 * np.cross(RM, g)                                     # g·(e_j × RM) = e_j·(RM × g)
    Nmat = np.concatenate([n_t, n_q], -1)                           # (K, N, 6)
    Nmat[miss] = 0.0
    Q = cost.Q
    PN = Q @ (Q.T @ Nmat) - Nmat                                  # (Φ̃Φ̃⁺ − I)·N
    c2 = cost.c ** 2
    w = np.where(miss, 0.0, c2 / (np.nan_to_num(d) ** 2 + c2) ** 1.5)          # W
    return w[..., None] * PN


@njit(cache=True, fastmath=True)
def _face_normal_equations_kernel(grads, intr4, R, t, X, Q, c, length, JtJ, Jtr, eps):  # pragma: no cover
    # Per candidate k: sample I, Ix, Iy at the projected template points, d = (QQᵀ − I)V,
    # n_i = ∇I·∂u/∂δ, J = W·(QQᵀ − I)·N (eq. 10), and accumulate JᵀJ, Jᵀr, ε = Σ ρ.
    # The same quantities as face_jacobian (the NumPy reference), without (K, N, 6) temporaries.
    fx, fy, cx, cy = intr4[0], intr4[1], intr4[2], intr4[3]
    _, h, w = grads.shape
    N, B = Q.shape
    V = np.zeros(N)
    Nm = np.zeros((N, 6))
    ok = np.zeros(N, np.bool_)
    coef = np.zeros(B)
    QN = np.zeros((B, 6))
    c2 = c * c
    for k in range(R.shape[0]):
        coef[:] = 0.0
        QN[:, :] = 0.0
        miss = 0
        for i in range(N):
            m0, m1, m2 = X[i, 0], X[i, 1], X[i, 2]
            rm0 = R[k, 0, 0] * m0 + R[k, 0, 1] * m1 + R[k, 0, 2] * m2
            rm1 = R[k, 1, 0] * m0 + R[k, 1, 1] * m1 + R[k, 1, 2] * m2
            rm2 = R[k, 2, 0] * m0 + R[k, 2, 1] * m1 + R[k, 2, 2] * m2
            x, y, z = rm0 + t[k, 0], rm1 + t[k, 1], rm2 + t[k, 2]
            u = fx * x / max(z, 1e-6) + cx
            v = fy * y / max(z, 1e-6) + cy
            ok[i] = z > 1e-6 and u >= 0.0 and v >= 0.0 and u <= w - 1.0 and v <= h - 1.0
            if not ok[i]:
                miss += 1
                continue
            u0, v0 = min(int(u), w - 2), min(int(v), h - 2)
            a, b = u - u0, v - v0
            w00, w01, w10, w11 = (1 - a) * (1 - b), a * (1 - b), (1 - a) * b, a * b      # bilinear weights
            s0 = w00 * grads[0, v0, u0] + w01 * grads[0, v0, u0 + 1] + w10 * grads[0, v0 + 1, u0] + w11 * grads[0, v0 + 1, u0 + 1]
            s1 = w00 * grads[1, v0, u0] + w01 * grads[1, v0, u0 + 1] + w10 * grads[1, v0 + 1, u0] + w11 * grads[1, v0 + 1, u0 + 1]
            s2 = w00 * grads[2, v0, u0] + w01 * grads[2, v0, u0 + 1] + w10 * grads[2, v0 + 1, u0] + w11 * grads[2, v0 + 1, u0 + 1]
            V[i] = s0
            g0, g1 = s1 * fx / z, s2 * fy / z
            g2 = -(s1 * fx * x + s2 * fy * y) / (z * z)
            Nm[i, 0], Nm[i, 1], Nm[i, 2] = g0 * length, g1 * length, g2 * length
            Nm[i, 3] = 2.0 * (rm1 * g2 - rm2 * g1)                     # 2·(RM × g)
            Nm[i, 4] = 2.0 * (rm2 * g0 - rm0 * g2)
            Nm[i, 5] = 2.0 * (rm0 * g1 - rm1 * g0)
            for bb in range(B):
                coef[bb] += Q[i, bb] * s0
                for j in range(6):
                    QN[bb, j] += Q[i, bb] * Nm[i, j]
        JtJ[k, :, :] = 0.0
        Jtr[k, :] = 0.0
        total = float(miss)
        row = np.zeros(6)
        for i in range(N):
            if not ok[i]:
                continue
            d = -V[i]
            for bb in range(B):
                d += Q[i, bb] * coef[bb]
            den = c2 + d * d
            r = d / np.sqrt(den)
            total += r * r
            wgt = c2 / (den * np.sqrt(den))
            for j in range(6):
                acc = -Nm[i, j]
                for bb in range(B):
                    acc += Q[i, bb] * QN[bb, j]
                row[j] = wgt * acc
            for j in range(6):
                Jtr[k, j] += row[j] * r
                for l in range(j, 6):                                  # upper triangle; mirrored below
                    JtJ[k, j, l] += row[j] * row[l]
        for j in range(6):
            for l in range(j):
                JtJ[k, j, l] = JtJ[k, l, j]
        eps[k] = total


def face_normal_equations(cost: EigenTemplateCost, space: RigidSpace, grads: np.ndarray,
                          X: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(JᵀJ (K, 6, 6), Jᵀr (K, 6), ε (K,))`` of the eigen-template cost at states X, compiled.

    The same J as :func:`face_jacobian` (eq. 10), which is its readable reference.
    """
    R, t = state_pose(X)
    K = len(X)
    JtJ, Jtr, eps = np.zeros((K, 6, 6)), np.zeros((K, 6)), np.zeros(K)
    intr = cost.intr
    _face_normal_equations_kernel(np.ascontiguousarray(grads, np.float32),
                                  np.array([intr.fx, intr.fy, intr.cx, intr.cy]), R, t,
                                  np.ascontiguousarray(cost.template.points, np.float64), np.ascontiguousarray(cost.Q),
                                  float(cost.c), float(space.length), JtJ, Jtr, eps)
    return JtJ, Jtr, eps
