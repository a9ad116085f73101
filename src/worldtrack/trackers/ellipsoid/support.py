"""How much of each person's ellipse is foreground that nobody else explains (their *support*).

Eq. 5 rates candidates; it does not say whether a track still has a person under it. A track
whose own pixels — visible, not hidden by obstacles, covered by nobody else — are mostly
background explains nothing the others do not: a ghost left beside the person it duplicated, or a
track that lost its person. :func:`track_support` counts, per person and camera, the visible
pixels, the own pixels and the own foreground pixels; the life cycle (:mod:`.life`) confirms and
ends people on these shares.

:func:`track_support` is compiled (a loop over sampled pixels and the people covering them);
:func:`track_support_reference` is the whole-box NumPy version it is tested against.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from worldtrack.trackers.ellipsoid.args import CameraArgs, Forms
from worldtrack.trackers.ellipsoid.forms import ideal_position, inside


@njit(cache=True)
def track_support(cam, mask, forms, target_pixels, covers):
    """How much foreground each person alone explains, in one camera.

    For every person k, over the visible pixels of its ellipse (not hidden by obstacles) that no
    other person's visible ellipse covers: the number of such pixels and how many of them are
    foreground.

    Parameters
    ----------
    cam : CameraArgs — ``grid``, ``has_dist``, ``occ`` are read
    mask : (H, W) uint8 — foreground (1) / background (0) / unsure (2, not counted)
    forms : Forms — the people's ellipses, boxes, floor distances and validity (N, …)
    target_pixels : int — sample about this many pixels per person (0 = all)
    covers : (N,) bool — which people take pixels away from the others (e.g. only confirmed
        tracks: two tentative ones on the same person must not cancel each other out)

    Returns
    -------
    visible : (N,) float64 — pixels of the ellipse inside the image and not hidden by obstacles
        (estimated from the samples: each sample counts stride² pixels)
    own : (N,) float64 — of those, the ones covered by nobody else (not counting unsure pixels)
    own_fg : (N,) float64 — of those, the foreground ones
    area : (N,) float64 — the whole ellipse's area in pixels, image border and obstacles ignored
    """
    inner, box, dist, valid = forms.inner, forms.box, forms.dist, forms.valid
    occ = cam.occ
    n = inner.shape[0]
    visible = np.zeros(n)
    own = np.zeros(n)
    own_fg = np.zeros(n)
    area = np.zeros(n)
    for k in range(n):
        if not valid[k]:
            continue
        area[k] = math.pi / math.sqrt(max(inner[k, 2] * inner[k, 4] - inner[k, 3] ** 2, 1e-300))
        u0, u1, v0, v1 = box[k, 0], box[k, 1], box[k, 2], box[k, 3]
        if u0 >= u1 or v0 >= v1:
            continue
        stride = 1
        if target_pixels > 0:
            stride = max(1, int(math.sqrt((u1 - u0) * (v1 - v0) / target_pixels)))
        for v in range(v0, v1, stride):
            for uu in range(u0, u1, stride):
                x, y = ideal_position(cam.grid, cam.has_dist, v, uu)
                o = occ[v, uu]
                if o < dist[k] or not inside(inner[k], x, y):
                    continue
                visible[k] += stride * stride
                covered = False
                for m in range(n):
                    if m == k or not valid[m] or not covers[m] or o < dist[m]:
                        continue
                    if uu < box[m, 0] or uu >= box[m, 1] or v < box[m, 2] or v >= box[m, 3]:
                        continue
                    if inside(inner[m], x, y):
                        covered = True
                        break
                if not covered and mask[v, uu] != 2:
                    own[k] += stride * stride
                    if mask[v, uu] == 1:
                        own_fg[k] += stride * stride
    return visible, own, own_fg, area


def track_support_reference(cam: CameraArgs, mask: np.ndarray, forms: Forms, target_pixels: int,
                            covers: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`track_support` with whole-box masks in NumPy: the version it is tested against."""
    n = len(forms.valid)
    visible, own, own_fg, area = (np.zeros(n) for _ in range(4))
    for k in np.flatnonzero(forms.valid):
        a11, a12, a22 = forms.inner[k, 2:]
        area[k] = math.pi / math.sqrt(max(a11 * a22 - a12 ** 2, 1e-300))
        u0, u1, v0, v1 = (int(b) for b in forms.box[k])
        if u0 >= u1 or v0 >= v1:
            continue
        stride = max(1, int(math.sqrt((u1 - u0) * (v1 - v0) / target_pixels))) if target_pixels > 0 else 1
        vv, uu = np.meshgrid(np.arange(v0, v1, stride), np.arange(u0, u1, stride), indexing="ij")
        x, y = _ideal(cam, vv, uu)
        occ = cam.occ[vv, uu]
        mine = (occ >= forms.dist[k]) & _inside(forms.inner[k], x, y)
        covered = np.zeros_like(mine)
        for m in np.flatnonzero(forms.valid & covers):
            if m != k:
                bu0, bu1, bv0, bv1 = forms.box[m]
                in_box = (uu >= bu0) & (uu < bu1) & (vv >= bv0) & (vv < bv1)
                covered |= in_box & (occ >= forms.dist[m]) & _inside(forms.inner[m], x, y)
        labels = mask[vv, uu]
        alone = mine & ~covered & (labels != 2)
        weight = stride * stride
        visible[k] = weight * np.count_nonzero(mine)
        own[k] = weight * np.count_nonzero(alone)
        own_fg[k] = weight * np.count_nonzero(alone & (labels == 1))
    return visible, own, own_fg, area


def _ideal(cam: CameraArgs, vv: np.ndarray, uu: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    if cam.has_dist:
        return cam.grid[vv, uu, 0].astype(np.float64), cam.grid[vv, uu, 1].astype(np.float64)
    return uu.astype(np.float64), vv.astype(np.float64)


def _inside(f: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    du, dv = x - f[0], y - f[1]
    return f[2] * du * du + 2.0 * f[3] * du * dv + f[4] * dv * dv < 1.0


__all__ = ["track_support", "track_support_reference"]
