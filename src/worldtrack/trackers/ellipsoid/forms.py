"""The image of a person's ellipsoid: its ellipse, the ellipse grown by the ring, their pixels.

Paper 000's appendix: the outline of an ellipsoid seen by a camera is a conic; in modern form
the dual conic ``C* = P·Q*·Pᵀ`` of the ellipsoid's dual quadric ``Q*``. Its point conic, scaled
so that the inside is ``< 1``, is kept as a *normal form* of 5 numbers ``(cx, cy, a11, a12,
a22)``: a point (u, v) of the ideal (undistorted) image is inside when
``a11·du² + 2·a12·du·dv + a22·dv² < 1`` with ``du = u − cx``, ``dv = v − cy``.

The ring of an ellipse with semi-axes (a, b) is the ellipse (a + r, b + r) — the dilation of the
ellipse by r pixels up to a sliver at the ends of the major axis. With lens distortion each real
pixel is tested at its ideal position (``CameraArgs.grid``), so silhouettes are exact.

:func:`ellipse_forms` is compiled; its readable reference is
:func:`worldtrack.geometry.quadric.ellipsoid_conics` with
:func:`~worldtrack.geometry.quadric.ellipse_parameters` (the tests draw both and compare).

>>> import numpy as np
>>> from worldtrack.geometry.camera import Camera
>>> from worldtrack.trackers.ellipsoid.args import DrawArgs, camera_args
>>> cam = camera_args(Camera.look_at("c", 160, 120, [0.0, -4.0, 2.6], [0.0, 0.0, 0.8], hfov_deg=60.0), 5.0)
>>> f = person_forms(cam, np.array([[0.0, 0.0]]), np.array([1.65]), np.array([0.4]), DrawArgs(0.1, 0.0))
>>> bool(f.valid[0]), int(ellipse_crop(f.inner[0], f.box[0], cam.grid, cam.has_dist).sum())
(True, 484)
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from worldtrack.geometry._kernels import ideal_to_real_pixel
from worldtrack.trackers.ellipsoid.args import CameraArgs, DrawArgs, Forms

#: Samples on an ellipse's outline used to bound it after lens distortion.
_OUTLINE_SAMPLES = 24


@njit(cache=True)
def ellipse_forms(cam, xy, heights, widths, draw):
    """Normal forms and bounding boxes of standing-person ellipsoids in one camera.

    Compiled; longer than most functions because it is one loop over people that the compiler
    keeps in registers (conic, eigen-decomposition, ring, box).

    Parameters
    ----------
    cam : CameraArgs — ``P``, and ``K``, ``dist``, ``has_dist`` for boxes under lens
        distortion, the image size, ``ring_px``
    xy : (N, 2) — floor positions, metres
    heights, widths : (N,) — ellipsoid sizes (2·Rb, 2·Ra), metres
    draw : DrawArgs — ``min_depth`` (an ellipsoid whose nearest point is closer than this to the
        image plane is not drawn, m) and ``ring_fraction`` (if > 0, the ring is at most this
        fraction of the ellipse's semi-minor axis: a far, small person gets a narrow ring instead
        of one wider than itself)

    Returns
    -------
    inner : (N, 5) — normal forms of the ellipses
    ring : (N, 5) — normal forms of the ring-expanded ellipses
    box : (N, 4) int64 — ``u0, u1, v0, v1`` (end exclusive) of the ring ellipse in the real image,
        clipped to the image; empty (u0 ≥ u1) when not visible
    valid : (N,) bool — ellipsoid fully in front of the camera and outline an ellipse
    """
    P = cam.P
    ring_px = cam.ring_px
    min_depth = draw.min_depth
    ring_fraction = draw.ring_fraction
    width = cam.width
    height = cam.height
    n = xy.shape[0]
    inner = np.zeros((n, 5))
    ring = np.zeros((n, 5))
    box = np.zeros((n, 4), dtype=np.int64)
    valid = np.zeros(n, dtype=np.bool_)
    Q = np.zeros((4, 4))
    for i in range(n):
        ra = 0.5 * widths[i]
        rb = 0.5 * heights[i]
        c0, c1, c2 = xy[i, 0], xy[i, 1], rb
        # Nearest depth of the ellipsoid: depth(centre) − ‖diag(r)·axis‖ (axis = P[2, :3], unit).
        dc = P[2, 0] * c0 + P[2, 1] * c1 + P[2, 2] * c2 + P[2, 3]
        ext = math.sqrt((ra * P[2, 0]) ** 2 + (ra * P[2, 1]) ** 2 + (rb * P[2, 2]) ** 2)
        if dc - ext < min_depth:
            continue
        # Dual quadric Q* = T·diag(ra², ra², rb², −1)·Tᵀ.
        cc = (c0, c1, c2)
        rr = (ra * ra, ra * ra, rb * rb)
        for a in range(3):
            for b in range(3):
                Q[a, b] = -cc[a] * cc[b]
            Q[a, a] += rr[a]
            Q[a, 3] = -cc[a]
            Q[3, a] = -cc[a]
        Q[3, 3] = -1.0
        # Dual conic C* = P·Q*·Pᵀ.
        PQ = P @ Q
        D = PQ @ P.T
        # Point conic = adjugate of C*; only the 2×2 block and the linear terms are needed.
        A11 = D[1, 1] * D[2, 2] - D[1, 2] * D[2, 1]
        A12 = D[0, 2] * D[2, 1] - D[0, 1] * D[2, 2]
        A22 = D[0, 0] * D[2, 2] - D[0, 2] * D[2, 0]
        B1 = D[0, 1] * D[1, 2] - D[0, 2] * D[1, 1]
        B2 = D[0, 2] * D[1, 0] - D[0, 0] * D[1, 2]
        F = D[0, 0] * D[1, 1] - D[0, 1] * D[1, 0]
        det = A11 * A22 - A12 * A12
        if det <= 0.0:
            continue
        # Centre of the conic and its value there.
        cu = -(A22 * B1 - A12 * B2) / det
        cv = -(-A12 * B1 + A11 * B2) / det
        k = F + B1 * cu + B2 * cv
        # Inside ⇔ (x−c)ᵀA(x−c) < −k: an ellipse needs A and −k of the same sign.
        if k * A11 >= 0.0:
            continue
        s = -1.0 / k
        a11, a12, a22 = A11 * s, A12 * s, A22 * s
        # Semi-axes from the eigenvalues of the normal form.
        tr = a11 + a22
        dd = math.sqrt(max((a11 - a22) ** 2 / 4.0 + a12 * a12, 0.0))
        l1 = tr / 2.0 - dd  # smaller eigenvalue → major axis
        l2 = tr / 2.0 + dd
        if l1 <= 0.0:
            continue
        ax1 = 1.0 / math.sqrt(l1)
        ax2 = 1.0 / math.sqrt(l2)
        # Eigenvector of l1: (l1 − a22, a12) or (a12, l1 − a11), whichever is better conditioned.
        e1x, e1y = l1 - a22, a12
        f1x, f1y = a12, l1 - a11
        if f1x * f1x + f1y * f1y > e1x * e1x + e1y * e1y:
            e1x, e1y = f1x, f1y
        nrm = math.sqrt(e1x * e1x + e1y * e1y)
        if nrm == 0.0:  # a circle: any direction
            e1x, e1y, nrm = 1.0, 0.0, 1.0
        e1x /= nrm
        e1y /= nrm
        e2x, e2y = -e1y, e1x
        r = ring_px
        if ring_fraction > 0.0:
            r = min(ring_px, max(1.0, ring_fraction * ax2))
        bx1 = ax1 + r
        bx2 = ax2 + r
        # Ring ellipse with the same axes directions and expanded semi-axes.
        w1 = 1.0 / (bx1 * bx1)
        w2 = 1.0 / (bx2 * bx2)
        inner[i, 0], inner[i, 1], inner[i, 2], inner[i, 3], inner[i, 4] = cu, cv, a11, a12, a22
        ring[i, 0], ring[i, 1] = cu, cv
        ring[i, 2] = w1 * e1x * e1x + w2 * e2x * e2x
        ring[i, 3] = w1 * e1x * e1y + w2 * e2x * e2y
        ring[i, 4] = w1 * e1y * e1y + w2 * e2y * e2y
        # Bounding box of the ring ellipse in the real image.
        if cam.has_dist:
            umin, umax, vmin, vmax = 1e300, -1e300, 1e300, -1e300
            for j in range(_OUTLINE_SAMPLES):
                t = 2.0 * math.pi * j / _OUTLINE_SAMPLES
                pu = cu + bx1 * math.cos(t) * e1x + bx2 * math.sin(t) * e2x
                pv = cv + bx1 * math.cos(t) * e1y + bx2 * math.sin(t) * e2y
                qu, qv = ideal_to_real_pixel(pu, pv, cam.K, cam.dist)
                umin, umax = min(umin, qu), max(umax, qu)
                vmin, vmax = min(vmin, qv), max(vmax, qv)
            umin -= 1.0
            vmin -= 1.0
            umax += 1.0
            vmax += 1.0
        else:
            hu = math.sqrt((bx1 * e1x) ** 2 + (bx2 * e2x) ** 2)
            hv = math.sqrt((bx1 * e1y) ** 2 + (bx2 * e2y) ** 2)
            umin, umax, vmin, vmax = cu - hu, cu + hu, cv - hv, cv + hv
        u0 = max(0, int(math.floor(umin)))
        u1 = min(width, int(math.ceil(umax)) + 1)
        v0 = max(0, int(math.floor(vmin)))
        v1 = min(height, int(math.ceil(vmax)) + 1)
        box[i, 0], box[i, 1], box[i, 2], box[i, 3] = u0, u1, v0, v1
        valid[i] = True
    return inner, ring, box, valid


def person_forms(cam: CameraArgs, xy: np.ndarray, heights: np.ndarray, widths: np.ndarray,
                 draw: DrawArgs) -> Forms:
    """:func:`ellipse_forms` of people at ``xy`` (N, 2) m, with their floor distances from the camera."""
    inner, ring, box, valid = ellipse_forms(cam, xy, heights, widths, draw)
    dist = np.hypot(xy[:, 0] - cam.centre[0], xy[:, 1] - cam.centre[1])
    return Forms(inner, ring, box, valid, dist)


@njit(cache=True, inline="always")
def inside(f, u, v):
    """Whether ideal point (u, v) is inside the ellipse of normal form ``f`` (5,)."""
    du = u - f[0]
    dv = v - f[1]
    return f[2] * du * du + 2.0 * f[3] * du * dv + f[4] * dv * dv < 1.0


@njit(cache=True, inline="always")
def ideal_position(grid, has_dist, v, u):
    """The ideal position (x, y) of real pixel (u, v): from ``grid`` under distortion, else itself."""
    if has_dist:
        return np.float64(grid[v, u, 0]), np.float64(grid[v, u, 1])
    return np.float64(u), np.float64(v)


@njit(cache=True)
def ellipse_crop(form, box, grid, has_dist):
    """(v1 − v0, u1 − u0) bool: pixels of ``box`` inside the ellipse of normal form ``form``."""
    u0, u1, v0, v1 = box[0], box[1], box[2], box[3]
    out = np.zeros((max(0, v1 - v0), max(0, u1 - u0)), dtype=np.bool_)
    for v in range(v0, v1):
        for uu in range(u0, u1):
            x, y = ideal_position(grid, has_dist, v, uu)
            out[v - v0, uu - u0] = inside(form, x, y)
    return out


def ellipse_crop_reference(form: np.ndarray, box: np.ndarray, grid: np.ndarray, has_dist: bool) -> np.ndarray:
    """:func:`ellipse_crop` in NumPy (the whole box at once): the version it is tested against."""
    u0, u1, v0, v1 = (int(b) for b in box)
    if has_dist:
        x = grid[v0:v1, u0:u1, 0].astype(np.float64)
        y = grid[v0:v1, u0:u1, 1].astype(np.float64)
    else:
        y, x = np.mgrid[v0:max(v0, v1), u0:max(u0, u1)].astype(np.float64)
    du, dv = x - form[0], y - form[1]
    return form[2] * du * du + 2.0 * form[3] * du * dv + form[4] * dv * dv < 1.0


@njit(cache=True)
def owner_crop(window, forms, grid, has_dist):
    """Who covers each pixel of ``window`` = (u0, u1, v0, v1): (v1 − v0, u1 − u0) int32, the
    index of the one person whose ellipse covers the pixel, −1 nobody, −2 several.

    ``window`` must lie inside the image (a person's box does). Only the people whose boxes meet
    it are visited, so the cost is that of the window, not of the image.

    Parameters
    ----------
    window : (4,) int64
    forms : Forms — the people's ellipses (``inner``, ``box``, ``valid`` are read)
    grid : (H, W, 2) float32 — ideal coordinates of each pixel (used when ``has_dist``)
    """
    inner, box, valid = forms.inner, forms.box, forms.valid
    u0, u1, v0, v1 = window[0], window[1], window[2], window[3]
    out = np.full((max(0, v1 - v0), max(0, u1 - u0)), -1, dtype=np.int32)
    for k in range(inner.shape[0]):
        if not valid[k]:
            continue
        for v in range(max(box[k, 2], v0), min(box[k, 3], v1)):
            for uu in range(max(box[k, 0], u0), min(box[k, 1], u1)):
                x, y = ideal_position(grid, has_dist, v, uu)
                if inside(inner[k], x, y):
                    out[v - v0, uu - u0] = k if out[v - v0, uu - u0] == -1 else -2
    return out


def owner_map(height: int, width: int, forms: Forms, grid: np.ndarray, has_dist: bool) -> np.ndarray:
    """(H, W) int32: index of the one person whose ellipse covers each pixel, −1 nobody, −2 several
    (:func:`owner_crop` over the whole image)."""
    return owner_crop(np.array([0, width, 0, height], dtype=np.int64), forms, grid, has_dist)


__all__ = ["ellipse_crop", "ellipse_crop_reference", "ellipse_forms", "ideal_position", "inside", "owner_crop",
           "owner_map", "person_forms"]
