"""The environment model p_e(X) of seed 002 (eq. 6): people keep clear of obstacles and walls
(e_h on the distance d_h to the nearest one) and carry their head near their height (e_v on d_v).

The paper leaves e_h and e_v open. Here, as squared residuals that Levenberg–Marquardt can use
(λ is the paper's weight; the objective adds ``−λ·(e_h + e_v)``):

    −e_h = (w·log(1 + e^((c − d_h)/w)) / s_h)²
                                          a hinge on the floor's signed distance field d_h (m),
                                          (c − d_h)/s_h inside the clearance c, ≈ 0 beyond it,
                                          its corner rounded over a width w (``softness``); the
                                          field is interpolated bilinearly
    −e_v = ((w − H) / σ_v)²              H: the person's head height (their stature)

Why round the hinge: Gauss–Newton sees a plain hinge only where it is already active, so a step
drives every sample that is just outside the clearance straight into it; the rounded hinge has a
small slope there, so the quadratic model sees the obstacle coming. Deep inside it is the hinge.

A barrier evaluated only at the grid steps lets a path hop over a thin wall between two steps
(at 2.5 Hz a walker moves 0.5 m per step). The hinge is therefore also evaluated at ``substeps``
points inside every step, on the cubic Hermite curve through the two states (positions and
velocities) — the motion model's own path between them — so each sample still touches two
neighbouring states only and the normal matrix stays block-tridiagonal.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy import ndimage
from scipy.special import expit

from worldtrack.errors import InputError
from worldtrack.scene.floor import FloorGrid
from worldtrack.trajectory.model import STATE

#: Where u, u̇, v, v̇ sit in the state; the hinge reads the floor position only.
_U, _UD, _V, _VD, _W = 0, 1, 2, 3, 4


def sample_field(grid: FloorGrid, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bilinear value and gradient of a floor field at points (N, 2), extrapolated outside the grid.

    Beyond the grid the value continues as ``d(nearest grid point) − distance to it`` (walls lie
    inside the grid, so there it only grows more negative), with its gradient.

    Returns
    -------
    d : (N,) field value (metres for a distance field)
    grad : (N, 2) ∂d/∂(x, y)
    """
    v = grid.values
    ny, nx = v.shape
    res = grid.resolution
    lo = grid.origin
    hi = lo + res * (np.array([nx, ny]) - 1)
    c = np.clip(xy, lo, hi)
    fi = (c[:, 0] - lo[0]) / res
    fj = (c[:, 1] - lo[1]) / res
    i0 = np.minimum(fi.astype(np.int64), nx - 2)
    j0 = np.minimum(fj.astype(np.int64), ny - 2)
    a, b = fi - i0, fj - j0
    v00, v01 = v[j0, i0], v[j0, i0 + 1]
    v10, v11 = v[j0 + 1, i0], v[j0 + 1, i0 + 1]
    d = (1 - a) * (1 - b) * v00 + a * (1 - b) * v01 + (1 - a) * b * v10 + a * b * v11
    grad = np.column_stack([((1 - b) * (v01 - v00) + b * (v11 - v10)) / res,
                            ((1 - a) * (v10 - v00) + a * (v11 - v01)) / res])
    out = c - xy
    gap = np.hypot(out[:, 0], out[:, 1])
    far = gap > 0
    if far.any():
        # d(p) = d(c(p)) − |c(p) − p|: the clamped coordinates of c do not follow p
        d[far] -= gap[far]
        grad[far] = np.where(out[far] != 0, 0.0, grad[far]) + out[far] / gap[far, None]
    return d, grad


def hermite_weights(alpha: np.ndarray, dt: float) -> np.ndarray:
    """(M, 4) weights of (p_t, ṗ_t, p_{t+1}, ṗ_{t+1}) for the cubic Hermite point at fractions α."""
    a2, a3 = alpha * alpha, alpha * alpha * alpha
    return np.column_stack([2 * a3 - 3 * a2 + 1, (a3 - 2 * a2 + alpha) * dt, -2 * a3 + 3 * a2, (a3 - a2) * dt])


@dataclass(frozen=True)
class Barrier:
    """The hinge e_h on a floor distance field.

    Parameters
    ----------
    field : FloorGrid — signed distance to the nearest obstacle or wall (m), positive where people walk
    clearance : float, metres — the hinge starts this far from an obstacle (about half a body width)
    scale : float, metres — a penetration of ``scale`` into the clearance costs 1 per sample
    substeps : int — samples per time step along the Hermite curve (1 = at the steps only)
    softness : float, metres — width w of the rounded corner of the hinge (see the module notes)
    """

    field: FloorGrid
    clearance: float = 0.2
    scale: float = 0.02
    substeps: int = 1
    softness: float = 0.03

    def __post_init__(self) -> None:
        if not (self.clearance >= 0 and self.scale > 0 and int(self.substeps) >= 1 and self.softness > 0):
            raise InputError("barrier: expected clearance ≥ 0 m, scale > 0 m, substeps ≥ 1 and softness > 0 m, "
                             f"got {self.clearance}, {self.scale}, {self.substeps}, {self.softness}")

    @staticmethod
    def substeps_for(dt: float, clearance: float, max_speed: float = 2.5) -> int:
        """Samples per step so that a walker at ``max_speed`` (m/s) moves at most ``clearance`` between them."""
        return max(1, int(np.ceil(max_speed * dt / max(clearance, 1e-3))))

    def gain(self, weight: float) -> float:
        """√(λ/m)/s_h (1/m): the factor of every sample's rounded hinge, environment weight λ = ``weight``
        spread over the m = ``substeps`` samples of a step."""
        return float(np.sqrt(weight / self.substeps) / self.scale)

    def samples(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """(step t, fraction α) of every sample on a grid of ``n`` steps: α = j/m on steps
        0 … n − 2, plus α = 1 on step n − 2 (the last state)."""
        m = int(self.substeps)
        t = np.repeat(np.arange(n - 1), m)
        alpha = np.tile(np.arange(m) / m, n - 1)
        return np.append(t, n - 2), np.append(alpha, 1.0)


@dataclass(frozen=True)
class HeightPrior:
    """e_v: the head height w stays near the person's head height.

    Parameters
    ----------
    height : float, metres — the person's head height when standing (their stature)
    sigma : float, metres — how far it strays per step (gait bob, stooping)
    """

    height: float = 1.70
    sigma: float = 0.05

    def __post_init__(self) -> None:
        if not (0.3 < self.height < 2.6 and self.sigma > 0):
            raise InputError(f"height: expected a head height in (0.3, 2.6) m and sigma > 0, got "
                             f"{self.height}, {self.sigma}")


@dataclass(frozen=True)
class EnvironmentModel:
    """p_e(X) with its weight λ: a barrier (or None: no obstacles) and a height prior (or None)."""

    barrier: Barrier | None = None
    height: HeightPrior | None = None
    weight: float = 1.0

    def without_barrier(self) -> "EnvironmentModel":
        return EnvironmentModel(None, self.height, self.weight)


@dataclass(frozen=True)
class BarrierResiduals:
    """Barrier samples: residuals and their Jacobians w.r.t. x_t and x_{t+1}.

    r : (M,) ; step : (M,) int — t ; J : (M, 12) — ∂r/∂(x_t, x_{t+1});
    inside : (M,) bool — the sample is within the clearance (the hinge proper, not its rounded tail)
    curvature : (M,) — 1 + r·r″/r′² ≥ 1: the factor that turns the Gauss–Newton term J·Jᵀ into the
        exact Hessian of r² along the distance gradient (the rounded corner is curved; without this
        Gauss–Newton under-estimates it and zig-zags across the corner)
    """

    r: np.ndarray
    step: np.ndarray
    J: np.ndarray
    inside: np.ndarray
    curvature: np.ndarray


#: Beyond z = (c − d)/w ≤ −30 a sample's residual is below 1e-13·w/s_h: it is left out (r = 0).
Z_CUTOFF = -30.0


def barrier_samples_reference(X: np.ndarray, step: np.ndarray, alpha: np.ndarray, dt: float, field: FloorGrid,
                              clearance: float, softness: float, gain: float):
    """NumPy reference of :func:`worldtrack.trajectory.kernels.barrier_samples`: for every sample
    (step t, fraction α), the residual r, its Jacobian J (M, 12) on (x_t, x_{t+1}), the distance d
    and the curvature factor (see :class:`BarrierResiduals`)."""
    H = hermite_weights(alpha, dt)
    x0, x1 = X[step], X[step + 1]
    u = H[:, 0] * x0[:, _U] + H[:, 1] * x0[:, _UD] + H[:, 2] * x1[:, _U] + H[:, 3] * x1[:, _UD]
    v = H[:, 0] * x0[:, _V] + H[:, 1] * x0[:, _VD] + H[:, 2] * x1[:, _V] + H[:, 3] * x1[:, _VD]
    d, grad = sample_field(field, np.column_stack([u, v]))
    z = (clearance - d) / softness
    reach = z > Z_CUTOFF                                       # beyond: r and J exactly 0
    r = np.where(reach, gain * softness * np.logaddexp(0.0, z), 0.0)      # w·log(1 + e^z)
    sigmoid = np.where(reach, expit(z), 0.0)
    # r′ = ∂r/∂(c − d) = gain·σ(z), r″ = gain·σ(1 − σ)/w, so r·r″/r′² = r·(1 − σ)/(gain·w·σ)
    curvature = np.where(reach, 1.0 + r * (1.0 - sigmoid) / (gain * softness * np.where(reach, sigmoid, 1.0)), 1.0)
    g = -(gain * sigmoid)[:, None] * grad                      # ∂r/∂(u, v) of the sample point
    J = np.zeros((len(d), 2 * STATE))
    for k, (iu, iud) in enumerate(((_U, _UD), (_V, _VD))):
        J[:, iu] = g[:, k] * H[:, 0]
        J[:, iud] = g[:, k] * H[:, 1]
        J[:, STATE + iu] = g[:, k] * H[:, 2]
        J[:, STATE + iud] = g[:, k] * H[:, 3]
    return r, J, d, curvature


def barrier_residuals(X: np.ndarray, barrier: Barrier, weight: float, dt: float,
                      only_active: bool = True, reference: bool = False) -> BarrierResiduals:
    """√(λ/m)·w·log(1 + e^((c − d_h(p(α)))/w))/s_h at every sample of :meth:`Barrier.samples`.

    With ``only_active`` only the samples with (c − d)/w > −30 are returned; otherwise all, in sample
    order, those beyond the barrier's reach with r = 0 and J = 0 (the solver's and the dense
    reference's use). ``reference``: the NumPy version instead of the compiled kernel.
    """
    from worldtrack.trajectory.kernels import barrier_samples
    t, alpha = barrier.samples(len(X))
    gain = barrier.gain(weight)
    f = barrier.field
    if reference:
        r, J, d, curvature = barrier_samples_reference(X, t, alpha, dt, f, barrier.clearance, barrier.softness, gain)
    else:
        r, J, d, curvature = barrier_samples(X, t, alpha, dt, f.values, np.asarray(f.origin, dtype=float),
                                             float(f.resolution), barrier.clearance, barrier.softness, gain)
    if only_active:
        keep = np.flatnonzero(barrier.clearance - d > Z_CUTOFF * barrier.softness)
        r, J, d, curvature, t = r[keep], J[keep], d[keep], curvature[keep], t[keep]
    return BarrierResiduals(r, t, J, d < barrier.clearance, curvature)


def height_residuals(X: np.ndarray, prior: HeightPrior, weight: float) -> tuple[np.ndarray, float]:
    """√λ·(w_t − H)/σ_v for every step (n,), and its constant derivative w.r.t. w_t."""
    gain = np.sqrt(weight) / prior.sigma
    return gain * (X[:, _W] - prior.height), gain


# ------------------------------------------------------------------ distance fields beyond scenes

def field_from_walkable(walkable: np.ndarray, origin: ArrayLike, resolution: float) -> FloorGrid:
    """Signed distance field (m) from a walkable raster (``walkable[j, i]`` at origin + (i, j)·res):
    positive inside, negative outside, as :meth:`worldtrack.scene.floor.WalkableArea.distance_field`."""
    walk = np.asarray(walkable, dtype=bool)
    inside = ndimage.distance_transform_edt(walk) * resolution
    outside = ndimage.distance_transform_edt(~walk) * resolution
    values = np.where(walk, inside - resolution / 2, -(outside - resolution / 2))
    return FloorGrid(np.asarray(origin, dtype=float), float(resolution), values)


def rasterise_segments(blocked: np.ndarray, segments: np.ndarray, origin: ArrayLike, resolution: float) -> None:
    """Mark the cells along wall segments (K, 2, 2) metres as blocked (``blocked[j, i]``, in place)."""
    origin = np.asarray(origin, dtype=float)
    for a, b in np.asarray(segments, dtype=float).reshape(-1, 2, 2):
        n = int(np.ceil(np.linalg.norm(b - a) / (resolution / 2))) + 1
        pts = a + np.linspace(0.0, 1.0, n)[:, None] * (b - a)
        ij = np.rint((pts - origin) / resolution).astype(int)
        ok = (ij[:, 0] >= 0) & (ij[:, 0] < blocked.shape[1]) & (ij[:, 1] >= 0) & (ij[:, 1] < blocked.shape[0])
        blocked[ij[ok, 1], ij[ok, 0]] = True


def inside_obstacles(field: FloorGrid, xy: ArrayLike) -> np.ndarray:
    """(N,) bool: floor points where the signed distance is negative (inside an obstacle or a wall)."""
    d, _ = sample_field(field, np.asarray(xy, dtype=float).reshape(-1, 2))
    return d < 0


def segment_crossings(path: ArrayLike, walls: ArrayLike) -> np.ndarray:
    """(T − 1,) bool: the step from ``path[t]`` to ``path[t+1]`` (floor points, m) crosses a wall
    segment (K, 2, 2) — proper intersection of the two segments."""
    p = np.asarray(path, dtype=float).reshape(-1, 2)
    w = np.asarray(walls, dtype=float).reshape(-1, 2, 2)
    if len(w) == 0 or len(p) < 2:
        return np.zeros(max(len(p) - 1, 0), dtype=bool)
    a, b = p[:-1, None, :], p[1:, None, :]                  # (T-1, 1, 2)
    c, d = w[None, :, 0, :], w[None, :, 1, :]                # (1, K, 2)

    def cross(o, q, r):
        return (q[..., 0] - o[..., 0]) * (r[..., 1] - o[..., 1]) - (q[..., 1] - o[..., 1]) * (r[..., 0] - o[..., 0])

    d1, d2 = cross(c, d, a), cross(c, d, b)
    d3, d4 = cross(a, b, c), cross(a, b, d)
    hit = (d1 * d2 < 0) & (d3 * d4 < 0)
    return hit.any(axis=1)
