"""The observation model p(Y|X) of seed 002 (eqs. 7, 8): head pixels y_t^i = π_i(x_t) + ω.

Only the cameras that see the person at a time contribute; between views there is nothing.
π_i is the calibrated camera's projection *with* its lens distortion (OpenCV model, as
:meth:`worldtrack.geometry.camera.Camera.project`), here with its analytic Jacobian.

An observation taken at time ``s`` between grid steps is predicted from the nearest step k by the
motion model itself: the head is at ``p_k + (s − t_k)·ṗ_k``, so off-grid time stamps (cameras
that are not synchronised) cost no accuracy and still touch one state only.

Feet (beyond the paper). One head pixel per camera cannot tell the head height from the distance:
a wrong height maps every back-projected point along its ray, a homothety about the camera's nadir.
A box gives its bottom as well as its top: the optional *feet* pixel of a row is the projection of
the floor point (u, v, 0) below the head at the same time, with its own σ. It touches the same state
(not w), so the normal matrix stays block-tridiagonal, and with it the head height is seen.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike

from worldtrack.errors import InputError
from worldtrack.geometry.camera import Camera
from worldtrack.trajectory.model import POS, STATE, VEL, TimeGrid


@dataclass(frozen=True, eq=False)
class Observations:
    """Head pixels of one person, in time order.

    Parameters
    ----------
    time : (N,) float, seconds, non-decreasing
    camera : (N,) int — index into ``cameras``
    uv : (N, 2) float, pixels of the real (distorted) image
    sigma : (N,) float, pixels — standard deviation of each pixel coordinate (Σ_ω = σ²·I)
    cameras : tuple of Camera
    feet_uv : (N, 2) float or None, pixels — the feet (floor point below the head, e.g. a box's
        bottom centre) seen at the same time by the same camera; NaN rows: not seen
    feet_sigma : (N,) float or None, pixels — its σ (default: ``sigma``)

    Examples
    --------
    >>> cam = Camera.look_at("c1", 640, 480, position=(0, -4, 2.5), target=(0, 0, 1.7), hfov_deg=60)
    >>> obs = Observations.from_points([0.0, 0.1], ["c1", "c1"], [[0, 0, 1.7], [0.1, 0, 1.7]], {"c1": cam})
    >>> obs.uv.round(1)
    array([[319.5, 239.5],
           [333.1, 239.5]])
    """

    time: np.ndarray
    camera: np.ndarray
    uv: np.ndarray
    sigma: np.ndarray
    cameras: tuple[Camera, ...]
    feet_uv: np.ndarray | None = None
    feet_sigma: np.ndarray | None = None

    def __post_init__(self) -> None:
        n = len(self.time)
        if n == 0:
            raise InputError("no observations")
        if self.uv.shape != (n, 2) or self.camera.shape != (n,) or self.sigma.shape != (n,):
            raise ValueError("Observations: time, camera, uv and sigma must have N rows")
        if np.any(np.diff(self.time) < 0):
            raise InputError("observations must be in time order")
        if not (np.all(np.isfinite(self.uv)) and np.all(self.sigma > 0)):
            raise InputError("observations need finite pixels and positive sigma")
        if self.feet_uv is not None:
            if self.feet_uv.shape != (n, 2) or (self.feet_sigma is not None and self.feet_sigma.shape != (n,)):
                raise ValueError("Observations: feet_uv must be (N, 2) and feet_sigma (N,)")
            if np.any(np.isnan(self.feet_uv).sum(axis=1) == 1) or np.any(np.isinf(self.feet_uv)):
                raise InputError("feet pixels: give both u_feet and v_feet as finite numbers, or neither")
            if self.feet_sigma is not None and not np.all(self.feet_sigma[self.has_feet] > 0):
                raise InputError("feet pixels need a positive sigma")

    @property
    def has_feet(self) -> np.ndarray:
        """(N,) bool: rows with a feet pixel."""
        if self.feet_uv is None:
            return np.zeros(len(self.time), dtype=bool)
        return np.all(np.isfinite(self.feet_uv), axis=1)

    def feet(self) -> "Observations | None":
        """The feet pixels as observations of their own (rows with feet only), or None."""
        keep = self.has_feet
        if not keep.any():
            return None
        sigma = self.sigma if self.feet_sigma is None else self.feet_sigma
        return Observations(self.time[keep], self.camera[keep], self.feet_uv[keep], sigma[keep], self.cameras)

    @classmethod
    def from_rows(cls, time: ArrayLike, camera_ids: ArrayLike, uv: ArrayLike, cameras: dict[str, Camera],
                  sigma: ArrayLike | float = 2.0, feet_uv: ArrayLike | None = None,
                  feet_sigma: ArrayLike | float | None = None) -> "Observations":
        """Rows of (time s, camera id, (u, v) px[, sigma px][, feet (u, v) px, NaN: none]);
        ``cameras`` maps ids to cameras."""
        ids = [str(c) for c in np.asarray(camera_ids).ravel()]
        order = list(cameras)
        unknown = sorted(set(ids) - set(order))
        if unknown:
            raise InputError(f"unknown camera {unknown[0]!r} (cameras: {', '.join(order)})")
        used = [c for c in order if c in set(ids)]
        index = {c: k for k, c in enumerate(used)}
        t = np.asarray(time, dtype=float).ravel()
        sig = np.broadcast_to(np.asarray(sigma, dtype=float), t.shape).copy()
        feet = None if feet_uv is None else np.asarray(feet_uv, dtype=float).reshape(-1, 2)
        feet_sig = (None if feet_sigma is None or feet is None
                    else np.broadcast_to(np.asarray(feet_sigma, dtype=float), t.shape).copy())
        return cls(t, np.array([index[c] for c in ids], dtype=np.int64), np.asarray(uv, dtype=float).reshape(-1, 2),
                   sig, tuple(cameras[c] for c in used), feet, feet_sig)

    @classmethod
    def from_points(cls, time: ArrayLike, camera_ids: ArrayLike, points: ArrayLike, cameras: dict[str, Camera],
                    sigma: float = 2.0) -> "Observations":
        """Noise-free observations of world head points (N, 3) — for tests and simulations."""
        ids = np.asarray(camera_ids).ravel()
        p = np.asarray(points, dtype=float).reshape(-1, 3)
        uv = np.empty((len(p), 2))
        for cid in np.unique(ids):
            sel = ids == cid
            uv[sel] = cameras[str(cid)].project(p[sel])
        return cls.from_rows(time, ids, uv, cameras, sigma)

    def __len__(self) -> int:
        return len(self.time)

    def camera_ids(self) -> list[str]:
        """The camera id of every row."""
        return [self.cameras[k].id for k in self.camera]

    def subset(self, keep: np.ndarray) -> "Observations":
        """The rows where ``keep`` (bool (N,)) holds."""
        pick = lambda a: None if a is None else a[keep]  # noqa: E731
        return Observations(self.time[keep], self.camera[keep], self.uv[keep], self.sigma[keep], self.cameras,
                            pick(self.feet_uv), pick(self.feet_sigma))


def project_with_jacobian(camera: Camera, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pixels of world points through ``camera`` (lens distortion included) and their Jacobian.

    Parameters
    ----------
    camera : Camera
    points : (N, 3) float, metres

    Returns
    -------
    uv : (N, 2) pixels — equal to ``camera.project(points)``
    J : (N, 2, 3) — ∂uv/∂point, pixels per metre
    depth : (N,) metres along the optical axis (≤ 0: behind the camera, uv meaningless)
    """
    pc = points @ camera.R.T + camera.t                     # camera frame
    z = pc[:, 2]
    zs = np.where(np.abs(z) > 1e-9, z, 1e-9)
    x, y = pc[:, 0] / zs, pc[:, 1] / zs
    # ∂(x, y)/∂pc for x = X/Z, y = Y/Z
    dn = np.zeros((len(z), 2, 3))
    dn[:, 0, 0] = dn[:, 1, 1] = 1.0 / zs
    dn[:, 0, 2] = -x / zs
    dn[:, 1, 2] = -y / zs
    k1, k2, p1, p2, k3 = camera.dist
    r2 = x * x + y * y
    radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
    dradial = k1 + r2 * (2 * k2 + 3 * k3 * r2)               # ∂radial/∂r²
    xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    dd = np.empty((len(z), 2, 2))                            # ∂(xd, yd)/∂(x, y)
    dd[:, 0, 0] = radial + 2 * x * x * dradial + 2 * p1 * y + 6 * p2 * x
    dd[:, 0, 1] = 2 * x * y * dradial + 2 * p1 * x + 2 * p2 * y
    dd[:, 1, 0] = 2 * x * y * dradial + 2 * p1 * x + 2 * p2 * y
    dd[:, 1, 1] = radial + 2 * y * y * dradial + 6 * p1 * y + 2 * p2 * x
    K2 = camera.K[:2, :2]
    uv = np.stack([xd, yd], axis=1) @ K2.T + camera.K[:2, 2]
    J = K2 @ dd @ dn @ camera.R                              # (2,2)(N,2,2)(N,2,3)(3,3)
    return uv, J, z


@dataclass(frozen=True, eq=False)
class ObservationTerm:
    """The observations placed on a time grid: residuals and Jacobians w.r.t. one state each.

    Attributes
    ----------
    obs : Observations
    step : (N,) int — grid step of each observation
    tau : (N,) float, seconds — its time minus the step's time
    floor : bool — the pixels are of the floor point (u, v, 0) below the head (feet), not the head
    """

    obs: Observations
    step: np.ndarray
    tau: np.ndarray
    floor: bool = False

    @classmethod
    def on_grid(cls, obs: Observations, grid: TimeGrid, floor: bool = False) -> "ObservationTerm":
        step, tau = grid.locate(obs.time)
        return cls(obs, step, tau, floor)

    @cached_property
    def rows_by_camera(self) -> list[np.ndarray]:
        """Row indices of each camera's observations."""
        return [np.flatnonzero(self.obs.camera == k) for k in range(len(self.obs.cameras))]

    def head_points(self, X: np.ndarray) -> np.ndarray:
        """(N, 3) predicted head points p_k + τ·ṗ_k at the observation times (z = 0 for feet)."""
        p = X[self.step][:, POS] + self.tau[:, None] * X[self.step][:, VEL]
        if self.floor:
            p[:, 2] = 0.0
        return p

    def residuals(self, X: np.ndarray, with_jacobian: bool = True) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
        """Whitened reprojection residuals (π(x) − y)/σ.

        Returns
        -------
        r : (N, 2)
        J : (N, 2, 6) — ∂r/∂x_step, or None
        depth : (N,) metres — for rejecting steps that put the head behind a camera
        """
        p = self.head_points(X)
        n = len(p)
        r = np.empty((n, 2))
        depth = np.empty(n)
        J = np.zeros((n, 2, STATE)) if with_jacobian else None
        for cam, sel in zip(self.obs.cameras, self.rows_by_camera):
            uv, Jp, z = project_with_jacobian(cam, p[sel])
            s = self.obs.sigma[sel]
            r[sel] = (uv - self.obs.uv[sel]) / s[:, None]
            depth[sel] = z
            if J is not None:
                Jp = Jp / s[:, None, None]
                block = np.zeros((len(sel), 2, STATE))
                block[:, :, POS] = Jp                              # ∂/∂p_k
                block[:, :, VEL] = Jp * self.tau[sel][:, None, None]  # ∂/∂ṗ_k (off-grid time)
                if self.floor:                                     # the feet do not depend on w, ẇ
                    block[:, :, POS[2]] = block[:, :, VEL[2]] = 0.0
                J[sel] = block
        return r, J, depth
