"""The head state, the time grid and the motion prior p_m(X) of seed 002 (eqs. 1, 2, 4, 5, 9).

State of the head at step t (eq. 1), world metres and m/s::

    x_t = (u, u̇, v, v̇, w, ẇ)         u, v on the floor, w the head height

The trajectory X = (x_1 … x_T) (eq. 2) lives on a uniform grid of real time stamps
``t_k = t0 + k·dt``; ``dt`` comes from the observations' time stamps, never "one frame".

Motion model (eq. 4): x_{t+1} = A·x_t + υ_t, υ_t ~ N(0, Σ_υ). Per axis, a constant velocity with
white-noise acceleration of spectral density q (m²/s³)::

    A₁ = [[1, dt], [0, 1]]          Σ₁ = q·[[dt³/3, dt²/2], [dt²/2, dt]]

(horizontal axes share ``q_horizontal``, the height has its own, smaller ``q_vertical``).

Eq. 9's Λ_X, as we read it
--------------------------
The extracted eq. 9 is garbled. −log p_m(X) = ½·Σ_t (x_{t+1} − A·x_t)ᵀ·Σ_υ⁻¹·(x_{t+1} − A·x_t)
expands into ½·Xᵀ·Λ_X·X with the block-tridiagonal

    Λ_X = [[AᵀΣ⁻¹A,   −AᵀΣ⁻¹,          0,       …],
           [−Σ⁻¹A,    Σ⁻¹ + AᵀΣ⁻¹A,    −AᵀΣ⁻¹,  …],
           [0,        −Σ⁻¹A,           Σ⁻¹ + AᵀΣ⁻¹A, …], …,  last diagonal block Σ⁻¹]

which is the paper's matrix with its "Σ_υ" read as the *inverse* covariance Σ_υ⁻¹ (otherwise a
larger motion noise would make the prior stiffer). We drop the common factor ½ throughout: the
objective is Σ of squared whitened residuals, here r_t = W·(x_{t+1} − A·x_t) with
W = chol(Σ_υ)⁻¹, so Σ_t ‖r_t‖² = Xᵀ·Λ_X·X.

The first velocity (beyond the paper)
-------------------------------------
The paper's Λ_X leaves x_1 free. A person seen once (or for a moment) and then unseen for many
seconds has no velocity at all until the next view, and a flat start lets the path bend off at
random speed (zara01 has one: seen once, then not for 15 s, 0.4–0.5 m/s off the wrong way). We add
a prior on the first state's velocity, u̇_1, v̇_1, ẇ_1 ~ N(0, σ₁²) per axis with σ₁ =
``first_velocity_sigma`` = 2 m/s by default — people walk at 1–1.5 m/s, so it only rules out the
absurd; it is the prior the Kalman+RTS baseline starts with. ``first_velocity_sigma=None`` is the
paper's flat start. Its residual x_1[u̇, v̇, ẇ]/σ₁ counts in the motion cost.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike

from worldtrack.errors import InputError

#: Index of u, v, w (positions) and of u̇, v̇, ẇ (velocities) in the state (eq. 1).
POS = np.array([0, 2, 4])
VEL = np.array([1, 3, 5])
STATE = 6


@dataclass(frozen=True)
class TimeGrid:
    """The uniform time grid ``t_k = t0 + k·dt``, k = 0 … n − 1 (seconds).

    >>> grid = TimeGrid.covering([0.0, 0.1, 0.25, 1.0], dt=0.1)
    >>> grid.n, float(grid.times[-1])
    (11, 1.0)
    >>> grid.locate([0.25])   # step 2 or 3: 0.25 s is 0.05 s after step 2
    (array([2]), array([0.05]))
    """

    t0: float
    dt: float
    n: int

    def __post_init__(self) -> None:
        if not (np.isfinite(self.dt) and self.dt > 0):
            raise InputError(f"dt: expected a positive time step in seconds, got {self.dt}")
        if self.n < 2:
            raise InputError(f"the time grid needs at least 2 steps, got {self.n}")

    @classmethod
    def covering(cls, times: ArrayLike, dt: float) -> "TimeGrid":
        """The grid from the first to (at least) the last of ``times`` (s) with step ``dt`` (s)."""
        t = np.asarray(times, dtype=float)
        t0, t1 = float(t.min()), float(t.max())
        n = int(np.ceil((t1 - t0) / dt - 1e-9)) + 1
        return cls(t0, float(dt), max(n, 2))

    @cached_property
    def times(self) -> np.ndarray:
        """(n,) time stamps, seconds."""
        return self.t0 + self.dt * np.arange(self.n)

    def locate(self, times: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Nearest step of each time and its offset ``tau = time − t_step`` in [−dt/2, dt/2] (s)."""
        t = np.asarray(times, dtype=float)
        step = np.clip(np.rint((t - self.t0) / self.dt).astype(np.int64), 0, self.n - 1)
        return step, t - (self.t0 + self.dt * step)


def frame_interval(times: ArrayLike, groups: ArrayLike | None = None) -> float:
    """The time step implied by observation time stamps (s): the smallest, over groups (cameras),
    of the median gap between a group's consecutive distinct time stamps.

    >>> frame_interval([0.0, 0.1, 0.2, 5.0, 5.1], [0, 0, 0, 1, 1])
    0.1
    """
    t = np.asarray(times, dtype=float)
    g = np.zeros(len(t), dtype=np.int64) if groups is None else np.asarray(groups)
    gaps = []
    for key in np.unique(g):
        u = np.unique(t[g == key])
        d = np.diff(u)
        d = d[d > 1e-9]
        if len(d):
            gaps.append(float(np.median(d)))
    if not gaps:
        raise InputError("cannot tell the time step: every camera has a single time stamp (give dt)")
    return round(min(gaps), 9)


@dataclass(frozen=True)
class MotionPrior:
    """Constant-velocity motion with white-noise acceleration (eq. 4).

    Parameters
    ----------
    q_horizontal : float, m²/s³
        Spectral density of the horizontal acceleration noise (a walking person: about 0.5–2).
    q_vertical : float, m²/s³
        The same for the head height, which changes little while walking.
    first_velocity_sigma : float or None, m/s
        Spread of the prior N(0, σ₁²) on each axis of the first state's velocity (walking speed;
        default 2 m/s); None: no prior on x_1, the paper's Λ_X (see the module's docstring).

    Examples
    --------
    >>> prior = MotionPrior(q_horizontal=1.0, q_vertical=0.01)
    >>> A, W = prior.transition(0.1), prior.whitener(0.1)
    >>> x0 = np.array([0.0, 1.0, 0.0, 0.0, 1.7, 0.0])
    >>> float(np.abs(W @ (A @ x0 - A @ x0)).max())   # a perfect constant-velocity step costs 0
    0.0
    """

    q_horizontal: float = 1.0
    q_vertical: float = 0.02
    first_velocity_sigma: float | None = 2.0

    def __post_init__(self) -> None:
        for name in ("q_horizontal", "q_vertical"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise InputError(f"{name}: expected a positive spectral density in m²/s³, got {value}")
        sigma = self.first_velocity_sigma
        if sigma is not None and not (np.isfinite(sigma) and sigma > 0):
            raise InputError(f"first_velocity_sigma: expected a positive speed in m/s or None, got {sigma}")

    @property
    def first_velocity_gain(self) -> float:
        """1/σ₁ (s/m), 0 without the prior: the residual of the first velocity is gain·x_1[u̇, v̇, ẇ]."""
        return 0.0 if self.first_velocity_sigma is None else 1.0 / self.first_velocity_sigma

    def transition(self, dt: float) -> np.ndarray:
        """A (6, 6): x_{t+1} = A·x_t for the state (u, u̇, v, v̇, w, ẇ)."""
        A = np.eye(STATE)
        A[POS, VEL] = dt
        return A

    def noise(self, dt: float) -> np.ndarray:
        """Σ_υ (6, 6): covariance of υ_t over one step of ``dt`` seconds."""
        per_axis = np.array([[dt ** 3 / 3, dt ** 2 / 2], [dt ** 2 / 2, dt]])
        Q = np.zeros((STATE, STATE))
        for k, q in enumerate((self.q_horizontal, self.q_horizontal, self.q_vertical)):
            Q[2 * k:2 * k + 2, 2 * k:2 * k + 2] = q * per_axis
        return Q

    def whitener(self, dt: float) -> np.ndarray:
        """W (6, 6) = chol(Σ_υ)⁻¹, so that ‖W·υ‖² = υᵀ·Σ_υ⁻¹·υ."""
        return np.linalg.inv(np.linalg.cholesky(self.noise(dt)))


def motion_residuals(X: np.ndarray, A: np.ndarray, W: np.ndarray) -> np.ndarray:
    """r_t = W·(x_{t+1} − A·x_t) for t = 1 … T−1: (T − 1, 6) from X (T, 6)."""
    return (X[1:] - X[:-1] @ A.T) @ W.T


def first_velocity_residuals(X: np.ndarray, gain: float) -> np.ndarray:
    """(3,) whitened residual gain·(u̇_1, v̇_1, ẇ_1) of the prior on the first velocity (``gain`` = 1/σ₁)."""
    return gain * X[0, VEL]


def motion_blocks(A: np.ndarray, W: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Λ_X of eq. 9 as blocks: diagonal D (n, 6, 6) and upper off-diagonal B (n − 1, 6, 6).

    ``B[t]`` is the block Λ[t, t+1] = −AᵀΣ⁻¹; Λ[t+1, t] = B[t]ᵀ.
    """
    Sinv = W.T @ W                       # Σ_υ⁻¹
    AtSA = A.T @ Sinv @ A
    D = np.empty((n, STATE, STATE))
    D[:] = Sinv + AtSA                   # Σ⁻¹ + AᵀΣ⁻¹A
    D[0] = AtSA                          # eq. 9: no prior on x_1 (Problem adds the first velocity's)
    D[-1] = Sinv
    B = np.empty((n - 1, STATE, STATE))
    B[:] = -A.T @ Sinv                   # −AᵀΣ⁻¹
    return D, B


def dense_from_blocks(D: np.ndarray, B: np.ndarray) -> np.ndarray:
    """The full symmetric (6n, 6n) matrix of a block-tridiagonal one (reference and tests only)."""
    n = len(D)
    H = np.zeros((STATE * n, STATE * n))
    for t in range(n):
        s = slice(STATE * t, STATE * t + STATE)
        H[s, s] = D[t]
        if t + 1 < n:
            s1 = slice(STATE * (t + 1), STATE * (t + 2))
            H[s, s1] = B[t]
            H[s1, s] = B[t].T
    return H
