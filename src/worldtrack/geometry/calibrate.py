"""Camera calibration from world/image point pairs (seed 000, §6.2 and eq. 1).

The 1999 paper puts a 0.3 × 0.3 × 1.1 m box with markers at known places in the room, clicks
the markers in the image, and fits the 3×4 camera matrix of its eq. (1) to ≥ 20 pairs
(30 in the paper) by linear least squares. Here that fit is the *normalised* DLT
(Hartley & Zisserman, Algorithm 4.2 and §7.1), and its camera is then refined by minimising the
reprojection error in pixels (Levenberg–Marquardt), optionally with radial lens distortion — the
paper's wide-angle camera 2 has visible barrel distortion, which the paper did not model and
which is most of its 0.10 m floor error at the image edge.

Points on one plane (a floor-only calibration) do not determine a 3×4 matrix; with known
intrinsics the pose follows from the plane's homography (Zhang 2000, §2.3 and appendix A).

>>> import numpy as np
>>> from worldtrack.geometry.camera import Camera
>>> cam = Camera.look_at("c1", 640, 480, position=(0, -4, 2.5), target=(0, 0, 1), hfov_deg=60)
>>> g = np.stack(np.meshgrid([-1.0, 0.0, 1.0], [-1.0, 0.0, 1.0], [0.0, 1.0]), -1).reshape(-1, 3)
>>> result = calibrate(g, cam.project(g), 640, 480)
>>> result.success, bool(np.allclose(result.camera.centre, [0, -4, 2.5]))
(True, True)
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.optimize
from numpy.typing import ArrayLike

from worldtrack.errors import InputError
from worldtrack.geometry.calibration_checks import (ADVISED_POINTS, MM_SUSPECT_M, PLANE_TOLERANCE, _check_intrinsics,
                                                    _check_pairs, _configuration, _radial_terms)
from worldtrack.geometry.camera import Camera, normalise_projection, radial_factor
from worldtrack.geometry.rotation import rodrigues, rotation_to_rodrigues


@dataclass(frozen=True, eq=False)
class CalibrationResult:
    """What :func:`calibrate` found, and how well it fits.

    Attributes
    ----------
    camera : Camera
        The fitted camera (the DLT camera if the refinement failed).
    residuals : (N, 2) ndarray, pixels
        ``camera.project(world) − image``.
    per_point_error : (N,) ndarray, pixels
        Length of each residual.
    rms : float, pixels
        Root mean square of ``per_point_error``.
    on_floor : (N,) ndarray of bool
        Points with ``|Z| ≤ 1 mm``: the ones the floor errors are measured on.
    floor_errors : (M,) ndarray, metres
        For the M floor points: distance on the floor between the true (X, Y) and the image point
        back-projected to Z = 0 through ``camera`` (the paper's check, §6.2).
    floor_in_centre : (M,) ndarray of bool
        Which floor points are seen in the inner half of the image radius (``r < r_max/2``, ``r``
        measured from the principal point and ``r_max`` the distance from it to the farthest image
        corner); the others are at the edge.
    floor_error_centre, floor_error_edge : float, metres
        Mean floor error of the floor points in the inner and the outer half of the image radius
        (the paper: 0.02 m and 0.10 m for its wide-angle camera). NaN when there are none.
    n_points : int
    warnings : list of str
        Things the user should look at although the fit worked (few points, outliers, …).
    success : bool
        The refinement converged to a camera that sees every point in front of it.
    message : str
        Why ``success`` is what it is, in one line.
    """

    camera: Camera
    residuals: np.ndarray
    per_point_error: np.ndarray
    rms: float
    on_floor: np.ndarray
    floor_errors: np.ndarray
    floor_in_centre: np.ndarray
    floor_error_centre: float
    floor_error_edge: float
    n_points: int
    warnings: list[str] = field(default_factory=list)
    success: bool = True
    message: str = ""

    @property
    def floor_error_mean(self) -> float:
        """Mean of :attr:`floor_errors` in metres (NaN without floor points)."""
        return float(np.mean(self.floor_errors)) if self.floor_errors.size else float("nan")


# ---------------------------------------------------------------------------- linear fits

def _similarity(points: np.ndarray) -> np.ndarray:
    """Hartley's normalising transform: centroid to the origin, mean distance √dim.

    Returns the (dim+1, dim+1) matrix ``T`` with ``T·[p, 1]`` the normalised point.
    """
    dim = points.shape[1]
    c = points.mean(axis=0)
    mean_dist = np.mean(np.linalg.norm(points - c, axis=1))
    s = np.sqrt(dim) / mean_dist
    T = np.eye(dim + 1)
    T[:dim, :dim] *= s
    T[:dim, dim] = -s * c
    return T


def _homogeneous(points: np.ndarray) -> np.ndarray:
    return np.hstack([points, np.ones((len(points), 1))])


def dlt(world: ArrayLike, image: ArrayLike) -> np.ndarray:
    """Normalised direct linear transform: the 3×4 camera matrix from ≥ 6 point pairs.

    Solves ``x_i × (P·X_i) = 0`` (Hartley & Zisserman, Algorithm 4.2 / §7.1) in coordinates
    normalised so that world points have centroid 0 and mean distance √3, image points centroid 0
    and mean distance √2; the right singular vector of the smallest singular value is ``P̃``,
    and ``P = T_image⁻¹ · P̃ · T_world``. This is the paper's least-squares fit of eq. (1), but
    without its ``C34 = 1`` (see :mod:`worldtrack.geometry.camera`) and well conditioned.

    Parameters
    ----------
    world : (N, 3) array_like, metres
        Not all on one plane or line.
    image : (N, 2) array_like, pixels
        Ideal (undistorted) image points; lens distortion is not modelled here.

    Returns
    -------
    (3, 4) ndarray
        ``P`` scaled as :func:`~worldtrack.geometry.camera.normalise_projection` does.

    Raises
    ------
    InputError
        Fewer than 6 points, non-finite values, repeated points, or points on one plane or line.
    """
    W, I, _ = _check_pairs(world, image, None)
    kind, _, _ = _configuration(W, I)
    if kind != "general":
        raise InputError("all world points lie on one plane, which does not determine a 3x4 camera matrix; "
                         "add points off that plane")
    return _normalised_camera(_normalised_dlt(W, I))


def _normalised_camera(P: np.ndarray) -> np.ndarray:
    """:func:`normalise_projection`, with a rank-deficient fit reported as an :class:`InputError`."""
    try:
        return normalise_projection(P)
    except ValueError:
        raise InputError("the points do not determine a camera (the fitted 3x4 matrix has rank < 3); "
                         "check for mislabelled points") from None


def _normalised_dlt(src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    """Normalised DLT for the 3×k matrix ``M`` with ``dst ~ M·[src, 1]``; (N, k−1), (N, 2) → (3, k).

    With 3-D ``src`` this is the camera matrix ``P`` (k = 4), with 2-D ``src`` the plane
    homography ``H`` (k = 3). The fit is made in Hartley-normalised coordinates and mapped back:
    ``M = T_dst⁻¹ · M̃ · T_src``.
    """
    Ts, Td = _similarity(src), _similarity(dst)
    s = _homogeneous(src) @ Ts.T                       # (N, k) normalised source
    d = _homogeneous(dst) @ Td.T                       # (N, 3) normalised image, last = 1
    n, k = s.shape
    A = np.zeros((2 * n, 3 * k))
    # Rows of d × (M s) = 0:  [0ᵀ, −w sᵀ, v sᵀ] and [w sᵀ, 0ᵀ, −u sᵀ]  (H&Z eq. 7.2)
    A[0::2, k:2 * k] = -d[:, 2:3] * s
    A[0::2, 2 * k:] = d[:, 1:2] * s
    A[1::2, :k] = d[:, 2:3] * s
    A[1::2, 2 * k:] = -d[:, 0:1] * s
    _, _, Vt = np.linalg.svd(A, full_matrices=False)      # U (2N, k), not (2N, 2N): memory linear in N
    return np.linalg.solve(Td, Vt[-1].reshape(3, k) @ Ts)


def _nearest_rotation(M: np.ndarray) -> np.ndarray:
    U, _, Vt = np.linalg.svd(M)
    R = U @ Vt
    if np.linalg.det(R) < 0:
        R = U @ np.diag([1.0, 1.0, -1.0]) @ Vt
    return R


def _pose_from_plane(W: np.ndarray, I: np.ndarray, K: np.ndarray, centroid: np.ndarray,
                     basis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World → camera ``R, t`` for points on one plane seen by a camera with intrinsics ``K``.

    With plane coordinates ``(a, b)`` the homography to normalised image coordinates is
    ``H ~ [r1 r2 t]`` (Zhang 2000, eq. 2): ``r1 = λh1, r2 = λh2, r3 = r1 × r2, t = λh3``.
    """
    ab = (W - centroid) @ basis[:2].T                  # (N, 2) metres in the plane
    m = _homogeneous(I) @ np.linalg.inv(K).T           # (N, 3) normalised image coordinates
    H = _normalised_dlt(ab, m[:, :2])
    lam = 2.0 / (np.linalg.norm(H[:, 0]) + np.linalg.norm(H[:, 1]))
    if H[2, 2] * lam < 0:                              # the plane's centroid must be in front
        lam = -lam
    r1, r2 = lam * H[:, 0], lam * H[:, 1]
    R_plane = _nearest_rotation(np.column_stack([r1, r2, np.cross(r1, r2)]))
    t_plane = lam * H[:, 2]
    # X_cam = R_plane · basis · (X − centroid) + t_plane
    R = R_plane @ basis
    return R, t_plane - R @ centroid


def _pose_from_projection(P: np.ndarray, K: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``R, t`` closest to ``P ~ K[R | t]`` for known ``K`` (P normalised, det > 0)."""
    A = np.linalg.solve(K, P)
    scale = np.linalg.svd(A[:, :3], compute_uv=False).mean()
    return _nearest_rotation(A[:, :3]), A[:, 3] / scale


# ---------------------------------------------------------------------------- refinement

def _project(W: np.ndarray, fx: float, fy: float, cx: float, cy: float, R: np.ndarray, t: np.ndarray,
             k: np.ndarray) -> np.ndarray:
    """Pinhole + radial distortion ``(1 + k1 r² + k2 r⁴ + k3 r⁶)``, as :meth:`Camera.project`."""
    pc = W @ R.T + t
    xy = pc[:, :2] / pc[:, 2:3]
    r2 = np.einsum("ij,ij->i", xy, xy)
    radial = radial_factor(r2, k[0], k[1], k[2])
    return np.column_stack([fx * xy[:, 0] * radial + cx, fy * xy[:, 1] * radial + cy])


class _Model:
    """Parameter vector ↔ camera: ``[fx, fy, cx, cy]`` (unless fixed), ``rvec``, ``t``, ``k1…``."""

    def __init__(self, K_fixed: np.ndarray | None, n_radial: int):
        self.K_fixed = K_fixed
        self.n_radial = n_radial

    def pack(self, K: np.ndarray, R: np.ndarray, t: np.ndarray, k: np.ndarray) -> np.ndarray:
        head = [] if self.K_fixed is not None else [K[0, 0], K[1, 1], K[0, 2], K[1, 2]]
        return np.concatenate([head, rotation_to_rodrigues(R), t, k[:self.n_radial]])

    def unpack(self, p: np.ndarray) -> tuple[float, float, float, float, np.ndarray, np.ndarray, np.ndarray]:
        if self.K_fixed is None:
            fx, fy, cx, cy = p[:4]
            p = p[4:]
        else:
            K = self.K_fixed
            fx, fy, cx, cy = K[0, 0], K[1, 1], K[0, 2], K[1, 2]
        k = np.zeros(3)
        k[:self.n_radial] = p[6:6 + self.n_radial]
        return fx, fy, cx, cy, rodrigues(p[:3]), p[3:6], k

    def residuals(self, p: np.ndarray, W: np.ndarray, I: np.ndarray) -> np.ndarray:
        fx, fy, cx, cy, R, t, k = self.unpack(p)
        return (_project(W, fx, fy, cx, cy, R, t, k) - I).ravel()

    def camera(self, p: np.ndarray, camera_id: str, width: int, height: int) -> Camera:
        fx, fy, cx, cy, R, t, k = self.unpack(p)
        K = np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])
        return Camera(camera_id, width, height, K, R, t, [k[0], k[1], 0.0, 0.0, k[2]])


def _refine(model: _Model, x0: np.ndarray, W: np.ndarray, I: np.ndarray) -> scipy.optimize.OptimizeResult:
    n_res, n_par = 2 * len(W), len(x0)
    # Levenberg–Marquardt (MINPACK) for the usual over-determined case; it needs m ≥ n.
    method = "lm" if n_res >= n_par else "trf"
    return scipy.optimize.least_squares(model.residuals, x0, args=(W, I), method=method, x_scale="jac",
                                        xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=200 * (n_par + 1))


# ---------------------------------------------------------------------------- evaluation

def floor_backprojection_errors(camera: Camera, world: ArrayLike, image: ArrayLike) -> np.ndarray:
    """Distance (m) on the floor between true (X, Y) and the image point back-projected to Z = 0.

    Parameters
    ----------
    camera : Camera
    world : (M, 3) array_like, metres
        Points on the floor (their Z is ignored).
    image : (M, 2) array_like, pixels
        Where they are seen (distorted image, as clicked).

    Returns
    -------
    (M,) ndarray, metres
        NaN where the pixel's ray does not reach the floor in front of the camera.
    """
    W = np.asarray(world, dtype=float).reshape(-1, 3)
    ground = camera.backproject(np.asarray(image, dtype=float).reshape(-1, 2), z=0.0)
    return np.hypot(ground[:, 0] - W[:, 0], ground[:, 1] - W[:, 1])


def _centre_edge(camera: Camera, image: np.ndarray, errors: np.ndarray) -> tuple[np.ndarray, float, float]:
    c = camera.K[:2, 2]
    corners = np.array([[-0.5, -0.5], [camera.width - 0.5, -0.5], [-0.5, camera.height - 0.5],
                        [camera.width - 0.5, camera.height - 0.5]])
    r_max = np.max(np.linalg.norm(corners - c, axis=1))
    inner = np.linalg.norm(image - c, axis=1) < r_max / 2
    centre = float(np.mean(errors[inner])) if inner.any() else float("nan")
    edge = float(np.mean(errors[~inner])) if (~inner).any() else float("nan")
    return inner, centre, edge


def _list(names: list[str], idx: np.ndarray, limit: int = 5) -> str:
    shown = ", ".join(names[i] for i in idx[:limit])
    return shown + (f" and {len(idx) - limit} more" if len(idx) > limit else "")


# ---------------------------------------------------------------------------- the fit

def calibrate(world: ArrayLike, image: ArrayLike, width: int, height: int, *, camera_id: str = "cam",
              distortion: bool | int = False, intrinsics: ArrayLike | None = None,
              point_names: Sequence[str] | None = None) -> CalibrationResult:
    """Fit a camera to world/image point pairs: normalised DLT, then reprojection-error refinement.

    Parameters
    ----------
    world : (N, 3) array_like, metres
        Marker positions in the room (Z up, floor Z = 0); N ≥ 6, ≥ 20 advised.
    image : (N, 2) array_like, pixels
        Where each marker is seen (x right, y down, pixel centres at integers).
    width, height : int
        Image size in pixels.
    camera_id : str
        Id of the returned :class:`Camera`.
    distortion : bool or int
        Also fit radial lens distortion, starting from none: ``True`` or 2 fits (k1, k2),
        1 fits k1, 3 fits (k1, k2, k3) and needs ≥ 20 points. Tangential terms stay zero.
    intrinsics : (4,) array_like, optional
        Known ``(fx, fy, cx, cy)`` in pixels, held fixed. Required when all points lie on one
        plane (e.g. only floor points); then the pose comes from the plane's homography.
    point_names : sequence of str, optional
        How error messages and warnings name each point (default ``"point i"``, 0-based);
        the command line passes ``"line n"`` of the CSV file.

    Returns
    -------
    CalibrationResult
        ``success`` is False (with ``message`` saying why) if the refinement did not converge or
        the fitted camera has points behind it; ``camera`` is then the best camera found.

    Raises
    ------
    InputError
        Fewer than 6 points, different numbers of world and image points, NaN or infinity,
        a world point given twice, points on one line, or points on one plane without
        ``intrinsics``.
    """
    W, I, names = _check_pairs(world, image, point_names)
    if int(width) != width or int(height) != height or width <= 0 or height <= 0:
        raise InputError(f"image size: expected positive integers width x height in pixels, got {width}x{height}")
    width, height = int(width), int(height)
    K_fixed = _check_intrinsics(intrinsics)
    n_radial = _radial_terms(distortion, len(W))
    kind, centroid, basis = _configuration(W, I)
    warnings: list[str] = []

    if kind != "general" and K_fixed is None:
        if kind == "horizontal":
            raise InputError(f"all points lie on the plane Z = {np.mean(W[:, 2]):.3f} m; give --intrinsics "
                             "fx,fy,cx,cy or add points at other heights (one plane does not determine "
                             "the intrinsics)")
        n = basis[2] * np.sign(basis[2][np.argmax(np.abs(basis[2]))])
        raise InputError(f"all points lie on one plane (normal ({n[0]:.2f}, {n[1]:.2f}, {n[2]:.2f})); give "
                         "--intrinsics fx,fy,cx,cy or add points off that plane (one plane does not determine "
                         "the intrinsics)")

    # Linear start: the paper's fit (normalised), or the plane's homography with known K.
    if kind == "general":
        P = _normalised_camera(_normalised_dlt(W, I))
        linear = Camera.from_projection(camera_id, width, height, P)
        if K_fixed is None:
            K0, (R0, t0) = linear.K.copy(), (linear.R, linear.t)
            K0[0, 1] = 0.0                                  # refined without skew
        else:
            K0, (R0, t0) = K_fixed, _pose_from_projection(P, K_fixed)
    else:
        K0 = K_fixed
        R0, t0 = _pose_from_plane(W, I, K_fixed, centroid, basis)
        linear = Camera(camera_id, width, height, K0, R0, t0)

    # Non-linear refinement of the reprojection error (pixels).
    model = _Model(K_fixed, n_radial)
    x0 = model.pack(K0, R0, t0, np.zeros(3))
    fit = _refine(model, x0, W, I)
    success = bool(fit.success)
    message = "" if success else f"the refinement did not converge ({fit.message})"
    camera = linear
    try:
        camera = model.camera(fit.x, camera_id, width, height)
    except ValueError as e:
        success, message = False, f"the refinement left an invalid camera ({e}); showing the linear fit"

    uv, depth = camera.project(W, return_depth=True)
    residuals = uv - I
    per_point = np.linalg.norm(residuals, axis=1)
    rms = float(np.sqrt(np.mean(per_point ** 2)))
    behind = np.flatnonzero(~(depth > 0))
    if behind.size == len(W):
        success = False
        message = ("every point is behind the fitted camera: the world coordinates look mirrored "
                   "(expected right-handed axes with Z up)")
    elif behind.size:
        success = False
        message = (f"{behind.size} points are behind the fitted camera ({_list(names, behind)}): "
                   "check the signs of their coordinates")
    elif success:
        message = f"converged: RMS reprojection error {rms:.3g} px over {len(W)} points"

    on_floor = np.abs(W[:, 2]) <= PLANE_TOLERANCE
    floor = floor_backprojection_errors(camera, W[on_floor], I[on_floor])
    in_centre, centre, edge = _centre_edge(camera, I[on_floor], floor)

    extent = float(np.ptp(W, axis=0).max())
    if extent > MM_SUSPECT_M:
        warnings.append(f"the world points span {extent:.0f} m: worldtrack expects metres; if they are "
                        "millimetres, divide them by 1000 (a fit in millimetres gives floor errors in millimetres)")
    if camera.centre[2] <= 0:
        warnings.append(f"the camera centre is at Z = {camera.centre[2]:.3f} m, not above the floor: "
                        "expected world Z up with the floor at Z = 0")
    if len(W) < ADVISED_POINTS:
        warnings.append(f"only {len(W)} points: the paper advises ≥ {ADVISED_POINTS}, spread over the image "
                        "and over heights")
    outside = np.flatnonzero(~camera.in_image(I))
    if outside.size:
        warnings.append(f"{outside.size} image points lie outside the {width}x{height} image "
                        f"({_list(names, outside)}): check the image size")
    if not on_floor.any():
        warnings.append("no points on the floor (Z = 0): the floor back-projection error is not measured")
    if rms > 2.0 and n_radial == 0:
        warnings.append(f"RMS {rms:.2f} px is large for clicked points: for a wide-angle lens fit its "
                        "distortion (--distortion); otherwise check the points with the largest errors")
    median = float(np.median(per_point))
    worst = int(np.argmax(per_point))
    if per_point[worst] > max(5 * median, 2.0):
        warnings.append(f"{names[worst]} has error {per_point[worst]:.2f} px (median {median:.2f} px): "
                        "check its coordinates")

    return CalibrationResult(camera=camera, residuals=residuals, per_point_error=per_point, rms=rms,
                             on_floor=on_floor, floor_errors=floor, floor_in_centre=in_centre,
                             floor_error_centre=centre,
                             floor_error_edge=edge, n_points=len(W), warnings=warnings,
                             success=success, message=message)
