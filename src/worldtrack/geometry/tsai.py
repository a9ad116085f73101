"""The Tsai camera model (as PETS 2009 ships it) and its conversion to an OpenCV-model Camera.

Tsai's model, in R. Willson's implementation (the one that wrote the PETS ``View_00N.xml``
files)::

    Xc = R·Xw + T,    R = Rz(rz)·Ry(ry)·Rx(rx)                 world → camera
    xu = f·Xc/Zc,     yu = f·Yc/Zc                              undistorted sensor point (mm)
    xu = xd·(1 + κ1·rd²),  yu = yd·(1 + κ1·rd²),  rd² = xd² + yd²   radial lens distortion (mm)
    u  = sx·xd/dpx + cx,   v = yd/dpy + cy                      pixels

The distortion runs the other way round from OpenCV's: Tsai's polynomial maps the *distorted*
(measured) sensor point to the undistorted one, so going from pixels to rays is explicit and
going from the world to pixels needs the root of the cubic ``κ1·rd³ + rd − ru = 0``
(:func:`distorted_radius`). OpenCV's polynomial maps undistorted normalised coordinates to
distorted ones. The two are not the same family of curves, so :func:`tsai_to_camera` fits
OpenCV's ``k1, k2, k3`` to the exact Tsai mapping over the whole image (linear least squares in
pixels) and reports how far apart they remain.

Units: world points and ``T`` in metres (worldtrack's SI rule); the sensor quantities keep
Willson's millimetres and are named so (``focal_mm``, ``dpx_mm``, ``kappa1_per_mm2``). Only
ratios of sensor quantities reach the pixels, so the sensor unit never mixes with the world one.
Pixel coordinates are taken as pixel centres at integers (Willson's frame-buffer coordinates).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike

from worldtrack.geometry.camera import Camera
from worldtrack.geometry.rotation import euler_zyx

#: Below this |κ1|·ru², the cubic is started from its series instead of Cardano's formula,
#: whose two cube roots cancel when κ1 → 0.
_SERIES_LIMIT = 1e-8


def distorted_radius(ru: ArrayLike, kappa1: float) -> np.ndarray:
    """Distorted sensor radius ``rd`` with ``rd·(1 + κ1·rd²) = ru`` (Tsai's model, inverted).

    Solves the cubic ``κ1·rd³ + rd − ru = 0`` in closed form as Willson's
    ``undistorted_to_distorted_sensor_coord`` does (Cardano for one real root; for three real
    roots, possible when κ1 < 0, the smaller positive one), then polishes with two Newton steps.

    Parameters
    ----------
    ru : (...) array_like
        Undistorted radius on the sensor (any length unit; ``kappa1`` in its inverse square).
    kappa1 : float
        Tsai's radial coefficient, 1/unit².

    Returns
    -------
    (...) ndarray
        ``rd``, same unit as ``ru``; NaN where no non-negative root exists (κ1 < 0 and ``ru``
        beyond the lens's largest undistorted radius ``2 / (3·sqrt(−3·κ1))``).
    """
    ru = np.asarray(ru, dtype=float)
    k = float(kappa1)
    if k == 0.0:
        return ru.copy()
    ru_flat = ru.reshape(-1)
    rd = np.empty_like(ru_flat)
    # Depressed cubic rd³ + p·rd + q = 0 with p = 1/κ1, q = −ru/κ1 (Willson: c, d).
    Q = (1.0 / k) / 3.0                       # p/3
    R = ru_flat / (2.0 * k)                   # −q/2
    D = Q ** 3 + R ** 2                       # discriminant
    one = D >= 0
    s = np.sqrt(D[one])
    rd[one] = np.cbrt(R[one] + s) + np.cbrt(R[one] - s)
    three = ~one
    if np.any(three):
        s = np.sqrt(-D[three])
        S = np.cbrt(np.hypot(R[three], s))
        T = np.arctan2(s, R[three]) / 3.0
        rd[three] = -S * np.cos(T) + np.sqrt(3.0) * S * np.sin(T)   # the smaller positive root
    small = np.abs(k) * ru_flat ** 2 < _SERIES_LIMIT
    rd[small] = ru_flat[small] * (1.0 - k * ru_flat[small] ** 2)
    for _ in range(2):                        # Newton: rd ← rd − f/f', f = κ1·rd³ + rd − ru
        rd = rd - (k * rd ** 3 + rd - ru_flat) / (3.0 * k * rd ** 2 + 1.0)
    bad = ~(rd >= 0) | (np.abs(k * rd ** 3 + rd - ru_flat) > 1e-9 * np.maximum(ru_flat, 1.0))
    if k < 0:
        bad |= ru_flat > 2.0 / (3.0 * np.sqrt(-3.0 * k)) * (1 + 1e-12)
    rd[bad] = np.nan
    return rd.reshape(ru.shape)


@dataclass(frozen=True, eq=False)
class TsaiCamera:
    """A camera in Tsai's model (see the module docstring for the equations).

    Parameters
    ----------
    id : str
    width, height : int
        Image size in pixels the calibration is for.
    rx, ry, rz : float, radians
        ``R = Rz(rz)·Ry(ry)·Rx(rx)``, world → camera.
    T : (3,) array_like, metres
        Translation world → camera: ``Xc = R·Xw + T``.
    focal_mm : float
        Effective focal length ``f``, millimetres.
    kappa1_per_mm2 : float
        Radial distortion ``κ1`` on distorted sensor coordinates, 1/mm².
    dpx_mm, dpy_mm : float
        Effective pixel pitch in x (``dx·Ncx/Nfx``) and y, millimetres per pixel.
    sx : float
        Horizontal scale factor (uncertainty of the frame grabber's sampling), unitless.
    cx, cy : float, pixels
        Centre of radial distortion (principal point).

    Examples
    --------
    >>> cam = TsaiCamera("c", 768, 576, rx=2.04, ry=-0.89, rz=-0.43, T=(0.83, -3.18, 35.47),
    ...                  focal_mm=5.555, kappa1_per_mm2=5.11e-3, dpx_mm=5.127e-3,
    ...                  dpy_mm=4.65e-3, sx=1.094, cx=324.2, cy=282.6)
    >>> uv = cam.project([[-4.14, -7.40, 0.0]])
    >>> bool(np.all(np.abs(uv - [[514.8, 232.0]]) < 1.0))
    True
    """

    id: str
    width: int
    height: int
    rx: float
    ry: float
    rz: float
    T: np.ndarray
    focal_mm: float
    kappa1_per_mm2: float
    dpx_mm: float
    dpy_mm: float
    sx: float = 1.0
    cx: float = 0.0
    cy: float = 0.0

    def __post_init__(self) -> None:
        T = np.array(self.T, dtype=float).reshape(3)
        T.setflags(write=False)
        object.__setattr__(self, "T", T)
        for name in ("focal_mm", "dpx_mm", "dpy_mm", "sx"):
            value = float(getattr(self, name))
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"Tsai camera: {name} must be a positive number, got {value}")
        if not all(np.isfinite([self.kappa1_per_mm2, self.cx, self.cy, self.rx, self.ry, self.rz])):
            raise ValueError("Tsai camera: expected finite kappa1, cx, cy and angles")
        if not np.all(np.isfinite(T)):
            raise ValueError("Tsai camera: expected a finite translation T")
        if self.width <= 0 or self.height <= 0:
            raise ValueError(f"Tsai camera: expected a positive image size, got {self.width}x{self.height}")

    # ------------------------------------------------------------------ geometry
    @cached_property
    def R(self) -> np.ndarray:
        """(3, 3) rotation world → camera, ``Rz(rz)·Ry(ry)·Rx(rx)``."""
        return euler_zyx(self.rz, self.ry, self.rx)

    @cached_property
    def centre(self) -> np.ndarray:
        """(3,) camera centre in world coordinates, metres: ``−Rᵀ·T``."""
        return -self.R.T @ self.T

    @property
    def fx(self) -> float:
        """Focal length in pixels along x, ``f·sx/dpx``."""
        return self.focal_mm * self.sx / self.dpx_mm

    @property
    def fy(self) -> float:
        """Focal length in pixels along y, ``f/dpy``."""
        return self.focal_mm / self.dpy_mm

    @cached_property
    def K(self) -> np.ndarray:
        """(3, 3) pinhole intrinsics of the same camera without its lens distortion."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    # ------------------------------------------------------------------ projection
    def project(self, points: ArrayLike) -> np.ndarray:
        """Exact Tsai projection of world points to pixels.

        Parameters
        ----------
        points : (..., 3) array_like, metres

        Returns
        -------
        (..., 2) ndarray, pixels
            NaN for points not in front of the camera or beyond the lens's valid radius.
        """
        p = np.asarray(points, dtype=float)
        lead = p.shape[:-1]
        pc = p.reshape(-1, 3) @ self.R.T + self.T          # Xc = R·Xw + T
        z = pc[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            xu = self.focal_mm * pc[:, 0] / z              # xu = f·Xc/Zc  (mm)
            yu = self.focal_mm * pc[:, 1] / z              # yu = f·Yc/Zc
            ru = np.hypot(xu, yu)
            rd = distorted_radius(ru, self.kappa1_per_mm2)  # rd·(1 + κ1·rd²) = ru
            scale = np.where(ru > 0, rd / ru, 1.0)
        xd, yd = xu * scale, yu * scale
        uv = np.stack([self.sx * xd / self.dpx_mm + self.cx,  # u = sx·xd/dpx + cx
                       yd / self.dpy_mm + self.cy], axis=1)   # v = yd/dpy + cy
        uv[~(z > 1e-9)] = np.nan
        return uv.reshape(lead + (2,))

    def pixels_to_normalised(self, uv: ArrayLike) -> np.ndarray:
        """Pixels → undistorted normalised image coordinates ``(Xc/Zc, Yc/Zc)`` (explicit).

        Parameters
        ----------
        uv : (..., 2) array_like, pixels

        Returns
        -------
        (..., 2) ndarray, unitless
        """
        p = np.asarray(uv, dtype=float)
        xd = (p[..., 0] - self.cx) * self.dpx_mm / self.sx   # sensor mm
        yd = (p[..., 1] - self.cy) * self.dpy_mm
        factor = 1.0 + self.kappa1_per_mm2 * (xd * xd + yd * yd)   # xu = xd·(1 + κ1·rd²)
        return np.stack([xd * factor, yd * factor], axis=-1) / self.focal_mm

    def backproject(self, uv: ArrayLike, z: ArrayLike = 0.0) -> np.ndarray:
        """World point on the plane ``Z = z`` (metres) seen at pixel ``uv``, (..., 2) → (..., 3).

        NaN where the viewing ray does not reach the plane in front of the camera.
        """
        xy = self.pixels_to_normalised(uv)
        lead = xy.shape[:-1]
        d = np.concatenate([xy.reshape(-1, 2), np.ones((xy[..., 0].size, 1))], axis=1) @ self.R  # Rᵀ·d
        zz = np.broadcast_to(np.asarray(z, dtype=float), lead).reshape(-1)
        with np.errstate(divide="ignore", invalid="ignore"):
            s = (zz - self.centre[2]) / d[:, 2]
        out = self.centre + s[:, None] * d
        out[~(s > 0)] = np.nan
        return out.reshape(lead + (3,))


# ---------------------------------------------------------------------------- conversion

@dataclass(frozen=True, eq=False)
class TsaiConversion:
    """A Tsai camera as an OpenCV-model :class:`Camera`, and how well the two agree.

    Attributes
    ----------
    camera : Camera
        Same K (``fx = f·sx/dpx``, ``fy = f/dpy``, principal point ``(cx, cy)``), R and T as the
        Tsai camera; radial distortion ``k1, k2(, k3)`` fitted; no tangential terms.
    radial_terms : int
        Number of OpenCV radial coefficients fitted (1 to 3).
    max_error_px, rms_error_px : float
        Largest and RMS distance (pixels) between where the converted camera and the exact Tsai
        model put the same world point, over every pixel of the image.
    max_error_margin_px : float
        Largest distance over the band of width ``margin`` around the image (where feet just
        outside the picture are back-projected).
    margin : float
        The fit covered the image enlarged by this fraction of its size on each side.
    n_points : int
        Points of the fitting grid.
    monotonic : bool
        Whether the fitted polynomial is invertible (monotonic in radius) over the fitted region;
        if not, back-projection there is ambiguous.
    """

    camera: Camera
    radial_terms: int
    max_error_px: float
    rms_error_px: float
    max_error_margin_px: float
    margin: float
    n_points: int
    monotonic: bool


def _fit_radial(tsai: TsaiCamera, uv: np.ndarray, terms: int) -> np.ndarray:
    """Least-squares OpenCV ``k1..k_terms`` (pixel residuals) on sample pixels uv (N, 2)."""
    xy = tsai.pixels_to_normalised(uv)
    x, y = xy[:, 0], xy[:, 1]
    r2 = x * x + y * y
    # OpenCV: u = fx·x·(1 + k1·r² + k2·r⁴ + k3·r⁶) + cx, likewise v; linear in k.
    powers = np.stack([r2 ** (i + 1) for i in range(terms)], axis=1)
    A = np.concatenate([tsai.fx * x[:, None] * powers, tsai.fy * y[:, None] * powers])
    b = np.concatenate([uv[:, 0] - tsai.cx - tsai.fx * x, uv[:, 1] - tsai.cy - tsai.fy * y])
    return np.linalg.lstsq(A, b, rcond=None)[0]


def _camera_with(tsai: TsaiCamera, k: np.ndarray) -> Camera:
    dist = np.zeros(5)
    dist[[0, 1, 4][:len(k)]] = k
    return Camera(tsai.id, tsai.width, tsai.height, tsai.K, tsai.R, tsai.T, dist)


def conversion_errors(tsai: TsaiCamera, camera: Camera, uv: ArrayLike) -> np.ndarray:
    """Pixel distance between ``camera`` and the exact Tsai model for the rays of pixels ``uv``.

    Each pixel's ray (exact, from Tsai) is cut at 10 m depth and projected with ``camera``; the
    distance to the pixel is the error. (N, 2) → (N,) pixels.
    """
    uv = np.asarray(uv, dtype=float).reshape(-1, 2)
    xy = tsai.pixels_to_normalised(uv)
    pc = np.concatenate([xy, np.ones((len(xy), 1))], axis=1) * 10.0
    world = (pc - tsai.T) @ tsai.R                           # Xw = Rᵀ·(Xc − T)
    return np.linalg.norm(camera.project(world) - uv, axis=1)


def _monotonic(camera: Camera, r_max: float) -> bool:
    """d/dr [r·(1 + k1 r² + k2 r⁴ + k3 r⁶)] > 0 for r in [0, r_max]."""
    k1, k2, _, _, k3 = camera.dist
    r = np.linspace(0.0, r_max, 2000)
    return bool(np.all(1 + 3 * k1 * r ** 2 + 5 * k2 * r ** 4 + 7 * k3 * r ** 6 > 0))


def tsai_to_camera(tsai: TsaiCamera, radial_terms: int | None = None, margin: float = 0.1,
                   grid_step_px: float = 2.0) -> TsaiConversion:
    """Convert a Tsai camera to an OpenCV-model :class:`Camera` by fitting its lens distortion.

    K, R and t carry over exactly (module docstring); only the distortion differs. The OpenCV
    radial coefficients are fitted by linear least squares on pixel residuals over a grid
    (``grid_step_px`` apart) covering the image enlarged by ``margin`` of its size on each side,
    and the agreement is then measured at every pixel of the image and of the margin band.

    Parameters
    ----------
    tsai : TsaiCamera
    radial_terms : {1, 2, 3} or None
        ``None`` chooses: two terms if they agree to 0.01 px over the fitted region, else three
        (PETS View_001 needs three: two leave 0.08 px in the margin).
    margin : float
        Fraction of the image size added on each side of the fitted region (≥ 0).
    grid_step_px : float
        Spacing of the fitting grid, pixels.

    Returns
    -------
    TsaiConversion
    """
    if radial_terms not in (None, 1, 2, 3):
        raise ValueError(f"radial_terms: expected 1, 2, 3 or None, got {radial_terms!r}")
    if not margin >= 0 or not grid_step_px > 0:
        raise ValueError("margin must be >= 0 and grid_step_px > 0")
    W, H = tsai.width, tsai.height
    mu, mv = margin * W, margin * H
    gu = np.arange(-0.5 - mu, W - 0.5 + mu + 1e-9, grid_step_px)
    gv = np.arange(-0.5 - mv, H - 0.5 + mv + 1e-9, grid_step_px)
    U, V = np.meshgrid(gu, gv)
    fit_uv = np.column_stack([U.ravel(), V.ravel()])

    # Every pixel of the image, and the margin band sampled at the same density.
    iu, iv = np.meshgrid(np.arange(W, dtype=float), np.arange(H, dtype=float))
    image_uv = np.column_stack([iu.ravel(), iv.ravel()])
    inside = (fit_uv[:, 0] >= -0.5) & (fit_uv[:, 0] <= W - 0.5) & (fit_uv[:, 1] >= -0.5) & (fit_uv[:, 1] <= H - 0.5)
    band_uv = fit_uv[~inside]
    corners = np.array([[-0.5 - mu, -0.5 - mv], [W - 0.5 + mu, -0.5 - mv],
                        [-0.5 - mu, H - 0.5 + mv], [W - 0.5 + mu, H - 0.5 + mv]])
    r_max = float(np.max(np.linalg.norm(tsai.pixels_to_normalised(corners), axis=1)))

    def attempt(terms: int) -> TsaiConversion:
        k = np.zeros(terms) if tsai.kappa1_per_mm2 == 0 else _fit_radial(tsai, fit_uv, terms)
        cam = _camera_with(tsai, k)
        err = conversion_errors(tsai, cam, image_uv)
        band = conversion_errors(tsai, cam, band_uv) if len(band_uv) else np.zeros(1)
        return TsaiConversion(cam, terms, float(np.max(err)), float(np.sqrt(np.mean(err ** 2))),
                              float(np.max(np.concatenate([band, err]))), float(margin), len(fit_uv),
                              _monotonic(cam, 1.05 * r_max))

    if radial_terms is not None:
        return attempt(radial_terms)
    two = attempt(2)
    if two.max_error_margin_px <= 0.01 and two.monotonic:
        return two
    three = attempt(3)
    return three if three.monotonic and three.max_error_margin_px < two.max_error_margin_px else two
