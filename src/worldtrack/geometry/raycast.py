"""Ray intersections with the analytic shapes of a scene, vectorised over rays.

Every function takes a ray origin ``o`` (3,) or (N, 3) and unit directions ``d`` (N, 3), and
returns the ray parameter ``s`` (N,) of the nearest hit in front of the origin (``s > 0``, metres
along the ray), or ``inf`` where the ray misses. The hit point is ``o + s·d``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

_EPS = 1e-12


def ray_ellipsoid(o: ArrayLike, d: np.ndarray, centre: ArrayLike, radii: ArrayLike,
                  R: np.ndarray | None = None) -> np.ndarray:
    """Nearest hit of rays with an ellipsoid ``Σ ((p − c)·axis_k / r_k)² = 1``.

    Parameters
    ----------
    o : (3,) or (N, 3)
    d : (N, 3) unit directions
    centre : (3,)
    radii : (3,) semi-axes, metres
    R : (3, 3), optional
        Rows are the ellipsoid's axes in world coordinates (identity: axis-aligned).
    """
    c = np.asarray(centre, dtype=float)
    r = np.asarray(radii, dtype=float)
    oc = np.asarray(o, dtype=float) - c
    if R is not None:
        oc = oc @ R.T
        d = d @ R.T
    oc = np.broadcast_to(oc / r, d.shape)
    dd = d / r
    a = np.einsum("ij,ij->i", dd, dd)
    b = np.einsum("ij,ij->i", oc, dd)
    cc = np.einsum("ij,ij->i", oc, oc) - 1.0
    disc = b * b - a * cc
    hit = disc >= 0
    sq = np.sqrt(np.where(hit, disc, 0.0))
    s0 = (-b - sq) / a
    s1 = (-b + sq) / a
    s = np.where(s0 > 0, s0, s1)
    return np.where(hit & (s > 0), s, np.inf)


def ray_box(o: ArrayLike, d: np.ndarray, centre: ArrayLike, size: ArrayLike, yaw: float = 0.0) -> np.ndarray:
    """Nearest hit of rays with a box standing upright and turned by ``yaw`` about Z (slab method).

    Parameters
    ----------
    centre : (3,) box centre, metres
    size : (3,) full extents along the box's own x, y and Z, metres
    yaw : float, radians
    """
    c, s_ = np.cos(yaw), np.sin(yaw)
    Rt = np.array([[c, s_, 0.0], [-s_, c, 0.0], [0.0, 0.0, 1.0]])  # world → box
    ol = (np.asarray(o, dtype=float) - np.asarray(centre, dtype=float)) @ Rt.T
    dl = d @ Rt.T
    half = np.asarray(size, dtype=float) / 2.0
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / np.where(np.abs(dl) < _EPS, _EPS, dl)
        t1 = (-half - ol) * inv
        t2 = (half - ol) * inv
    tnear = np.max(np.minimum(t1, t2), axis=-1)
    tfar = np.min(np.maximum(t1, t2), axis=-1)
    hit = (tnear <= tfar) & (tfar > 0)
    s = np.where(tnear > 0, tnear, tfar)
    return np.where(hit, s, np.inf)


def ray_quad(o: ArrayLike, d: np.ndarray, corners: ArrayLike) -> np.ndarray:
    """Hit of rays with a flat convex quadrilateral given by its 4 corners in order (4, 3)."""
    q = np.asarray(corners, dtype=float)
    n = np.cross(q[1] - q[0], q[2] - q[0])
    n /= np.linalg.norm(n)
    o = np.asarray(o, dtype=float)
    denom = d @ n
    with np.errstate(divide="ignore", invalid="ignore"):
        s = ((q[0] - o) @ n if o.ndim == 1 else np.einsum("ij,j->i", q[0] - o, n)) / denom
    s = np.where(np.isfinite(s), s, np.inf)  # rays parallel to the patch never hit it
    p = o + np.where(np.isfinite(s), s, 0.0)[:, None] * d
    inside = np.ones(len(d), dtype=bool)
    for k in range(4):
        edge = q[(k + 1) % 4] - q[k]
        inside &= np.cross(edge, p - q[k]) @ n >= -1e-12
    ok = inside & (np.abs(denom) > _EPS) & (s > 0)
    return np.where(ok, s, np.inf)


def ray_plane_z(o: ArrayLike, d: np.ndarray, z: float = 0.0) -> np.ndarray:
    """Hit of rays with the horizontal plane ``Z = z`` (the floor for z = 0)."""
    o = np.asarray(o, dtype=float)
    oz = o[2] if o.ndim == 1 else o[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (z - oz) / d[:, 2]
    return np.where((np.abs(d[:, 2]) > _EPS) & (s > 0), s, np.inf)


def ray_capsule(o: ArrayLike, d: np.ndarray, a: ArrayLike, b: ArrayLike, radius: float) -> np.ndarray:
    """Nearest hit of rays with a capsule: all points within ``radius`` of the segment ``a``–``b``.

    The capsule is the union of a cylinder around the segment and two spheres at its ends, so the
    nearest hit is the smallest positive parameter among the cylinder's side (only where the hit
    lies between the end planes) and the two end spheres. Rays parallel to the axis miss the side
    and hit a cap.

    Parameters
    ----------
    o : (3,) or (N, 3)
    d : (N, 3) unit directions
    a, b : (3,) segment end points, metres
    radius : float, metres
    """
    o = np.asarray(o, dtype=float)
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    d = np.asarray(d, dtype=float)
    oa = np.broadcast_to(o - a, d.shape)
    ba = b - a
    baba = float(ba @ ba)
    bard = d @ ba
    baoa = oa @ ba
    rdoa = np.einsum("ij,ij->i", d, oa)
    oaoa = np.einsum("ij,ij->i", oa, oa)
    # Side: |(oa + s·d) − ((oa + s·d)·ba / |ba|²)·ba|² = r², multiplied through by |ba|².
    qa = baba - bard * bard
    qb = baba * rdoa - baoa * bard
    qc = baba * oaoa - baoa * baoa - radius * radius * baba
    disc = qb * qb - qa * qc
    side_ok = (qa > _EPS * max(baba, _EPS)) & (disc >= 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        s_side = (-qb - np.sqrt(np.where(side_ok, disc, 0.0))) / np.where(side_ok, qa, 1.0)
    y = baoa + s_side * bard
    s_side = np.where(side_ok & (s_side > 0) & (y > 0) & (y < baba), s_side, np.inf)
    s_a = ray_ellipsoid(o, d, a, (radius, radius, radius))
    s_b = ray_ellipsoid(o, d, b, (radius, radius, radius))
    return np.minimum(s_side, np.minimum(s_a, s_b))
