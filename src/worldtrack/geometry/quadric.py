"""The image of an ellipsoid: conics, their parameters, bounding boxes and filled masks.

A person is the paper's ellipsoid (seed 000, eq. 2)::

    (X − Xp)²/Ra² + (Y − Yp)²/Ra² + (Z − Rb)²/Rb² = 1,   Ra = width/2, Rb = height/2.

Its outline in the (ideal, undistorted) image is a conic. Two equivalent computations are here:

* the modern one, the dual conic ``C* = P·Q*·Pᵀ`` of the dual quadric ``Q*``
  (Hartley & Zisserman, Result 8.9), used everywhere;
* the paper's appendix, :func:`kato_conic_coefficients`, kept as the reference it is tested against.

Sign convention: point conics ``C`` are scaled so that ``xᵀ·C·x < 0`` inside the ellipse
(``x = (u, v, 1)``). All functions are vectorised over a leading axis of N ellipsoids.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike


def ellipsoid_dual_quadric(centres: ArrayLike, radii: ArrayLike) -> np.ndarray:
    """Dual quadrics of axis-aligned ellipsoids.

    Parameters
    ----------
    centres : (N, 3) array_like, metres
    radii : (N, 3) array_like, metres
        Semi-axes along X, Y, Z.

    Returns
    -------
    (N, 4, 4) ndarray
        ``Q* = T·diag(a², b², c², −1)·Tᵀ`` with ``T`` the translation to the centre.
    """
    c = np.atleast_2d(np.asarray(centres, dtype=float))
    r = np.atleast_2d(np.asarray(radii, dtype=float))
    n = max(len(c), len(r))
    c = np.broadcast_to(c, (n, 3))
    r2 = np.broadcast_to(r, (n, 3)) ** 2
    Q = np.zeros((n, 4, 4))
    # T diag(r²,-1) Tᵀ written out: top-left diag(r²) − c cᵀ, top-right −c, bottom-right −1.
    Q[:, :3, :3] = -c[:, :, None] * c[:, None, :]
    Q[:, [0, 1, 2], [0, 1, 2]] += r2
    Q[:, :3, 3] = -c
    Q[:, 3, :3] = -c
    Q[:, 3, 3] = -1.0
    return Q


def person_ellipsoid(xy: ArrayLike, height: ArrayLike, width: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Centres and radii of the paper's standing-person ellipsoids.

    Parameters
    ----------
    xy : (N, 2) array_like, metres
    height, width : (N,) or scalar, metres

    Returns
    -------
    centres : (N, 3) ndarray — ``(Xp, Yp, Rb)``
    radii : (N, 3) ndarray — ``(Ra, Ra, Rb)``
    """
    xy = np.atleast_2d(np.asarray(xy, dtype=float))
    n = len(xy)
    rb = np.broadcast_to(np.asarray(height, dtype=float) / 2.0, (n,))
    ra = np.broadcast_to(np.asarray(width, dtype=float) / 2.0, (n,))
    centres = np.column_stack([xy[:, 0], xy[:, 1], rb])
    radii = np.column_stack([ra, ra, rb])
    return centres, radii


def ellipsoid_dual_conics(P: ArrayLike, centres: ArrayLike, radii: ArrayLike) -> np.ndarray:
    """Dual conics ``C* = P·Q*·Pᵀ`` (N, 3, 3) of the ellipsoids' outlines in the ideal image."""
    P = np.asarray(P, dtype=float)
    Q = ellipsoid_dual_quadric(centres, radii)
    return P @ Q @ P.T


def point_conics(dual: np.ndarray, inside_point: ArrayLike) -> np.ndarray:
    """Point conics from dual conics, scaled so that ``inside_point`` evaluates negative.

    Parameters
    ----------
    dual : (N, 3, 3) ndarray
    inside_point : (N, 2) array_like
        A pixel known to be inside each outline (e.g. the projected ellipsoid centre).

    Returns
    -------
    (N, 3, 3) ndarray
        The adjugate of ``dual`` (= its inverse up to scale, defined even when near-singular),
        normalised to unit Frobenius norm and signed.
    """
    C = _adjugate3(dual)
    C /= np.linalg.norm(C, axis=(1, 2), keepdims=True)
    p = np.asarray(inside_point, dtype=float).reshape(-1, 2)
    x = np.column_stack([p, np.ones(len(p))])
    val = np.einsum("ni,nij,nj->n", x, C, x)
    C *= np.where(val > 0, -1.0, 1.0)[:, None, None]
    return C


def ellipsoid_conics(P: ArrayLike, centres: ArrayLike, radii: ArrayLike) -> np.ndarray:
    """Point conics (N, 3, 3) of ellipsoids in the ideal image; negative inside.

    The ellipsoids must lie in front of the camera (the outline is then an ellipse).
    """
    P = np.asarray(P, dtype=float)
    c = np.atleast_2d(np.asarray(centres, dtype=float))
    dual = ellipsoid_dual_conics(P, c, radii)
    h = np.column_stack([c, np.ones(len(c))]) @ P.T
    centre_px = h[:, :2] / h[:, 2:3]
    return point_conics(dual, centre_px)


def kato_conic_coefficients(C: ArrayLike, xy: ArrayLike, Ra: ArrayLike, Rb: ArrayLike) -> np.ndarray:
    """The paper's appendix: outline ``K1 x² + K2 y² + K3 xy + K4 x + K5 y + K6 = 0``.

    Reference implementation of seed 000's appendix, kept to test :func:`ellipsoid_conics`.
    The derivation holds for any scale of ``C`` (the paper's ``C34 = 1`` is only the least-squares
    normalisation), provided ``C[:, :3]`` is invertible.

    Parameters
    ----------
    C : (3, 4) array_like
        Camera matrix.
    xy : (N, 2) array_like
        Person positions ``(Xp, Yp)``, metres.
    Ra, Rb : (N,) or scalar
        Half width and half height, metres.

    Returns
    -------
    (N, 6) ndarray
        ``K1 … K6``; the discriminant ``D/4`` is positive inside the outline.
    """
    C4 = np.vstack([np.asarray(C, dtype=float), [0.0, 0.0, 0.0, 1.0]])
    D = np.linalg.inv(C4)
    xy = np.atleast_2d(np.asarray(xy, dtype=float))
    n = len(xy)
    Ra = np.broadcast_to(np.asarray(Ra, dtype=float), (n,))
    Rb = np.broadcast_to(np.asarray(Rb, dtype=float), (n,))
    ra2, rb2 = Ra ** 2, Rb ** 2
    (D11, D12, D13, D14), (D21, D22, D23, D24), (D31, D32, D33, D34) = D[:3]
    a1 = rb2 * (D11 ** 2 + D21 ** 2) + ra2 * D31 ** 2
    a2 = rb2 * (D12 ** 2 + D22 ** 2) + ra2 * D32 ** 2
    a3 = 2 * rb2 * (D11 * D12 + D21 * D22) + 2 * ra2 * D31 * D32
    a4 = 2 * rb2 * (D11 * D13 + D21 * D23) + 2 * ra2 * D31 * D33
    a5 = 2 * rb2 * (D12 * D13 + D22 * D23) + 2 * ra2 * D32 * D33
    a6 = rb2 * (D13 ** 2 + D23 ** 2) + ra2 * D33 ** 2
    ex, ey, ez = D14 - xy[:, 0], D24 - xy[:, 1], D34 - Rb
    b1 = rb2 * D11 * ex + rb2 * D21 * ey + ra2 * D31 * ez
    b2 = rb2 * D12 * ex + rb2 * D22 * ey + ra2 * D32 * ez
    b3 = rb2 * D13 * ex + rb2 * D23 * ey + ra2 * D33 * ez
    c1 = rb2 * ex ** 2 + rb2 * ey ** 2 + ra2 * ez ** 2 - ra2 * rb2
    return np.column_stack([
        b1 ** 2 - a1 * c1,
        b2 ** 2 - a2 * c1,
        2 * b1 * b2 - a3 * c1,
        2 * b1 * b3 - a4 * c1,
        2 * b2 * b3 - a5 * c1,
        b3 ** 2 - a6 * c1,
    ])


def conic_matrix(coefficients: ArrayLike) -> np.ndarray:
    """(N, 6) coefficients ``K1 … K6`` → (N, 3, 3) symmetric conic matrices."""
    k = np.atleast_2d(np.asarray(coefficients, dtype=float))
    M = np.empty((len(k), 3, 3))
    M[:, 0, 0], M[:, 1, 1], M[:, 2, 2] = k[:, 0], k[:, 1], k[:, 5]
    M[:, 0, 1] = M[:, 1, 0] = k[:, 2] / 2
    M[:, 0, 2] = M[:, 2, 0] = k[:, 3] / 2
    M[:, 1, 2] = M[:, 2, 1] = k[:, 4] / 2
    return M


def ellipse_parameters(C: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centre, semi-axes and angle of ellipses given as point conics (negative inside).

    Parameters
    ----------
    C : (N, 3, 3) array_like

    Returns
    -------
    centre : (N, 2) ndarray, pixels
    semi_axes : (N, 2) ndarray, pixels — major first; NaN if the conic is not a real ellipse
    angle : (N,) ndarray, radians — of the major axis from the image x axis (towards y)
    """
    C = np.asarray(C, dtype=float).reshape(-1, 3, 3)
    A, b = C[:, :2, :2], C[:, :2, 2]
    centre = -np.linalg.solve(A, b[:, :, None])[:, :, 0]
    k = C[:, 2, 2] + np.einsum("ni,ni->n", b, centre)  # conic value at the centre
    lam, vec = np.linalg.eigh(A)  # ascending eigenvalues: the smaller one is the major axis
    with np.errstate(invalid="ignore", divide="ignore"):
        axes = np.sqrt(-k[:, None] / lam)
    valid = (lam[:, 0] > 0) & (k < 0)
    axes[~valid] = np.nan
    angle = np.arctan2(vec[:, 1, 0], vec[:, 0, 0])
    return centre, axes, angle


def dual_conic_bbox(dual: ArrayLike) -> np.ndarray:
    """Tight bounding boxes of ellipses given as dual conics.

    A line ``l`` touches the conic when ``lᵀ·C*·l = 0``; for the vertical line ``u = x``,
    ``l = (1, 0, −x)`` gives ``C*33·x² − 2·C*13·x + C*11 = 0`` (likewise for horizontal lines).

    Returns
    -------
    (N, 4) ndarray
        ``(u_min, u_max, v_min, v_max)`` in ideal-image pixels; NaN where not an ellipse.
    """
    Cd = np.asarray(dual, dtype=float).reshape(-1, 3, 3)
    c33 = Cd[:, 2, 2]
    out = np.empty((len(Cd), 4))
    for axis in (0, 1):
        cii, ci3 = Cd[:, axis, axis], Cd[:, axis, 2]
        with np.errstate(invalid="ignore", divide="ignore"):
            root = np.sqrt(ci3 ** 2 - cii * c33)
            lo, hi = (ci3 - root) / c33, (ci3 + root) / c33
        out[:, 2 * axis] = np.minimum(lo, hi)
        out[:, 2 * axis + 1] = np.maximum(lo, hi)
    return out


def conic_values(C: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Evaluate one point conic (3, 3) at pixel coordinates ``u, v`` (any equal shapes)."""
    return (C[0, 0] * u * u + 2 * C[0, 1] * u * v + C[1, 1] * v * v
            + 2 * C[0, 2] * u + 2 * C[1, 2] * v + C[2, 2])


def ellipse_mask(C: np.ndarray, shape: tuple[int, int], box: tuple[int, int, int, int] | None = None,
                 ideal_grid: np.ndarray | None = None) -> np.ndarray:
    """Filled ellipse as a boolean mask, evaluated at pixel centres.

    Parameters
    ----------
    C : (3, 3) ndarray
        Point conic, negative inside.
    shape : (H, W)
        Size of the full image.
    box : (u0, u1, v0, v1), optional
        Integer pixel range to evaluate (inclusive starts, exclusive ends); the returned mask has
        the box's size. Default: the whole image.
    ideal_grid : (H, W, 2) ndarray, optional
        :attr:`Camera.ideal_pixel_grid` for a distorted camera: the conic is then evaluated at each
        real pixel's undistorted position, giving the exact silhouette in the real image.

    Returns
    -------
    (v1 − v0, u1 − u0) bool ndarray
    """
    H, W = shape
    u0, u1, v0, v1 = box if box is not None else (0, W, 0, H)
    if ideal_grid is None:
        v, u = np.mgrid[v0:v1, u0:u1].astype(float)
    else:
        g = ideal_grid[v0:v1, u0:u1]
        u, v = g[..., 0].astype(float), g[..., 1].astype(float)
    return conic_values(C, u, v) < 0


def _adjugate3(M: np.ndarray) -> np.ndarray:
    """Adjugate of symmetric or general 3×3 matrices, (N, 3, 3)."""
    a = M
    out = np.empty_like(a)
    out[:, 0, 0] = a[:, 1, 1] * a[:, 2, 2] - a[:, 1, 2] * a[:, 2, 1]
    out[:, 0, 1] = a[:, 0, 2] * a[:, 2, 1] - a[:, 0, 1] * a[:, 2, 2]
    out[:, 0, 2] = a[:, 0, 1] * a[:, 1, 2] - a[:, 0, 2] * a[:, 1, 1]
    out[:, 1, 0] = a[:, 1, 2] * a[:, 2, 0] - a[:, 1, 0] * a[:, 2, 2]
    out[:, 1, 1] = a[:, 0, 0] * a[:, 2, 2] - a[:, 0, 2] * a[:, 2, 0]
    out[:, 1, 2] = a[:, 0, 2] * a[:, 1, 0] - a[:, 0, 0] * a[:, 1, 2]
    out[:, 2, 0] = a[:, 1, 0] * a[:, 2, 1] - a[:, 1, 1] * a[:, 2, 0]
    out[:, 2, 1] = a[:, 0, 1] * a[:, 2, 0] - a[:, 0, 0] * a[:, 2, 1]
    out[:, 2, 2] = a[:, 0, 0] * a[:, 1, 1] - a[:, 0, 1] * a[:, 1, 0]
    return out
