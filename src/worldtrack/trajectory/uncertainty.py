"""How sure the estimate is at every step: the diagonal blocks of the inverse Gauss–Newton matrix.

At the optimum the posterior is approximately N(X*, H⁻¹) with H = JᵀJ (the objective is twice the
negative log posterior, so JᵀJ is its precision). Only the 6 × 6 diagonal blocks of H⁻¹ are
wanted — "how sure are we where the person was between cameras" — and for a block-tridiagonal H
they follow in O(T) from the block LDLᵀ recursion (what an RTS smoother computes)::

    S_0 = D_0,      S_t = D_t − B_{t−1}ᵀ·S_{t−1}⁻¹·B_{t−1}                   (forward)
    Σ_{T−1} = S_{T−1}⁻¹,   Σ_t = S_t⁻¹ + S_t⁻¹·B_t·Σ_{t+1}·B_tᵀ·S_t⁻¹          (backward)

The recursion runs over time, so it is a Numba kernel; :func:`marginal_covariances_dense` (the
inverse of the whole matrix) is the reference it is tested against.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from worldtrack.trajectory.model import dense_from_blocks


@njit(cache=True)
def _block_tridiagonal_marginals(D: np.ndarray, B: np.ndarray) -> np.ndarray:  # pragma: no cover (compiled)
    n = D.shape[0]
    Sinv = np.empty_like(D)
    Sinv[0] = np.linalg.inv(D[0])
    for t in range(1, n):
        S = D[t] - B[t - 1].T @ Sinv[t - 1] @ B[t - 1]
        Sinv[t] = np.linalg.inv(S)
    out = np.empty_like(D)
    out[n - 1] = Sinv[n - 1]
    for t in range(n - 2, -1, -1):
        G = Sinv[t] @ B[t]
        out[t] = Sinv[t] + G @ out[t + 1] @ G.T
    return out


def marginal_covariances(D: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Diagonal blocks (n, 6, 6) of H⁻¹ for the SPD block-tridiagonal H of D (n, 6, 6), B (n − 1, 6, 6).

    >>> D = np.stack([2 * np.eye(6)] * 3); B = np.stack([-0.5 * np.eye(6)] * 2)
    >>> C = marginal_covariances(D, B)
    >>> bool(np.allclose(C, marginal_covariances_dense(D, B)))
    True
    """
    C = _block_tridiagonal_marginals(np.ascontiguousarray(D, dtype=np.float64),
                                     np.ascontiguousarray(B, dtype=np.float64))
    return 0.5 * (C + C.transpose(0, 2, 1))


def marginal_covariances_dense(D: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Reference: invert the whole (6n, 6n) matrix and cut out its diagonal blocks (small n only)."""
    n, k = D.shape[0], D.shape[1]
    inv = np.linalg.inv(dense_from_blocks(D, B))
    return np.stack([inv[k * t:k * t + k, k * t:k * t + k] for t in range(n)])
