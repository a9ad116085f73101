"""The small typed containers the ellipsoid tracker's compiled kernels take (NamedTuples).

A kernel takes a handful of these instead of a long list of positional arrays: a camera
(:class:`CameraArgs`), people's ellipses in it (:class:`Forms`), how ellipses are drawn
(:class:`DrawArgs`) and scored (:class:`ScoreArgs`). NamedTuples of arrays and scalars are
passed to Numba's nopython mode as they are; a tuple of several cameras' :class:`CameraArgs` is
indexed by camera inside the matching rounds. No Numba here: this module is light to import.

>>> import numpy as np
>>> draw = DrawArgs(min_depth=0.1, ring_fraction=2.0)
>>> draw.ring_fraction
2.0
>>> f = Forms.empty(3)
>>> f.inner.shape, f.box.dtype.name, bool(f.valid.any())
((3, 5), 'int64', False)
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

#: The ideal-pixel grid of a camera without lens distortion (never read: a placeholder of the
#: right type, so that every camera's :class:`CameraArgs` has the same Numba type).
NO_GRID = np.zeros((1, 1, 2), dtype=np.float32)


class CameraArgs(NamedTuple):
    """One camera as the kernels read it (everything constant from frame to frame).

    Attributes
    ----------
    P : (3, 4) float64 — camera matrix, normalised (third row = depth along the optical axis)
    K : (3, 3) float64 — intrinsics; dist : (5,) float64 — OpenCV's k1, k2, p1, p2, k3
    has_dist : bool — lens distortion present (pixels are tested at their ideal positions)
    width, height : int — image size, pixels
    centre : (3,) float64 — the camera's centre, metres
    floor_direction : (2,) float64 — unit floor projection of the viewing direction
    ring_px : float — width of the −1 ring of the ternary images at this image size, pixels
    grid : (H, W, 2) float32 — ideal (undistorted) position of each pixel (:data:`NO_GRID`
        without distortion)
    occ : (H, W) float32 — floor distance (m) of the nearest obstacle seen at each pixel (inf:
        none; paper 000 §3.3)
    """

    P: np.ndarray
    K: np.ndarray
    dist: np.ndarray
    has_dist: bool
    width: int
    height: int
    centre: np.ndarray
    floor_direction: np.ndarray
    ring_px: float
    grid: np.ndarray
    occ: np.ndarray


def camera_args(camera, ring_px: float, occ: np.ndarray | None = None) -> CameraArgs:
    """The :class:`CameraArgs` of a :class:`~worldtrack.geometry.camera.Camera`.

    Arrays are writable C-contiguous copies of fixed dtypes, so every camera's arguments have
    one Numba type (a tuple of several is indexed in the compiled rounds).

    Parameters
    ----------
    camera : Camera
    ring_px : float — ring width, pixels
    occ : (H, W) float, optional — obstacle floor distances (default: none, all inf)
    """
    if occ is None:
        occ = np.full((camera.height, camera.width), np.inf, np.float32)
    grid = np.array(camera.ideal_pixel_grid, dtype=np.float32) if camera.has_distortion else NO_GRID.copy()
    f64 = np.float64
    return CameraArgs(np.array(camera.P, f64), np.array(camera.K, f64), np.array(camera.dist, f64),
                      bool(camera.has_distortion), int(camera.width), int(camera.height),
                      np.array(camera.centre, f64), np.array(camera.floor_direction, f64), float(ring_px),
                      np.ascontiguousarray(grid), np.array(occ, dtype=np.float32))


class DrawArgs(NamedTuple):
    """How people's ellipses are drawn (the same in every camera).

    Attributes
    ----------
    min_depth : float — an ellipsoid nearer than this to a camera's image plane is not drawn, m
    ring_fraction : float — the ring is at most this fraction of the ellipse's semi-minor axis
        (0: always the camera's ``ring_px``)
    """

    min_depth: float
    ring_fraction: float


class ScoreArgs(NamedTuple):
    """How eq. 5 is summed for one person's candidates.

    Attributes
    ----------
    use_ring : bool — the −1 ring in both images (False in capture mode)
    target_pixels : int — visit about this many pixels per candidate set (0: all)
    count_unexplained : bool — add the foreground that no ellipse covers to the denominator
    """

    use_ring: bool
    target_pixels: int
    count_unexplained: bool


class Forms(NamedTuple):
    """People's ellipses in one camera (N of them), as :func:`~.forms.ellipse_forms` gives them.

    Attributes
    ----------
    inner : (N, 5) float64 — normal forms ``(cx, cy, a11, a12, a22)`` of the ellipses
    ring : (N, 5) float64 — normal forms of the ellipses grown by the ring
    box : (N, 4) int64 — ``u0, u1, v0, v1`` (end exclusive) of the ring ellipse in the image
    valid : (N,) bool — in front of the camera, outline an ellipse
    dist : (N,) float64 — floor distance from the camera, m (against ``CameraArgs.occ``)
    """

    inner: np.ndarray
    ring: np.ndarray
    box: np.ndarray
    valid: np.ndarray
    dist: np.ndarray

    @classmethod
    def empty(cls, n: int) -> "Forms":
        """Forms of ``n`` people none of whom is drawn."""
        return cls(np.zeros((n, 5)), np.zeros((n, 5)), np.zeros((n, 4), np.int64), np.zeros(n, np.bool_),
                   np.zeros(n))


class Window(NamedTuple):
    """The pixels a kernel visits: rows ``vs, vs + stride, … < v1``, columns ``us, … < u1``."""

    vs: int
    v1: int
    us: int
    u1: int
    stride: int


class Sums(NamedTuple):
    """Per candidate (C,): eq. 5's numerator and denominator, and the visited pixels inside it."""

    num: np.ndarray
    den: np.ndarray
    n_in: np.ndarray


class People(NamedTuple):
    """Everybody in the joint image: floor positions (N, 2) m, heights (N,) m, widths (N,) m."""

    xy: np.ndarray
    heights: np.ndarray
    widths: np.ndarray


class Walkable(NamedTuple):
    """The walkable floor as a raster: ``inside`` (rows y, columns x) bool, ``origin`` (2,) m of
    cell (0, 0)'s corner, ``resolution`` m per cell."""

    inside: np.ndarray
    origin: np.ndarray
    resolution: float


class Scoring(NamedTuple):
    """How a frame's candidates are drawn and scored (the same for every person and camera).

    Attributes
    ----------
    draw : DrawArgs
    target_pixels : int — pixels visited per candidate set (0: all)
    symmetric : bool — count the foreground no ellipse explains, for tracked people
    held : bool — with several cameras, weigh each camera as at a tracked person's current place
    fixed_pixels : bool — with ``held``, also score each camera on the pixels counted at the current
        place (:mod:`.fixed_pixels`)
    """

    draw: DrawArgs
    target_pixels: int
    symmetric: bool
    held: bool
    fixed_pixels: bool = False


class StepArgs(NamedTuple):
    """The matching steps (paper: s = 50 mm, K = 3 rounds) and worldtrack's adaptive steps.

    Attributes
    ----------
    step_m, min_step_m, max_step_m : float — first step and the adaptive step's limits, m
    iterations, max_iterations : int — rounds (K), and the cap on rounds with the adaptive step
    adaptive : bool — halve the step on "stay", double it when still moving after K rounds
    min_gain : float — with the adaptive step, a smaller gain of E counts as "stay"
    """

    step_m: float
    min_step_m: float
    max_step_m: float
    iterations: int
    max_iterations: int
    adaptive: bool
    min_gain: float


__all__ = ["CameraArgs", "DrawArgs", "Forms", "NO_GRID", "People", "ScoreArgs", "Scoring", "StepArgs", "Sums", "Walkable",
           "Window", "camera_args"]
