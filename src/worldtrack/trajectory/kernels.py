"""Compiled kernels of the normal equations, each beside the NumPy reference it is tested against.

At T = 100 000 an iteration touches arrays of tens of megabytes; done with NumPy, the scatters
(adding the barrier samples' outer products into the blocks with ``np.add.at``, copying the blocks
into LAPACK's band storage by fancy indexing) and the temporaries of the motion term dominate
it. These are plain loops in Numba over buffers that are allocated once.
"""

from __future__ import annotations

import heapq

import numpy as np
from numba import njit

STATE = 6
BANDWIDTH = 2 * STATE - 1


@njit(cache=True)
def add_motion_terms(X: np.ndarray, A: np.ndarray, W: np.ndarray, g: np.ndarray) -> float:  # pragma: no cover
    """In place: the motion residuals r_t = W·(x_{t+1} − A·x_t) added into the half-gradient g (n, 6)
    (∂r_t/∂x_t = −W·A, ∂r_t/∂x_{t+1} = W); returns Σ‖r_t‖². One pass, no temporaries."""
    n = X.shape[0]
    WA = W @ A
    e = np.empty(STATE)
    r = np.empty(STATE)
    cost = 0.0
    for t in range(n - 1):
        for i in range(STATE):
            acc = X[t + 1, i]
            for j in range(STATE):
                acc -= A[i, j] * X[t, j]
            e[i] = acc
        for i in range(STATE):
            acc = 0.0
            for j in range(STATE):
                acc += W[i, j] * e[j]
            r[i] = acc
            cost += acc * acc
        for j in range(STATE):
            down, up = 0.0, 0.0
            for i in range(STATE):
                down += WA[i, j] * r[i]
                up += W[i, j] * r[i]
            g[t, j] -= down
            g[t + 1, j] += up
    return cost


def add_motion_terms_reference(X: np.ndarray, A: np.ndarray, W: np.ndarray, g: np.ndarray) -> float:
    """NumPy reference of :func:`add_motion_terms`."""
    r = (X[1:] - X[:-1] @ A.T) @ W.T
    g[:-1] -= r @ (W @ A)
    g[1:] += r @ W
    return float(np.sum(r * r))


@njit(cache=True)
def add_pair_terms(D: np.ndarray, B: np.ndarray, g: np.ndarray, step: np.ndarray, J: np.ndarray,
                   r: np.ndarray, weight: np.ndarray) -> None:  # pragma: no cover (compiled)
    """In place: residuals r (M,) with Jacobians J (M, 12) on (x_t, x_{t+1}), t = step, added into
    the diagonal blocks D and upper blocks B (as weight·JᵀJ) and the half-gradient g (as Jᵀr)."""
    for m in range(step.shape[0]):
        if r[m] != 0.0:                # r = 0: a sample left out (beyond the barrier's reach)
            add_pair_row(D, B, g, step[m], J[m], r[m], weight[m])


@njit(cache=True, inline="always")
def add_pair_row(D: np.ndarray, B: np.ndarray, g: np.ndarray, t: int, row: np.ndarray, r: float,
                 w: float) -> None:  # pragma: no cover (compiled)
    """In place: one residual r with Jacobian ``row`` (12,) on (x_t, x_{t+1}) into D, B (as w·JᵀJ) and g (Jᵀr)."""
    for i in range(2 * STATE):
        ji = row[i]
        if ji == 0.0:
            continue
        if i < STATE:
            g[t, i] += ji * r
        else:
            g[t + 1, i - STATE] += ji * r
        for j in range(2 * STATE):
            v = w * ji * row[j]
            if i < STATE and j < STATE:
                D[t, i, j] += v
            elif i >= STATE and j >= STATE:
                D[t + 1, i - STATE, j - STATE] += v
            elif i < STATE:
                B[t, i, j - STATE] += v


def add_pair_terms_reference(D: np.ndarray, B: np.ndarray, g: np.ndarray, step: np.ndarray, J: np.ndarray,
                             r: np.ndarray, weight: np.ndarray) -> None:
    """NumPy reference of :func:`add_pair_terms` (``np.add.at`` over the samples)."""
    J0, J1 = J[:, :STATE], J[:, STATE:]
    w = weight[:, None, None]
    np.add.at(D, step, w * J0[:, :, None] * J0[:, None, :])
    np.add.at(D, step + 1, w * J1[:, :, None] * J1[:, None, :])
    np.add.at(B, step, w * J0[:, :, None] * J1[:, None, :])
    np.add.at(g, step, J0 * r[:, None])
    np.add.at(g, step + 1, J1 * r[:, None])


@njit(cache=True)
def block_matvec(D: np.ndarray, B: np.ndarray, x: np.ndarray) -> np.ndarray:  # pragma: no cover (compiled)
    """H·x (n, 6) for the block-tridiagonal H of diagonal blocks D (n, 6, 6), upper blocks B (n − 1, 6, 6)."""
    n = D.shape[0]
    y = np.zeros_like(x)
    for t in range(n):
        for i in range(STATE):
            acc = 0.0
            for j in range(STATE):
                acc += D[t, i, j] * x[t, j]
                if t + 1 < n:
                    acc += B[t, i, j] * x[t + 1, j]
                if t > 0:
                    acc += B[t - 1, j, i] * x[t - 1, j]
            y[t, i] = acc
    return y


def block_matvec_reference(D: np.ndarray, B: np.ndarray, x: np.ndarray) -> np.ndarray:
    """NumPy reference of :func:`block_matvec`."""
    y = np.einsum("nij,nj->ni", D, x)
    y[:-1] += np.einsum("nij,nj->ni", B, x[1:])
    y[1:] += np.einsum("nji,nj->ni", B, x[:-1])
    return y


@njit(cache=True)
def model_decrease(D: np.ndarray, B: np.ndarray, g: np.ndarray, x: np.ndarray) -> float:  # pragma: no cover
    """−(2·gᵀx + xᵀHx): how much the Gauss–Newton model F + 2gᵀx + xᵀHx falls along the step x (n, 6),
    H block-tridiagonal (D, B); one pass, no H·x temporary (H·x is :func:`block_matvec`)."""
    n = D.shape[0]
    acc = 0.0
    for t in range(n):
        for i in range(STATE):
            hx = 0.0
            for j in range(STATE):
                hx += D[t, i, j] * x[t, j]
            if t + 1 < n:
                for j in range(STATE):
                    hx += B[t, i, j] * x[t + 1, j]
            if t > 0:
                for j in range(STATE):
                    hx += B[t - 1, j, i] * x[t - 1, j]
            acc += x[t, i] * (2.0 * g[t, i] + hx)
    return -acc


def model_decrease_reference(D: np.ndarray, B: np.ndarray, g: np.ndarray, x: np.ndarray) -> float:
    """NumPy reference of :func:`model_decrease`."""
    return float(-(2.0 * np.sum(g * x) + np.sum(x * block_matvec_reference(D, B, x))))


@njit(cache=True)
def block_cholesky_solve(D: np.ndarray, B: np.ndarray, damping: np.ndarray, rhs: np.ndarray, L: np.ndarray,
                         C: np.ndarray, y: np.ndarray, x: np.ndarray) -> bool:  # pragma: no cover (compiled)
    """Solve (H + diag(damping))·x = rhs for the SPD block-tridiagonal H of D (n, 6, 6), B (n − 1, 6, 6):
    the banded Cholesky factorisation done block by block (S_t = D_t − C_{t−1}ᵀC_{t−1} = L_t·L_tᵀ,
    C_t = L_t⁻¹·B_t, then forward and back substitution). L, C (n, 6, 6), y, x (n, 6) are work and
    output buffers; returns False if H is not positive definite."""
    n = D.shape[0]
    S = np.empty((STATE, STATE))
    for t in range(n):
        # S = D_t + diag(damping_t) - C_{t-1}^T C_{t-1}
        for i in range(STATE):
            for j in range(i + 1):
                acc = D[t, i, j]
                if t > 0:
                    for k in range(STATE):
                        acc -= C[t - 1, k, i] * C[t - 1, k, j]
                S[i, j] = acc
            S[i, i] += damping[t, i]
        # Cholesky S = L L^T (lower)
        for j in range(STATE):
            acc = S[j, j]
            for k in range(j):
                acc -= L[t, j, k] * L[t, j, k]
            if not acc > 0.0:
                return False
            d = np.sqrt(acc)
            L[t, j, j] = d
            for i in range(j + 1, STATE):
                acc = S[i, j]
                for k in range(j):
                    acc -= L[t, i, k] * L[t, j, k]
                L[t, i, j] = acc / d
            for i in range(j):
                L[t, i, j] = 0.0
        # forward: y_t = L^-1 (rhs_t - C_{t-1}^T y_{t-1})
        for i in range(STATE):
            acc = rhs[t, i]
            if t > 0:
                for k in range(STATE):
                    acc -= C[t - 1, k, i] * y[t - 1, k]
            for k in range(i):
                acc -= L[t, i, k] * y[t, k]
            y[t, i] = acc / L[t, i, i]
        # C_t = L^-1 B_t
        if t < n - 1:
            for col in range(STATE):
                for i in range(STATE):
                    acc = B[t, i, col]
                    for k in range(i):
                        acc -= L[t, i, k] * C[t, k, col]
                    C[t, i, col] = acc / L[t, i, i]
    for t in range(n - 1, -1, -1):
        for i in range(STATE - 1, -1, -1):
            acc = y[t, i]
            if t < n - 1:
                for k in range(STATE):
                    acc -= C[t, i, k] * x[t + 1, k]
            for k in range(i + 1, STATE):
                acc -= L[t, k, i] * x[t, k]
            x[t, i] = acc / L[t, i, i]
    return True


@njit(cache=True)
def fill_banded(D: np.ndarray, B: np.ndarray, ab: np.ndarray) -> None:  # pragma: no cover (compiled)
    """In place: LAPACK upper band storage ``ab[u + i − j, j] = H[i, j]`` (u = 11) of the
    block-tridiagonal H with diagonal blocks D (n, 6, 6) and upper blocks B (n − 1, 6, 6)."""
    n = D.shape[0]
    for t in range(n):
        for b in range(STATE):
            col = STATE * t + b
            for a in range(b + 1):
                ab[BANDWIDTH + a - b, col] = D[t, a, b]
            if t > 0:
                for a in range(STATE):
                    ab[BANDWIDTH - STATE + a - b, col] = B[t - 1, a, b]


def fill_banded_reference(D: np.ndarray, B: np.ndarray) -> np.ndarray:
    """NumPy reference of :func:`fill_banded`: the band storage (12, 6n) by fancy indexing."""
    n = len(D)
    ab = np.zeros((BANDWIDTH + 1, STATE * n))
    a, b = np.triu_indices(STATE)
    t = np.arange(n)[:, None]
    ab[BANDWIDTH + a - b, STATE * t + b] = D[:, a, b]
    ao, bo = np.indices((STATE, STATE)).reshape(2, -1)
    ab[BANDWIDTH + ao - bo - STATE, STATE * (t[:-1] + 1) + bo] = B.reshape(n - 1, -1)
    return ab


@njit(cache=True)
def barrier_samples(X: np.ndarray, step: np.ndarray, alpha: np.ndarray, dt: float, values: np.ndarray,
                    origin: np.ndarray, res: float, clearance: float, softness: float,
                    gain: float):  # pragma: no cover (compiled)
    """The barrier at every sample (:func:`barrier_point`; see ``environment.barrier_samples_reference``):
    the rounded hinge r (M,), its Jacobian J (M, 12), the distance d (M,) and the curvature factor (M,)."""
    m_count = step.shape[0]
    r = np.empty(m_count)
    J = np.empty((m_count, 2 * STATE))        # every entry written by barrier_point
    d_out = np.empty(m_count)
    curvature = np.empty(m_count)
    for m in range(m_count):
        r[m], d_out[m], curvature[m] = barrier_point(X, step[m], alpha[m], dt, values, origin, res, clearance,
                                                     softness, gain, J[m])
    return r, J, d_out, curvature


@njit(cache=True, inline="always")
def barrier_point(X: np.ndarray, t: int, a: float, dt: float, values: np.ndarray, origin: np.ndarray, res: float,
                  clearance: float, softness: float, gain: float, row: np.ndarray):  # pragma: no cover (compiled)
    """One barrier sample: the Hermite point of (x_t, x_{t+1}) at α = a, its bilinear distance and gradient
    (extrapolated outside the grid), the rounded hinge r; its Jacobian on (x_t, x_{t+1}) written into
    ``row`` (12,); returns (r, d, curvature factor)."""
    h0 = 2 * a ** 3 - 3 * a ** 2 + 1
    h1 = (a ** 3 - 2 * a ** 2 + a) * dt
    h2 = -2 * a ** 3 + 3 * a ** 2
    h3 = (a ** 3 - a ** 2) * dt
    px = h0 * X[t, 0] + h1 * X[t, 1] + h2 * X[t + 1, 0] + h3 * X[t + 1, 1]
    py = h0 * X[t, 2] + h1 * X[t, 3] + h2 * X[t + 1, 2] + h3 * X[t + 1, 3]
    cx, cy, i0, j0, u, v = grid_cell(values, origin, res, px, py)
    v00, v01 = values[j0, i0], values[j0, i0 + 1]
    v10, v11 = values[j0 + 1, i0], values[j0 + 1, i0 + 1]
    d = (1 - u) * (1 - v) * v00 + u * (1 - v) * v01 + (1 - u) * v * v10 + u * v * v11
    gx = ((1 - v) * (v01 - v00) + v * (v11 - v10)) / res
    gy = ((1 - u) * (v10 - v00) + u * (v11 - v01)) / res
    ox, oy = cx - px, cy - py
    gap = np.sqrt(ox * ox + oy * oy)
    if gap > 0:                    # d(p) = d(c(p)) − |c(p) − p|, c the clamped point
        d -= gap
        gx = (0.0 if ox != 0 else gx) + ox / gap
        gy = (0.0 if oy != 0 else gy) + oy / gap
    z = (clearance - d) / softness
    row[4], row[5], row[10], row[11] = 0.0, 0.0, 0.0, 0.0     # the hinge reads positions only
    if z <= -30.0:                 # r < 1e-13·w/s: the sample is left out (r, J exactly 0)
        row[0], row[1], row[2], row[3], row[6], row[7], row[8], row[9] = 0, 0, 0, 0, 0, 0, 0, 0
        return 0.0, d, 1.0
    soft = z + np.log1p(np.exp(-z)) if z > 0 else np.log1p(np.exp(z))
    sig = 1.0 / (1.0 + np.exp(-z))
    r = gain * softness * soft
    sx, sy = -gain * sig * gx, -gain * sig * gy
    row[0], row[1], row[6], row[7] = sx * h0, sx * h1, sx * h2, sx * h3
    row[2], row[3], row[8], row[9] = sy * h0, sy * h1, sy * h2, sy * h3
    return r, d, 1.0 + r * (1.0 - sig) / (gain * softness * sig)


@njit(cache=True, inline="always")
def grid_cell(values: np.ndarray, origin: np.ndarray, res: float, x: float, y: float):  # pragma: no cover
    """The bilinear cell of the floor point (x, y) on the grid ``values[j, i]`` at origin + (i, j)·res: the point
    clamped to the grid (cx, cy), the cell's corner (i0, j0) and the fractions (u, v) within it."""
    ny, nx = values.shape
    cx = min(max(x, origin[0]), origin[0] + res * (nx - 1))
    cy = min(max(y, origin[1]), origin[1] + res * (ny - 1))
    fi = (cx - origin[0]) / res
    fj = (cy - origin[1]) / res
    i0 = min(int(fi), nx - 2)
    j0 = min(int(fj), ny - 2)
    return cx, cy, i0, j0, fi - i0, fj - j0


@njit(cache=True)
def field_value(values: np.ndarray, origin: np.ndarray, res: float, x: float, y: float) -> float:  # pragma: no cover
    """The value d of ``environment.sample_field`` at one floor point (x, y) without its gradient: bilinear on
    the grid ``values[j, i]`` at origin + (i, j)·res, beyond it d(nearest grid point) minus the distance to it.
    The same arithmetic in the same order."""
    cx, cy, i0, j0, a, b = grid_cell(values, origin, res, x, y)
    d = ((1 - a) * (1 - b) * values[j0, i0] + a * (1 - b) * values[j0, i0 + 1]
         + (1 - a) * b * values[j0 + 1, i0] + a * b * values[j0 + 1, i0 + 1])
    gap = np.hypot(cx - x, cy - y)
    return d - gap if gap > 0 else d


@njit(cache=True)
def field_values(values: np.ndarray, origin: np.ndarray, res: float, xy: np.ndarray) -> np.ndarray:  # pragma: no cover
    """:func:`field_value` at floor points xy (N, 2): d (N,) (the free-space routes' rasters)."""
    d = np.empty(xy.shape[0])
    for k in range(xy.shape[0]):
        d[k] = field_value(values, origin, res, xy[k, 0], xy[k, 1])
    return d


#: The 8 neighbours of a raster cell (dj, di) and their lengths in cells.
_NEIGHBOURS = ((0, 1, 1.0), (1, 0, 1.0), (0, -1, 1.0), (-1, 0, 1.0),
               (1, 1, np.sqrt(2.0)), (1, -1, np.sqrt(2.0)), (-1, 1, np.sqrt(2.0)), (-1, -1, np.sqrt(2.0)))


@njit(cache=True)
def raster_route(weight: np.ndarray, free: np.ndarray, start: int, goal: int, res: float) -> np.ndarray:  # pragma: no cover
    """Dijkstra on an 8-connected raster (ny, nx), stopping at the goal: an edge between free cells p, q
    costs its length (res or res·√2) times the mean of their weights. Returns the flat cells from start
    to goal, or an empty array if the goal cannot be reached. (``scipy.sparse.csgraph.dijkstra`` on the
    same graph is the reference: same cost, the same path up to ties.)"""
    ny, nx = weight.shape
    w, ok = weight.ravel(), free.ravel()
    dist = np.full(ny * nx, np.inf)
    pred = np.full(ny * nx, -1)
    done = np.zeros(ny * nx, dtype=np.bool_)
    dist[start] = 0.0
    heap = [(0.0, start)]
    while len(heap):
        d, p = heapq.heappop(heap)
        if done[p]:
            continue
        done[p] = True
        if p == goal:
            break
        j, i = p // nx, p % nx
        for dj, di, ell in _NEIGHBOURS:
            jj, ii = j + dj, i + di
            if jj < 0 or jj >= ny or ii < 0 or ii >= nx:
                continue
            q = jj * nx + ii
            if not ok[q] or done[q]:
                continue
            nd = d + res * ell * 0.5 * (w[p] + w[q])
            if nd < dist[q]:
                dist[q] = nd
                pred[q] = p
                heapq.heappush(heap, (nd, q))
    if not done[goal]:
        return np.empty(0, dtype=np.int64)
    count = 1
    p = goal
    while p != start:
        p = pred[p]
        count += 1
    cells = np.empty(count, dtype=np.int64)
    p = goal
    for k in range(count - 1, -1, -1):
        cells[k] = p
        p = pred[p]
    return cells
