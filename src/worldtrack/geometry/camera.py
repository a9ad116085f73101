"""The calibrated camera: projection, back-projection and viewing geometry.

Conventions (DESIGN.md): world right-handed, Z up, floor Z = 0, metres. Camera frame: x right,
y down, z forward (OpenCV). Image: x right, y down, pixel centres at integer coordinates, so the
image covers ``-0.5 ≤ u < width - 0.5``.

Normalisation of the projection matrix
--------------------------------------
The 1999 paper fixes ``C34 = 1``. That divides by the depth of the world origin, which is zero
whenever the origin lies on the camera's principal plane (the plane through the camera centre
parallel to the image), and then the normalisation breaks. worldtrack instead scales ``P`` so that
its third row has ``‖(P31, P32, P33)‖ = 1`` and ``det(P[:, :3]) > 0``. This always exists for a
rank-3 camera, and with it the homogeneous scale ``h`` of ``h·(u, v, 1) = P·(X, Y, Z, 1)`` is the
point's depth along the optical axis in metres: positive in front of the camera, negative behind.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike

from worldtrack.errors import InputError

_WORLD_UP = np.array([0.0, 0.0, 1.0])


def _as_points(points: ArrayLike, dim: int) -> tuple[np.ndarray, tuple[int, ...]]:
    """Reshape ``points`` to (N, dim) float64, remembering the leading shape."""
    p = np.asarray(points, dtype=float)
    if p.shape[-1] != dim:
        raise ValueError(f"expected points with last dimension {dim}, got shape {p.shape}")
    return p.reshape(-1, dim), p.shape[:-1]


def radial_factor(r2: np.ndarray, k1: float, k2: float, k3: float) -> np.ndarray:
    """OpenCV's radial distortion factor ``1 + k1·r² + k2·r⁴ + k3·r⁶`` at ``r2 = r²`` (NumPy; the
    compiled kernels' is :func:`worldtrack.geometry._kernels.radial_factor`)."""
    return 1 + r2 * (k1 + r2 * (k2 + r2 * k3))


def normalise_projection(P: ArrayLike) -> np.ndarray:
    """Scale a 3×4 projection matrix so that ‖P[2, :3]‖ = 1 and det(P[:, :3]) > 0.

    Parameters
    ----------
    P : (3, 4) array_like

    Returns
    -------
    (3, 4) ndarray
        With this scale, ``P @ [X, Y, Z, 1]`` has third component equal to the point's depth
        along the optical axis (metres, positive in front).

    Raises
    ------
    ValueError
        If the left 3×3 block has rank < 3 (no finite camera centre).
    """
    P = np.asarray(P, dtype=float)
    if P.shape != (3, 4):
        raise ValueError(f"expected 3x4 matrix, got {P.shape[0]}x{P.shape[1] if P.ndim > 1 else 1}")
    M = P[:, :3]
    s = np.linalg.svd(M, compute_uv=False)
    if s[-1] <= 1e-12 * max(s[0], 1e-300):
        raise ValueError("rank of the left 3x3 block is below 3 (not a finite camera)")
    scale = 1.0 / np.linalg.norm(M[2])
    if np.linalg.det(M) < 0:
        scale = -scale
    return P * scale


@dataclass(frozen=True, eq=False)
class Camera:
    """A pinhole camera with optional OpenCV lens distortion.

    Parameters
    ----------
    id : str
        Name used in scene files and on the command line (``--video CAM=PATH``).
    width, height : int
        Image size in pixels.
    K : (3, 3) array_like
        Intrinsics ``[[fx, s, cx], [0, fy, cy], [0, 0, 1]]`` in pixels.
    R : (3, 3) array_like
        Rotation world → camera.
    t : (3,) array_like
        Translation world → camera in metres: ``X_cam = R·X_world + t``.
    dist : (5,) array_like, optional
        OpenCV distortion ``(k1, k2, p1, p2, k3)``; zeros (none) by default.

    Examples
    --------
    >>> cam = Camera.look_at("c1", 640, 480, position=(0, -4, 2.5), target=(0, 0, 1), hfov_deg=60)
    >>> uv = cam.project([[0, 0, 1]])
    >>> bool(np.allclose(uv, [[319.5, 239.5]]))
    True
    """

    id: str
    width: int
    height: int
    K: np.ndarray
    R: np.ndarray
    t: np.ndarray
    dist: np.ndarray = field(default_factory=lambda: np.zeros(5))

    def __post_init__(self) -> None:
        K = np.array(self.K, dtype=float).reshape(3, 3)
        R = np.array(self.R, dtype=float).reshape(3, 3)
        t = np.array(self.t, dtype=float).reshape(3)
        dist = np.zeros(5) if self.dist is None else np.array(self.dist, dtype=float).ravel()
        if dist.size > 5:
            raise ValueError(f"expected at most 5 distortion coefficients (k1,k2,p1,p2,k3), got {dist.size}")
        dist = np.concatenate([dist, np.zeros(5 - dist.size)])
        if K[0, 0] <= 0 or K[1, 1] <= 0 or abs(K[2, 2] - 1) > 1e-9 or np.any(K[[1, 2, 2], [0, 0, 1]] != 0):
            raise ValueError("expected K = [[fx, s, cx], [0, fy, cy], [0, 0, 1]] with fx, fy > 0")
        if not np.allclose(R @ R.T, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
            raise ValueError("expected R to be a rotation matrix (orthonormal, det +1)")
        if self.width <= 0 or self.height <= 0:
            raise ValueError(f"expected a positive image size, got {self.width}x{self.height}")
        for name, value in (("K", K), ("R", R), ("t", t), ("dist", dist)):
            value.setflags(write=False)
            object.__setattr__(self, name, value)

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_projection(cls, id: str, width: int, height: int, P: ArrayLike,
                        dist: ArrayLike | None = None) -> "Camera":
        """Decompose a 3×4 projection matrix ``P ~ K[R | t]`` (RQ decomposition).

        Any overall scale or sign of ``P`` is accepted (see the module's normalisation note).
        """
        Pn = normalise_projection(P)
        K, R = scipy.linalg.rq(Pn[:, :3])
        D = np.diag(np.sign(np.diag(K)))
        K, R = K @ D, D @ R
        # ‖P[2, :3]‖ = 1 and R orthonormal make K[2, 2] = 1 already; remove rounding only.
        K = K / K[2, 2]
        t = np.linalg.solve(K, Pn[:, 3])
        K[1, 0] = K[2, 0] = K[2, 1] = 0.0
        return cls(id, int(width), int(height), K, R, t, dist)

    @classmethod
    def look_at(cls, id: str, width: int, height: int, position: ArrayLike, target: ArrayLike,
                K: ArrayLike | None = None, hfov_deg: float | None = None,
                dist: ArrayLike | None = None) -> "Camera":
        """Camera at ``position`` (m) looking at ``target`` (m), image top towards world up.

        Give either ``K`` or a horizontal field of view ``hfov_deg`` (square pixels, principal
        point at the image centre). A camera looking straight down has image top towards +Y.
        """
        position = np.asarray(position, dtype=float).reshape(3)
        R = look_at_rotation(position, np.asarray(target, dtype=float).reshape(3))
        if K is None:
            if hfov_deg is None:
                raise ValueError("look_at needs K or hfov_deg")
            K = intrinsics_from_fov(width, height, hfov_deg)
        return cls(id, int(width), int(height), np.asarray(K, float), R, -R @ position, dist)

    # ------------------------------------------------------------------ basic properties
    @cached_property
    def P(self) -> np.ndarray:
        """(3, 4) projection matrix ``K[R | t]`` with the module's normalisation."""
        return self.K @ np.hstack([self.R, self.t[:, None]])

    @cached_property
    def centre(self) -> np.ndarray:
        """(3,) camera centre in world coordinates, metres."""
        return -self.R.T @ self.t

    @cached_property
    def optical_axis(self) -> np.ndarray:
        """(3,) unit viewing direction in world coordinates."""
        return self.R[2].copy()

    @cached_property
    def has_distortion(self) -> bool:
        """True when any lens distortion coefficient is non-zero."""
        return bool(np.any(self.dist != 0))

    @cached_property
    def floor_direction(self) -> np.ndarray:
        """(2,) unit vector: the viewing direction projected on the floor.

        For a camera looking straight down (horizontal part of the optical axis under 1e-6) the
        direction towards the image top is used instead, so the pair (this, its perpendicular)
        is always defined.
        """
        d = self.optical_axis[:2]
        if np.linalg.norm(d) < 1e-6:
            d = -self.R[1, :2]
        return d / np.linalg.norm(d)

    def depth(self, points: ArrayLike) -> np.ndarray:
        """Depth along the optical axis (m) of world points (..., 3) → (...)."""
        p, lead = _as_points(points, 3)
        return (p @ self.R[2] + self.t[2]).reshape(lead)

    def floor_distance(self, points: ArrayLike) -> np.ndarray:
        """Distance (m) on the floor plane from the camera's foot point to the points' (X, Y).

        The 1999 paper's occlusion depth (measured in the Z = 0 plane, not in 3-D).
        """
        p, lead = _as_points(points, 3)
        return np.hypot(p[:, 0] - self.centre[0], p[:, 1] - self.centre[1]).reshape(lead)

    def floor_rays(self, xy: ArrayLike, min_distance: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """The camera's lines of sight on the floor through floor points ``xy`` (..., 2).

        Returns
        -------
        along : (..., 2) unit vectors from the camera's foot point towards the points — the
            direction in which one camera cannot tell depth; :attr:`floor_direction` for points
            within ``min_distance`` (m, at least 1e-9) of the foot point, where it is undefined
            or unstable
        distance : (...) floor distance (m) from the foot point, as :meth:`floor_distance`
        """
        p, lead = _as_points(xy, 2)
        d = p - self.centre[:2]
        n = np.hypot(d[:, 0], d[:, 1])
        far = n > max(min_distance, 1e-9)          # the centre is recovered to ~1e-15 m
        along = np.where(far[:, None], d / np.where(far, n, 1.0)[:, None], self.floor_direction)
        return along.reshape(lead + (2,)), n.reshape(lead)

    # ------------------------------------------------------------------ projection
    def project(self, points: ArrayLike, return_depth: bool = False):
        """Project world points to pixels, lens distortion included.

        Parameters
        ----------
        points : (..., 3) array_like, metres
        return_depth : bool
            Also return the depth along the optical axis.

        Returns
        -------
        uv : (..., 2) ndarray, pixels
            NaN for points not in front of the camera (depth ≤ 1e-9 m).
        depth : (...) ndarray, metres
            Only with ``return_depth``.
        """
        p, lead = _as_points(points, 3)
        pc = p @ self.R.T + self.t
        z = pc[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            xy = pc[:, :2] / z[:, None]
        xy[z <= 1e-9] = np.nan
        uv = self._normalised_to_pixels(self.distort_normalised(xy))
        uv = uv.reshape(lead + (2,))
        return (uv, z.reshape(lead)) if return_depth else uv

    def distort_normalised(self, xy: np.ndarray) -> np.ndarray:
        """Apply the OpenCV distortion model to normalised image coordinates (N, 2)."""
        if not self.has_distortion:
            return xy
        k1, k2, p1, p2, k3 = self.dist
        x, y = xy[:, 0], xy[:, 1]
        r2 = x * x + y * y
        radial = radial_factor(r2, k1, k2, k3)
        xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
        yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
        return np.stack([xd, yd], axis=1)

    def undistort_normalised(self, xy_distorted: np.ndarray, max_iterations: int = 200,
                             tol: float = 1e-12) -> np.ndarray:
        """Invert :meth:`distort_normalised` by fixed-point iteration (as OpenCV does), (N, 2).

        Iterates until no point moves by more than ``tol`` (normalised units) or
        ``max_iterations``. Points with no solution (beyond the range where the distortion
        polynomial is monotonic) come back NaN.
        """
        if not self.has_distortion:
            return xy_distorted
        k1, k2, p1, p2, k3 = self.dist
        xd, yd = xy_distorted[:, 0], xy_distorted[:, 1]
        x, y = xd.copy(), yd.copy()
        for _ in range(max_iterations):
            r2 = x * x + y * y
            radial = radial_factor(r2, k1, k2, k3)
            dx = 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
            dy = p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
            xn = (xd - dx) / radial
            yn = (yd - dy) / radial
            change = np.nanmax(np.abs(np.concatenate([xn - x, yn - y]))) if len(xn) else 0.0
            x, y = xn, yn
            if not change > tol:
                break
        out = np.stack([x, y], axis=1)
        # Pixels beyond the lens's monotonic range have no ray: the iteration then settles on
        # a point that does not distort back to the pixel. Mark those NaN.
        bad = np.abs(self.distort_normalised(out) - xy_distorted).max(axis=1) > 1e-7
        out[bad] = np.nan
        # Near the corners of a strongly distorted lens the iteration converges slowly and can
        # stop 1e-8 short (a millionth of a pixel that a round trip shows): two Newton steps on
        # the residual, with the 2×2 Jacobian by central differences, finish it — for the points
        # that have a ray only (from a pixel beyond the fold, Newton would find a root on the
        # lens's far, non-monotonic branch).
        good = np.flatnonzero(~bad)
        p, target = out[good], xy_distorted[good]
        h = 1e-7
        for _ in range(2):
            residual = self.distort_normalised(p) - target
            jx = (self.distort_normalised(p + [h, 0.0]) - self.distort_normalised(p - [h, 0.0])) / (2 * h)
            jy = (self.distort_normalised(p + [0.0, h]) - self.distort_normalised(p - [0.0, h])) / (2 * h)
            det = jx[:, 0] * jy[:, 1] - jy[:, 0] * jx[:, 1]
            with np.errstate(invalid="ignore", divide="ignore"):
                step = np.stack([(jy[:, 1] * residual[:, 0] - jy[:, 0] * residual[:, 1]) / det,
                                 (jx[:, 0] * residual[:, 1] - jx[:, 1] * residual[:, 0]) / det], axis=1)
            p = np.where(np.isfinite(step), p - step, p)
        out[good] = p
        return out

    def _normalised_to_pixels(self, xy: np.ndarray) -> np.ndarray:
        K = self.K
        u = K[0, 0] * xy[:, 0] + K[0, 1] * xy[:, 1] + K[0, 2]
        v = K[1, 1] * xy[:, 1] + K[1, 2]
        return np.stack([u, v], axis=1)

    def _pixels_to_normalised(self, uv: np.ndarray) -> np.ndarray:
        K = self.K
        y = (uv[:, 1] - K[1, 2]) / K[1, 1]
        x = (uv[:, 0] - K[0, 2] - K[0, 1] * y) / K[0, 0]
        return np.stack([x, y], axis=1)

    def undistort_pixels(self, uv: ArrayLike) -> np.ndarray:
        """Pixels of the real (distorted) image → pixels of the ideal pinhole image, (..., 2)."""
        p, lead = _as_points(uv, 2)
        if not self.has_distortion:
            return p.reshape(lead + (2,)).copy()
        xy = self.undistort_normalised(self._pixels_to_normalised(p))
        return self._normalised_to_pixels(xy).reshape(lead + (2,))

    def distort_pixels(self, uv_ideal: ArrayLike) -> np.ndarray:
        """Pixels of the ideal pinhole image → pixels of the real (distorted) image, (..., 2)."""
        p, lead = _as_points(uv_ideal, 2)
        if not self.has_distortion:
            return p.reshape(lead + (2,)).copy()
        xy = self.distort_normalised(self._pixels_to_normalised(p))
        return self._normalised_to_pixels(xy).reshape(lead + (2,))

    @cached_property
    def ideal_pixel_grid(self) -> np.ndarray:
        """(H, W, 2) float32: for every real pixel, its ideal (undistorted) pixel coordinates.

        Computed once; lets conics (which live in the ideal image) be evaluated on the real one.
        """
        v, u = np.mgrid[0:self.height, 0:self.width]
        grid = np.stack([u.ravel(), v.ravel()], axis=1).astype(float)
        out = self.undistort_pixels(grid).reshape(self.height, self.width, 2).astype(np.float32)
        out.setflags(write=False)
        return out

    # ------------------------------------------------------------------ back-projection
    def rays(self, uv: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Viewing rays of pixels.

        Returns
        -------
        origin : (3,) ndarray
            The camera centre (m).
        directions : (..., 3) ndarray
            Unit directions in world coordinates, one per pixel.
        """
        p, lead = _as_points(uv, 2)
        # Homogeneous normalised coordinates (x, y, 1), filled in place: this is called for a
        # pixel or two at a time, where every temporary array costs as much as the arithmetic.
        K = self.K
        h = np.empty((len(p), 3))
        h[:, 1] = (p[:, 1] - K[1, 2]) / K[1, 1]
        h[:, 0] = (p[:, 0] - K[0, 2] - K[0, 1] * h[:, 1]) / K[0, 0]
        h[:, 2] = 1.0
        if self.has_distortion:
            h[:, :2] = self.undistort_normalised(h[:, :2])
        d = h @ self.R  # Rᵀ·d for each row
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        return self.centre.copy(), d.reshape(lead + (3,))

    def backproject(self, uv: ArrayLike, z: ArrayLike = 0.0) -> np.ndarray:
        """World point on the horizontal plane ``Z = z`` seen at pixel ``uv``.

        Parameters
        ----------
        uv : (..., 2) array_like, pixels
        z : float or (...) array_like, metres
            Plane height (0 = floor; 1.65 = a head).

        Returns
        -------
        (..., 3) ndarray, metres
            NaN where the ray does not reach the plane in front of the camera.
        """
        origin, d = self.rays(uv)
        d2 = d.reshape(-1, 3)
        zz = float(z) if np.ndim(z) == 0 else np.broadcast_to(np.asarray(z, dtype=float), d.shape[:-1]).reshape(-1)
        with np.errstate(divide="ignore", invalid="ignore"):
            s = (zz - origin[2]) / d2[:, 2]
        bad = ~(s > 0) | (np.abs(d2[:, 2]) < 1e-12)
        out = origin + s[:, None] * d2
        if bad.any():
            out[bad] = np.nan
        return out.reshape(d.shape)

    def image_down_direction(self, uv: ArrayLike) -> np.ndarray:
        """Unit image direction (..., 2) in which a world vertical through each pixel goes down.

        Towards the image bottom for an oblique camera; towards the image of the camera's foot
        point (the nadir) for one looking straight down, where people appear as spokes. NaN for
        pixels whose ray does not reach the floor region in front of the camera.
        """
        p, lead = _as_points(uv, 2)
        top = self.backproject(p, 0.5 * self.centre[2])
        below = top - np.array([0.0, 0.0, 0.05 * abs(self.centre[2]) + 1e-3])
        d = self.project(below) - p
        with np.errstate(invalid="ignore", divide="ignore"):
            d /= np.linalg.norm(d, axis=1, keepdims=True)
        return d.reshape(lead + (2,))

    def in_image(self, uv: ArrayLike, margin: float = 0.0) -> np.ndarray:
        """True where pixel coordinates fall inside the image (shrunk by ``margin`` px), (...)."""
        p, lead = _as_points(uv, 2)
        u, v = p[:, 0], p[:, 1]
        ok = ((u >= -0.5 + margin) & (u < self.width - 0.5 - margin)
              & (v >= -0.5 + margin) & (v < self.height - 0.5 - margin))
        return ok.reshape(lead)

    def sees_standing(self, xy: ArrayLike, height: float) -> np.ndarray:
        """(N,) bool: a person ``height`` metres tall standing at floor points ``xy`` (N, 2), metres,
        has feet and head in front of the camera and inside its image (:meth:`project` gives NaN,
        which no image holds, for points behind it)."""
        xy = np.asarray(xy, dtype=float).reshape(-1, 2)
        feet_and_head = np.concatenate([np.column_stack([xy, np.full(len(xy), z)]) for z in (0.0, height)])
        return self.in_image(self.project(feet_and_head)).reshape(2, -1).all(axis=0)

    # ------------------------------------------------------------------ variants
    def scaled(self, factor: float) -> "Camera":
        """The same camera for an image resized by ``factor`` (e.g. 0.625 for 768→480 px).

        Pixel centres stay at integers: ``u' = factor·(u + 0.5) − 0.5``.
        """
        S = np.array([[factor, 0, 0.5 * factor - 0.5], [0, factor, 0.5 * factor - 0.5], [0, 0, 1]])
        return Camera(self.id, int(round(self.width * factor)), int(round(self.height * factor)),
                      S @ self.K, self.R, self.t, self.dist)

    def moved(self, R: ArrayLike, t: ArrayLike) -> "Camera":
        """Same intrinsics, new pose (a camera on a moving robot)."""
        return Camera(self.id, self.width, self.height, self.K, R, t, self.dist)

    def __repr__(self) -> str:
        c = self.centre
        return (f"Camera({self.id!r}, {self.width}x{self.height}, "
                f"centre=({c[0]:.2f}, {c[1]:.2f}, {c[2]:.2f}) m)")


def intrinsics_from_fov(width: int, height: int, hfov_deg: float) -> np.ndarray:
    """K for square pixels, principal point at the image centre, horizontal FOV in degrees."""
    if not 0 < hfov_deg < 180:
        raise InputError(f"hfov_deg: expected a value in (0, 180), got {hfov_deg}")
    f = (width / 2.0) / np.tan(np.radians(hfov_deg) / 2.0)
    return np.array([[f, 0.0, (width - 1) / 2.0], [0.0, f, (height - 1) / 2.0], [0.0, 0.0, 1.0]])


def look_at_rotation(position: np.ndarray, target: np.ndarray) -> np.ndarray:
    """World → camera rotation for a camera at ``position`` looking at ``target``.

    Camera z = viewing direction, x = z × world-up (image right), y = z × x (image down).
    Looking straight down, world +Y is taken as the image top.
    """
    z = target - position
    n = np.linalg.norm(z)
    if n < 1e-12:
        raise ValueError("camera position and look-at point coincide")
    z = z / n
    x = np.cross(z, _WORLD_UP)
    if np.linalg.norm(x) < 1e-9:
        x = np.cross(z, np.array([0.0, 1.0, 0.0]))
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return np.vstack([x, y, z])
