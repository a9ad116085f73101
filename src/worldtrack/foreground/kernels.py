"""Per-pixel foreground kernels (Numba), each with the plain NumPy version it must agree with."""

from __future__ import annotations

import numpy as np
from numba import njit

#: Shadows are darker than the background; brighter than this ratio is not a shadow.
SHADOW_MAX_RATIO = 0.97


@njit(cache=True)
def colour_labels(image, background, bg_norm2, threshold, shadows, min_ratio, distortion):
    """Labels of a colour frame against a background in one pass.

    Parameters
    ----------
    image, background : (H, W, 3) uint8
    bg_norm2 : (H, W) float32 — ``‖B‖²`` per pixel (at least 1)
    threshold : float — RGB distance above which a pixel has changed
    shadows : bool — mark shadow-like changes ``2`` instead of ``1``
    min_ratio : float — darkest shadow as a fraction of the background brightness
    distortion : float — largest colour distortion of a shadow as a fraction of ``‖B‖``

    Returns
    -------
    (H, W) uint8 — 0 unchanged, 1 foreground, 2 shadow-like
    """
    H, W = bg_norm2.shape
    out = np.zeros((H, W), np.uint8)
    t2 = threshold * threshold
    d2max = distortion * distortion
    for v in range(H):
        for u in range(W):
            i0, i1, i2 = np.float32(image[v, u, 0]), np.float32(image[v, u, 1]), np.float32(image[v, u, 2])
            b0, b1, b2 = np.float32(background[v, u, 0]), np.float32(background[v, u, 1]), np.float32(background[v, u, 2])
            d0, d1, d2 = i0 - b0, i1 - b1, i2 - b2
            if d0 * d0 + d1 * d1 + d2 * d2 <= t2:
                continue
            out[v, u] = 1
            if shadows:
                n2 = bg_norm2[v, u]
                a = (i0 * b0 + i1 * b1 + i2 * b2) / n2
                if min_ratio <= a <= SHADOW_MAX_RATIO:
                    r0, r1, r2 = i0 - a * b0, i1 - a * b1, i2 - a * b2
                    if r0 * r0 + r1 * r1 + r2 * r2 <= d2max * n2:
                        out[v, u] = 2
    return out


def shadow_like(img, bg, bg_norm2, min_ratio, distortion):
    """(H, W) bool: pixels whose colour is the background's in shadow (the test of :func:`colour_labels`).

    A pixel ``I`` is shadow-like when ``I ≈ a·B`` with brightness ratio
    ``a = I·B / ‖B‖²`` in ``[min_ratio, SHADOW_MAX_RATIO]`` and colour distortion
    ``‖I − a·B‖ ≤ distortion·‖B‖`` (Horprasert et al. 1999).

    Parameters
    ----------
    img, bg : (H, W, 3) float32
    bg_norm2 : (H, W) float32 — ``‖B‖²`` per pixel (at least 1)
    min_ratio, distortion : float — as for :func:`colour_labels`
    """
    a = np.einsum("hwc,hwc->hw", img, bg) / bg_norm2                 # brightness ratio
    resid = img - a[..., None] * bg
    return (a >= min_ratio) & (a <= SHADOW_MAX_RATIO) & (np.einsum("hwc,hwc->hw", resid, resid)
                                                         <= (distortion ** 2) * bg_norm2)


def colour_labels_reference(image, background, threshold, shadows, min_ratio, distortion):
    """NumPy version of :func:`colour_labels` (same arguments, ``bg_norm2`` computed here)."""
    img = image.astype(np.float32)
    bg = background.astype(np.float32)
    diff = img - bg
    changed = np.einsum("hwc,hwc->hw", diff, diff) > np.float32(threshold) ** 2
    out = changed.astype(np.uint8)
    if shadows:
        n2 = np.maximum(np.einsum("hwc,hwc->hw", bg, bg), 1.0)
        out[changed & shadow_like(img, bg, n2, min_ratio, distortion)] = 2
    return out
