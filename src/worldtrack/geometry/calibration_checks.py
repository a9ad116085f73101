"""What a list of world/image point pairs must satisfy before a camera is fitted to it
(:func:`worldtrack.geometry.calibrate.calibrate`): finite numbers, plausible units and ranges, enough
points, no point twice, not all on one line, and the shape of the points (general, on the floor, on
another plane), which decides how the camera is fitted. Every refusal is an
:class:`~worldtrack.errors.InputError` that names the point.

>>> import numpy as np
>>> W = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [2, 0, 0], [0, 2, 0.0]])
>>> _configuration(W, W[:, :2] * 100 + 5)[0]
'horizontal'
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from worldtrack.errors import InputError


MIN_POINTS = 6
"""A 3×4 camera has 11 degrees of freedom and each point gives 2 equations."""

ADVISED_POINTS = 20
"""The paper (§2.1.4) asks for at least 20 points."""

#: Most point pairs a calibration takes (its refinement's Jacobian grows with the count).
MAX_POINTS = 100_000
#: World coordinates beyond ± this many metres are refused; a point cloud wider than
#: MM_SUSPECT_M is warned about (millimetres given as metres).
MAX_WORLD_M = 10_000.0
MM_SUSPECT_M = 100.0
#: Pixel coordinates beyond ± this are refused.
MAX_PIXEL = 1_000_000.0

PLANE_TOLERANCE = 1e-3
"""Metres: points within this distance of a plane (or a line) count as lying on it."""

_COLUMNS = ("X", "Y", "Z", "x", "y")


def _names(point_names: Sequence[str] | None, n: int) -> list[str]:
    if point_names is None:
        return [f"point {i}" for i in range(n)]
    names = [str(s) for s in point_names]
    if len(names) != n:
        raise ValueError(f"point_names: expected {n} names, got {len(names)}")
    return names


def _check_pairs(world: ArrayLike, image: ArrayLike,
                 names: Sequence[str] | None) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Arrays (N, 3), (N, 2) after every check a user's point list can fail."""
    W = np.asarray(world, dtype=float)
    I = np.asarray(image, dtype=float)
    if W.ndim != 2 or W.shape[1] != 3:
        raise InputError(f"world points: expected an (N, 3) array of metres, got shape {W.shape}")
    if I.ndim != 2 or I.shape[1] != 2:
        raise InputError(f"image points: expected an (N, 2) array of pixels, got shape {I.shape}")
    if len(W) != len(I):
        raise InputError(f"expected as many image points as world points, got {len(W)} world and {len(I)} image")
    label = _names(names, len(W))
    pairs = np.hstack([W, I])
    bad = ~np.isfinite(pairs)
    if bad.any():
        i = int(np.flatnonzero(bad.any(axis=1))[0])
        cols = ", ".join(f"{c} = {pairs[i, k]}" for k, c in enumerate(_COLUMNS) if bad[i, k])
        raise InputError(f"{label[i]}: expected finite numbers, got {cols}")
    for what, A, limit, unit in (("world", W, MAX_WORLD_M, "m"), ("image", I, MAX_PIXEL, "px")):
        far = np.abs(A) > limit
        if far.any():
            i = int(np.flatnonzero(far.any(axis=1))[0])
            hint = " (world coordinates are metres: were they millimetres?)" if what == "world" else ""
            raise InputError(f"{label[i]}: expected {what} coordinates within ±{limit:g} {unit}, got "
                             f"{np.abs(A[i]).max():.4g}{hint}")
    if len(W) > MAX_POINTS:
        raise InputError(f"expected at most {MAX_POINTS:,} points, got {len(W):,}")
    if len(W) < MIN_POINTS:
        raise InputError(f"expected at least {MIN_POINTS} points (the paper advises ≥ {ADVISED_POINTS}), "
                         f"got {len(W)}")
    _, first, inverse = np.unique(W, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.ravel()
    dup = np.flatnonzero(first[inverse] != np.arange(len(W)))
    if dup.size:
        j = int(dup[0])
        i = int(first[inverse[j]])
        X, Y, Z = W[j]
        if np.array_equal(I[i], I[j]):
            raise InputError(f"{label[i]} and {label[j]} are the same pair twice "
                             f"(world ({X:g}, {Y:g}, {Z:g}) m, image ({I[j, 0]:g}, {I[j, 1]:g}) px): remove one")
        raise InputError(f"{label[i]} and {label[j]} give the same world point ({X:g}, {Y:g}, {Z:g}) m with "
                         f"different image points ({I[i, 0]:g}, {I[i, 1]:g}) and ({I[j, 0]:g}, {I[j, 1]:g}) px: "
                         "one of them is mislabelled")
    return W, I, label


def _spread(points: np.ndarray) -> tuple[np.ndarray, float, float, np.ndarray]:
    """Centroid, largest distance from the best-fit line and plane, and the principal axes (rows)."""
    c = points.mean(axis=0)
    d = points - c
    _, _, Vt = np.linalg.svd(d, full_matrices=False)     # (k, k) axes; U is (N, k): memory linear in N
    along = d @ Vt[0]
    off_line = float(np.max(np.linalg.norm(d - along[:, None] * Vt[0], axis=1)))
    off_plane = float(np.max(np.abs(d @ Vt[-1]))) if points.shape[1] == 3 else 0.0
    return c, off_line, off_plane, Vt


def _configuration(W: np.ndarray, I: np.ndarray) -> tuple[str, np.ndarray, np.ndarray]:
    """Classify the world points: ``"general"``, ``"horizontal"`` or ``"plane"``.

    Returns the kind, the centroid (3,) and a right-handed basis (3, 3) whose rows are two
    in-plane directions and the plane normal (meaningful for the planar kinds).
    """
    c, off_line, off_plane, Vt = _spread(W)
    if off_line <= PLANE_TOLERANCE:
        raise InputError(f"all world points lie on one line (within {PLANE_TOLERANCE * 1e3:g} mm), which does "
                         "not determine a camera; add points off that line")
    _, img_off_line, _, _ = _spread(I)
    if img_off_line <= 1.0:
        raise InputError("all image points lie on one line (within 1 px): the camera centre is in the plane of "
                         "the points, or the image coordinates are wrong")
    if np.ptp(W[:, 2]) <= PLANE_TOLERANCE:
        return "horizontal", c, np.eye(3)
    if off_plane <= PLANE_TOLERANCE:
        B = Vt.copy()
        B[2] = np.cross(B[0], B[1])
        return "plane", c, B
    return "general", c, np.eye(3)


def _check_intrinsics(intrinsics: ArrayLike | None) -> np.ndarray | None:
    if intrinsics is None:
        return None
    k = np.asarray(intrinsics, dtype=float).ravel()
    if k.size != 4 or not np.all(np.isfinite(k)) or k[0] <= 0 or k[1] <= 0:
        raise InputError(f"intrinsics: expected 4 finite numbers fx, fy, cx, cy (pixels) with fx, fy > 0, "
                         f"got {np.asarray(intrinsics).ravel().tolist()}")
    return np.array([[k[0], 0.0, k[2]], [0.0, k[1], k[3]], [0.0, 0.0, 1.0]])


def _radial_terms(distortion: bool | int, n: int) -> int:
    if distortion is True:
        return 2
    if distortion is False or distortion is None:
        return 0
    terms = int(distortion)
    if terms != distortion or not 0 <= terms <= 3:
        raise InputError(f"distortion: expected True/False or the number of radial terms 0 to 3, got {distortion!r}")
    if terms == 3 and n < ADVISED_POINTS:
        raise InputError(f"distortion: fitting k3 needs at least {ADVISED_POINTS} points, got {n}")
    return terms
