"""Texture test of shadow-like pixels: does the background's pattern show through?

A cast shadow darkens the floor without changing its colour — and so does a dark garment whose
colour is close to the floor's (brown trousers on a wooden floor, grey on grey tiles); the
brightness/chroma test (Horprasert et al. 1999, also behind MOG2's shadow detection) cannot tell
them apart. Their texture can: in a shadow the floor's grain or tile edges still show, darker,
so the image and the background correlate over a small window; cloth replaces the pattern.

:func:`texture_correlation` computes the local normalised cross-correlation (NCC) of the grey
levels over the whole image with OpenCV box filters — the reference; :func:`texture_at` computes it
only at listed pixels (Numba), which is what a frame with a few thousand shadow-like pixels needs.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
from numba import njit

#: Side of the square window (pixels) and the least grey-level σ of the background in it for the
#: correlation to mean anything (a plain floor has no pattern to show through).
TEXTURE_WINDOW = 5
TEXTURE_MIN_SD = 4.0


def grey(image: np.ndarray) -> np.ndarray:
    """(H, W) uint8 grey levels of a BGR image."""
    return cv2.cvtColor(np.ascontiguousarray(image), cv2.COLOR_BGR2GRAY)


def texture_correlation(image: np.ndarray, background: np.ndarray, window: int) -> tuple[np.ndarray, np.ndarray]:
    """Local normalised cross-correlation of the grey levels of ``image`` and ``background``.

    Parameters
    ----------
    image, background : (H, W, 3) uint8 BGR
    window : int — side of the square window (pixels, odd); the image border is reflected

    Returns
    -------
    ncc : (H, W) float32 in [−1, 1] (0 where either window is flat)
    background_sd : (H, W) float32 — the background's grey-level σ in the window
    """
    a = grey(image).astype(np.float32)
    b = grey(background).astype(np.float32)

    def mean(x: np.ndarray) -> np.ndarray:
        return cv2.boxFilter(x, -1, (window, window), borderType=cv2.BORDER_REFLECT)

    ma, mb = mean(a), mean(b)
    va = np.maximum(mean(a * a) - ma * ma, 0.0)
    vb = np.maximum(mean(b * b) - mb * mb, 0.0)
    cov = mean(a * b) - ma * mb
    denom = np.sqrt(va * vb)
    ncc = np.where(denom > 1e-3, cov / np.maximum(denom, 1e-3), 0.0).astype(np.float32)
    return ncc, np.sqrt(vb)


@njit(cache=True, inline="always")
def _reflect(i, n):
    """OpenCV's BORDER_REFLECT (``fedcba|abcdef``) for an index at most n outside [0, n), kept inside
    the image when it is narrower than the window reaches."""
    if i < 0:
        i = -i - 1
    elif i >= n:
        i = 2 * n - i - 1
    return min(max(i, 0), n - 1)


@njit(cache=True, inline="always")
def _ncc_at(grey_image, grey_background, v0, u0, m):
    """NCC and background σ of the (2m + 1)² window centred on (v0, u0), border reflected."""
    H, W = grey_image.shape
    sa = sb = saa = sbb = sab = 0  # integer sums of uint8 values: exact
    interior = m <= v0 < H - m and m <= u0 < W - m
    for dv in range(-m, m + 1):
        v = v0 + dv if interior else _reflect(v0 + dv, H)
        for du in range(-m, m + 1):
            u = u0 + du if interior else _reflect(u0 + du, W)
            a = np.int64(grey_image[v, u])
            b = np.int64(grey_background[v, u])
            sa += a
            sb += b
            saa += a * a
            sbb += b * b
            sab += a * b
    n = float((2 * m + 1) * (2 * m + 1))
    ma, mb = sa / n, sb / n
    va = max(saa / n - ma * ma, 0.0)
    vb = max(sbb / n - mb * mb, 0.0)
    denom = math.sqrt(va * vb)
    ncc = (sab / n - ma * mb) / denom if denom > 1e-3 else 0.0
    return ncc, math.sqrt(vb)


@njit(cache=True)
def texture_at(grey_image, grey_background, vs, us, window):
    """:func:`texture_correlation` at the listed pixels only.

    Parameters
    ----------
    grey_image, grey_background : (H, W) uint8
    vs, us : (K,) int — rows and columns of the pixels
    window : int — odd side of the window

    Returns
    -------
    ncc, background_sd : (K,) float64
    """
    ncc = np.zeros(vs.shape[0])
    sd = np.zeros(vs.shape[0])
    for k in range(vs.shape[0]):
        ncc[k], sd[k] = _ncc_at(grey_image, grey_background, vs[k], us[k], window // 2)
    return ncc, sd


@njit(cache=True)
def _judge(labels, grey_image, grey_background, window, min_sd, cloth_at_most, shadow_at_least, candidate, cloth,
           shadow):
    H, W = labels.shape
    for v in range(H):
        for u in range(W):
            if labels[v, u] == candidate:
                ncc, sd = _ncc_at(grey_image, grey_background, v, u, window // 2)
                if sd >= min_sd:
                    if ncc <= cloth_at_most:
                        labels[v, u] = cloth
                    elif ncc >= shadow_at_least:
                        labels[v, u] = shadow


def judge_shadows(labels: np.ndarray, image: np.ndarray, grey_background: np.ndarray, cloth_at_most: float,
                  shadow_at_least: float = np.inf, candidate: int = 2, cloth: int = 1, shadow: int = 3) -> np.ndarray:
    """Judge shadow-like pixels by whether the background's texture shows through, in place.

    Pixels labelled ``candidate`` where the background is textured (σ ≥ ``TEXTURE_MIN_SD`` over a
    ``TEXTURE_WINDOW`` window) become ``cloth`` when the image does not correlate with it (NCC ≤
    ``cloth_at_most``; a flat image window has NCC 0: the pattern is gone) and ``shadow`` when it
    does (NCC ≥ ``shadow_at_least``: the pattern shows through, darker); the others — a plain floor,
    or in between — keep their label (cannot be told). One pass of a Numba kernel over the labels
    (exact integer window sums); :func:`judge_shadows_reference` is the same with OpenCV box filters.

    Parameters
    ----------
    labels : (H, W) uint8, C-contiguous
    image : (H, W, 3) uint8 BGR
    grey_background : (H, W) uint8 — :func:`grey` of the background
    cloth_at_most, shadow_at_least : float — NCC thresholds (``shadow_at_least = inf``: never shadow)
    candidate, cloth, shadow : int — the labels read and written
    """
    _judge(labels, grey(image), grey_background, TEXTURE_WINDOW, float(TEXTURE_MIN_SD), float(cloth_at_most),
           float(shadow_at_least), candidate, cloth, shadow)
    return labels


def judge_shadows_reference(labels: np.ndarray, image: np.ndarray, background: np.ndarray, cloth_at_most: float,
                            shadow_at_least: float = np.inf, candidate: int = 2, cloth: int = 1,
                            shadow: int = 3) -> np.ndarray:
    """:func:`judge_shadows` over the whole image with :func:`texture_correlation` (a new array)."""
    ncc, sd = texture_correlation(image, background, TEXTURE_WINDOW)
    out = labels.copy()
    textured = (labels == candidate) & (sd >= TEXTURE_MIN_SD)
    out[textured & (ncc <= cloth_at_most)] = cloth
    out[textured & ~(ncc <= cloth_at_most) & (ncc >= shadow_at_least)] = shadow
    return out


def relabel_cloth(labels: np.ndarray, image: np.ndarray, grey_background: np.ndarray, max_ncc: float,
                  candidate: int = 2, cloth: int = 1) -> np.ndarray:
    """Shadow-like pixels that hide the background's texture are foreground, in place: the cloth half
    of :func:`judge_shadows` (NCC ≤ ``max_ncc`` → ``cloth``; never shadow)."""
    return judge_shadows(labels, image, grey_background, max_ncc, np.inf, candidate, cloth, candidate)


def relabel_cloth_reference(labels: np.ndarray, image: np.ndarray, background: np.ndarray, max_ncc: float,
                            candidate: int = 2, cloth: int = 1) -> np.ndarray:
    """:func:`relabel_cloth` over the whole image with :func:`texture_correlation` (a new array)."""
    return judge_shadows_reference(labels, image, background, max_ncc, np.inf, candidate, cloth, candidate)
