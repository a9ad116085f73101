"""Cast shadows as a tracker reads them: where they can fall, and what a shadow-like pixel is.

Every foreground model sets shadow-like changes apart as ``UNSURE`` (2): the brightness and colour
test of :mod:`worldtrack.foreground.kernels` (the background darkened without a change of colour),
or MOG2/KNN's own shadow detection. A tracker that can use more reads them with
:func:`read_shadows`: a shadow-like pixel off the walkable floor is object (shadows fall on the
floor, :func:`floor_pixels`); on the floor the texture test (:func:`~worldtrack.foreground.texture.judge_shadows`)
calls it cloth (object) where the floor's pattern is gone, a shadow where it shows through, and
leaves it unsure in between. The particle tracker reads shadows as background or as no evidence.

>>> import numpy as np
>>> labels = np.array([[0, 1, 2, 2]], np.uint8)
>>> floor = np.array([[True, True, True, False]])
>>> flat = np.full((1, 4, 3), 120, np.uint8)                     # a plain floor: no texture to judge by
>>> read_shadows(labels, flat, flat, floor, shadow_as=0).tolist()
[[0, 1, 2, 1]]
"""

from __future__ import annotations

import numpy as np

from worldtrack.foreground.texture import grey, judge_shadows, judge_shadows_reference
from worldtrack.geometry.camera import Camera

#: Foreground labels: 0 background, 1 object, 2 unsure (shadow-like), and :data:`SHADOW` for a
#: shadow-like pixel the texture test calls a shadow.
OBJECT, UNSURE, SHADOW = 1, 2, 3
#: The texture test's thresholds on the normalised cross-correlation of image and background: at or
#: below the first the floor's pattern is gone (cloth), at or above the second it shows (a shadow).
SHADOW_NCC = (0.2, 0.5)


def read_shadows(labels: np.ndarray, image: np.ndarray, background: np.ndarray, floor: np.ndarray | None,
                 shadow_as: int, grey_background: np.ndarray | None = None) -> np.ndarray:
    """A foreground's labels with its shadow-like pixels judged: a new (H, W) uint8 array.

    Parameters
    ----------
    labels : (H, W) uint8 — 0 background, 1 object, 2 unsure (a foreground model's ``labels``)
    image, background : (H, W, 3) uint8 BGR — the frame and the empty scene
    floor : (H, W) bool or None — where shadows can fall (:func:`floor_pixels`); None: everywhere
    shadow_as : int — the label a judged shadow gets: 0 (background) or 2 (no evidence)
    grey_background : (H, W) uint8, optional — :func:`~worldtrack.foreground.texture.grey` of the
        background, if at hand

    Returns
    -------
    (H, W) uint8 — 0 background or shadow, 1 object or cloth, 2 unsure (or shadow)
    """
    out = np.array(labels, dtype=np.uint8, order="C", copy=True)
    if floor is not None:
        out[(out == UNSURE) & ~floor] = OBJECT
    gb = grey(background) if grey_background is None else grey_background
    judge_shadows(out, image, gb, SHADOW_NCC[0], SHADOW_NCC[1], candidate=UNSURE, cloth=OBJECT, shadow=SHADOW)
    out[out == SHADOW] = shadow_as
    return out


def read_shadows_reference(labels: np.ndarray, image: np.ndarray, background: np.ndarray,
                           floor: np.ndarray | None, shadow_as: int) -> np.ndarray:
    """:func:`read_shadows` with the texture test of OpenCV box filters (the reference)."""
    out = np.array(labels, dtype=np.uint8, copy=True)
    if floor is not None:
        out[(out == UNSURE) & ~floor] = OBJECT
    out = judge_shadows_reference(out, image, background, SHADOW_NCC[0], SHADOW_NCC[1], candidate=UNSURE,
                                  cloth=OBJECT, shadow=SHADOW)
    out[out == SHADOW] = shadow_as
    return out


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


__all__ = ["OBJECT", "SHADOW", "SHADOW_NCC", "UNSURE", "floor_pixels", "read_shadows", "read_shadows_reference"]
