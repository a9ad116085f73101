"""Labels of a frame against its background: object, background, and cast shadows set apart.

The particle tracker (seed 004) reads per pixel ``F > γ``, F the Euclidean RGB distance to the
background (eq. 13), and, beyond the paper, tells cast shadows from objects by colour and texture:

* :func:`hit_image` — ``F > γ`` as (H, W) uint8;
* :func:`hit_labels` — the same with cast shadows set apart (background, or "no evidence", 2) by
  colour and texture (a Numba kernel, with :func:`hit_labels_reference` in NumPy);
* :func:`thresholded_difference` — F with ``F ≤ γ`` set to 0 (the point likelihood, eq. 7);
* :func:`floor_pixels` — the pixels whose background is the walkable floor (where shadows fall).

>>> import numpy as np
>>> hit_image(np.array([[10.0, 30.0]]), 25.0).tolist()
[[0, 1]]
"""

from __future__ import annotations

import numpy as np
from numba import njit

from worldtrack.foreground.texture import TEXTURE_MIN_SD, TEXTURE_WINDOW, texture_correlation
from worldtrack.geometry.camera import Camera

def hit_image(difference: np.ndarray, gamma: float) -> np.ndarray:
    """``F > γ`` as (H, W) uint8 (1 = object), read by the column likelihood.

    Parameters
    ----------
    difference : (H, W) float — background difference F (Euclidean RGB distance)
    gamma : float — threshold γ in the same units
    """
    return np.ascontiguousarray(np.asarray(difference) > gamma).view(np.uint8)


#: Texture test of shadow candidates (window and least background contrast from
#: :mod:`worldtrack.foreground.texture`): the normalised cross-correlation at or above which the
#: candidate is a shadow / below which it is object.
TEXTURE_NCC = (0.2, 0.5)


def hit_labels(image: np.ndarray, background: np.ndarray, gamma: float,
               brightness: tuple[float, float] = (0.5, 0.95), chroma: float = 10.0,
               where: np.ndarray | None = None, shadow: int = 2, texture: bool = True) -> np.ndarray:
    """``F > γ`` with cast shadows set apart, (H, W) uint8: 0 background, 1 object, 2 no evidence.

    A pixel is a shadow *candidate* when it is the background darkened without a change of colour:
    its brightness ratio ``a = (I·B) / (B·B)`` lies in ``brightness`` and its colour distortion
    ``‖I − a·B‖`` is at most ``chroma`` (the test of Horprasert et al. 1999, also behind OpenCV
    MOG2's shadow detection). Grey trousers over a grey floor pass that test as well as a shadow
    does, so with ``texture`` a candidate is then judged by whether the background's texture shows
    through (a shadow darkens the floor's pattern, cloth replaces it): over a
    ``TEXTURE_WINDOW``-pixel window where the background's grey level varies (σ ≥
    ``TEXTURE_MIN_SD``), a normalised cross-correlation of image and background ≥
    ``TEXTURE_NCC[1]`` makes it a shadow and < ``TEXTURE_NCC[0]`` object; otherwise (a plain
    floor, or in between) it cannot be told and reads 2, no evidence. Shadows get the label
    ``shadow``: 2 (no evidence) or 0 (background). Without ``texture`` every candidate is a shadow.
    Not in seed 004, whose F counts shadows as object. The per-pixel test is a Numba kernel, the
    texture test box filters (OpenCV); :func:`hit_labels_reference` is the same in NumPy.

    Parameters
    ----------
    image, background : (H, W, 3) uint8
    gamma : float — threshold γ on ``F = ‖I − B‖``
    brightness : (lo, hi) — range of the brightness ratio of shadows
    chroma : float — largest colour distortion of shadows (RGB units)
    where : (H, W) bool, optional — the only pixels where shadows can be (e.g. those that see the
        floor, :func:`floor_pixels`); default everywhere
    shadow : {2, 0} — the label of shadow pixels
    texture : bool — apply the texture test to the candidates
    """
    img = np.ascontiguousarray(image)
    bg = np.ascontiguousarray(background)
    w = np.ones(img.shape[:2], dtype=np.bool_) if where is None else np.ascontiguousarray(where, dtype=np.bool_)
    out = np.empty(img.shape[:2], dtype=np.uint8)
    _shadow_labels(img, bg, float(gamma), float(brightness[0]), float(brightness[1]), float(chroma), w,
                   CANDIDATE if texture else int(shadow), out)
    return _judge_texture(out, img, bg, shadow) if texture else out


#: Temporary label of shadow candidates before the texture test.
CANDIDATE = 3


def _judge_texture(labels: np.ndarray, image: np.ndarray, background: np.ndarray, shadow: int,
                   crop: bool = True) -> np.ndarray:
    """Relabel the ``CANDIDATE`` pixels of ``labels`` by the texture test of :func:`hit_labels`, in place.

    ``crop``: compute the correlation only over the candidates' bounding box grown by half a window
    (each candidate's window lies inside it, or meets the image border there, so the result is the
    same as over the whole image, which ``crop=False`` computes — the reference's way)."""
    cand = labels == CANDIDATE
    rows, cols = np.flatnonzero(cand.any(axis=1)), np.flatnonzero(cand.any(axis=0))
    if not len(rows):
        return labels
    m = TEXTURE_WINDOW // 2
    box = ((slice(max(rows[0] - m, 0), rows[-1] + m + 1), slice(max(cols[0] - m, 0), cols[-1] + m + 1))
           if crop else (slice(None), slice(None)))
    ncc, sd = texture_correlation(image[box], background[box], TEXTURE_WINDOW)
    textured = sd >= TEXTURE_MIN_SD
    judged = np.full(ncc.shape, 2, dtype=np.uint8)
    judged[textured & (ncc >= TEXTURE_NCC[1])] = shadow
    judged[textured & (ncc < TEXTURE_NCC[0])] = 1
    sub, c = labels[box], cand[box]
    sub[c] = judged[c]
    return labels


@njit(cache=True)
def _shadow_labels(img, bg, gamma, lo, hi, chroma, where, shadow, out):
    H, W = out.shape
    g2 = gamma * gamma
    c2 = chroma * chroma
    for v in range(H):
        for u in range(W):
            i0, i1, i2 = float(img[v, u, 0]), float(img[v, u, 1]), float(img[v, u, 2])
            b0, b1, b2 = float(bg[v, u, 0]), float(bg[v, u, 1]), float(bg[v, u, 2])
            d0, d1, d2 = i0 - b0, i1 - b1, i2 - b2
            if d0 * d0 + d1 * d1 + d2 * d2 <= g2:
                out[v, u] = 0
                continue
            out[v, u] = 1
            if where[v, u]:
                a = (i0 * b0 + i1 * b1 + i2 * b2) / max(b0 * b0 + b1 * b1 + b2 * b2, 1.0)
                if lo <= a <= hi:
                    e0, e1, e2 = i0 - a * b0, i1 - a * b1, i2 - a * b2
                    if e0 * e0 + e1 * e1 + e2 * e2 <= c2:
                        out[v, u] = shadow


def hit_labels_reference(image: np.ndarray, background: np.ndarray, gamma: float,
                         brightness: tuple[float, float] = (0.5, 0.95), chroma: float = 10.0,
                         where: np.ndarray | None = None, shadow: int = 2, texture: bool = True) -> np.ndarray:
    """:func:`hit_labels` in NumPy (float64), the reference the kernel is tested against (the
    texture test is the same code)."""
    I = image.astype(np.float64)
    B = background.astype(np.float64)
    d = I - B
    F2 = np.einsum("hwc,hwc->hw", d, d)
    bb = np.einsum("hwc,hwc->hw", B, B)
    a = np.einsum("hwc,hwc->hw", I, B) / np.maximum(bb, 1.0)
    e = I - a[..., None] * B
    cd2 = np.einsum("hwc,hwc->hw", e, e)
    is_shadow = (a >= brightness[0]) & (a <= brightness[1]) & (cd2 <= chroma * chroma)
    if where is not None:
        is_shadow &= where
    hit = F2 > gamma * gamma
    labels = np.where(hit & is_shadow, CANDIDATE if texture else shadow, hit).astype(np.uint8)
    return _judge_texture(labels, image, background, shadow, crop=False) if texture else labels


def thresholded_difference(difference: np.ndarray, gamma: float) -> np.ndarray:
    """F with ``F ≤ γ`` set to 0, (H, W) float32, read by the point likelihood."""
    f = np.asarray(difference, dtype=np.float32)
    return np.ascontiguousarray(np.where(f > gamma, f, np.float32(0.0)))


def floor_pixels(camera: Camera, walkable, occlusion_floor_distance: np.ndarray | None = None) -> np.ndarray:
    """(H, W) bool: pixels whose background is the walkable floor (where people cast shadows).

    Parameters
    ----------
    camera : Camera
    walkable : object with ``contains((N, 2) xy) -> (N,) bool`` (the scene's walkable area)
    occlusion_floor_distance : (H, W), optional — floor distance of the obstacle seen at each pixel
        (:class:`~worldtrack.scene.occlusion.OcclusionMap`); pixels where an obstacle is nearer
        than the floor point are not floor
    """
    v, u = np.mgrid[0:camera.height, 0:camera.width]
    p = camera.backproject(np.column_stack([u.ravel(), v.ravel()]).astype(float), 0.0)
    ok = np.isfinite(p).all(axis=1)
    out = np.zeros(len(p), dtype=bool)
    out[ok] = walkable.contains(p[ok, :2])
    if occlusion_floor_distance is not None:
        d = np.full(len(p), np.inf)
        d[ok] = camera.floor_distance(p[ok])
        out &= d < np.asarray(occlusion_floor_distance).ravel()
    return out.reshape(camera.height, camera.width)


__all__ = ["CANDIDATE", "TEXTURE_NCC", "floor_pixels", "hit_image", "hit_labels", "hit_labels_reference",
           "thresholded_difference"]
