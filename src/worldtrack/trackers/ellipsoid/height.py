"""Measuring a person's height from a clear view, for the ellipsoid model.

The paper fixes every person at 1.65 m. From an oblique camera a wrong height moves the person
along the line of sight: the model matches the top of the head at the wrong height, i.e. at the
wrong distance — about ``Δh · d / (H − h)`` for a camera at height H and a person d metres away
(0.25 m of height error is over 1 m of depth at 8 m from a 3.6 m camera). When a camera sees a
person whole and alone, the foreground gives the height directly: the feet back-projected to
the floor, and the top of the head's viewing ray above that point.

The measurement scatters by about ±4 cm (the front of the shoes, hair, the mask's edge), which
near an oblique camera is itself 0.1 m of depth: the tracker keeps the default height unless the
running median of the measurements differs from it by more than that.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from worldtrack.foreground.components import extreme_indices
from worldtrack.geometry.camera import Camera


def measure_height(camera: Camera, labels: np.ndarray, occ: np.ndarray, xy: np.ndarray,
                   region: np.ndarray, box: tuple[int, int, int, int], max_offset_m: float = 0.4,
                   height_range_m: tuple[float, float] = (1.2, 2.2), down: np.ndarray | None = None,
                   max_depth_offset_m: float | None = None) -> float | None:
    """Height (m) of the person whose foreground lies in ``region`` of ``box``, or None.

    Parameters
    ----------
    camera : Camera
    labels : (H, W) uint8 — foreground labels (1 = foreground)
    occ : (H, W) float32 — obstacle floor distances (inf = none)
    xy : (2,) — the person's current floor position, metres
    region : (v1 − v0, u1 − u0) bool — where this person's pixels may be (its ellipse and ring)
    box : (u0, u1, v0, v1) — the region's place in the image
    max_offset_m : float — the measured feet must be this close to ``xy`` across the camera's line
        of sight (and along it, unless ``max_depth_offset_m`` is given)
    height_range_m : (min, max) — plausible heights
    down : (2,), optional — the image's world-down direction there (computed when not given)
    max_depth_offset_m : float, optional — the limit along the line of sight. A wrong model height
        puts a track too deep or too near along the ray (a 1.95 m person tracked with a 1.7 m
        ellipse 10 m away: ~0.5 m), which is what measuring the height corrects; sideways the
        feet of somebody else are what is found

    Returns
    -------
    float or None
        None when the view is not clear: too few pixels, head or feet at the image border or
        hidden by an obstacle, or a result outside the plausible range.
    """
    u0, u1, v0, v1 = box
    if u0 <= 0 or v0 <= 0 or u1 >= camera.width or v1 >= camera.height:
        return None  # the person may extend past the image border
    ends = _ends(camera, labels, region, box, down)
    if ends is None:
        return None
    top, bottom, down = ends
    if not pixel_clear(camera, occ, bottom + 2 * down):
        return None  # feet at the border or on an obstacle's edge
    feet = camera.backproject(bottom[None], 0.0)[0]
    if not np.isfinite(feet).all():
        return None
    # The feet's offset from the track, along the camera's line of sight and across it.
    off = feet[:2] - np.asarray(xy, dtype=float)
    ray = feet[:2] - camera.centre[:2]
    ray = ray / max(float(np.hypot(*ray)), 1e-9)
    along = abs(float(off @ ray))
    across = abs(float(off[0] * ray[1] - off[1] * ray[0]))
    depth_limit = max_offset_m if max_depth_offset_m is None else max_depth_offset_m
    if across > max_offset_m or along > depth_limit:
        return None
    origin, d = camera.rays(top[None])
    d = d[0]
    dxy = d[:2]
    if np.dot(dxy, dxy) < 1e-12:
        return None
    s = np.dot(feet[:2] - origin[:2], dxy) / np.dot(dxy, dxy)  # closest approach to the feet's vertical
    h = float(origin[2] + s * d[2])
    lo, hi = height_range_m
    return h if lo <= h <= hi else None


def head_ray(camera: Camera, labels: np.ndarray, occ: np.ndarray, region: np.ndarray,
             box: tuple[int, int, int, int], down: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray] | None:
    """Viewing ray (origin (3,), unit direction (3,)) through the top of a person's head, or None.

    Needs the top of the region inside the image and not on an obstacle; the feet may be hidden.
    """
    u0, u1, v0, v1 = box
    if v0 <= 0 or u0 <= 0 or u1 >= camera.width:
        return None
    ends = _ends(camera, labels, region, box, down)
    if ends is None:
        return None
    top = ends[0]
    if not pixel_clear(camera, occ, top):
        return None
    origin, d = camera.rays(top[None])
    return (origin, d[0]) if np.isfinite(d).all() else None


def pixel_clear(camera: Camera, occ: np.ndarray | None, p: np.ndarray) -> np.ndarray:
    """Whether point(s) ``p`` (..., 2), rounded to the nearest pixel, are inside the image and
    (unless ``occ`` is None) not on an obstacle (``occ`` finite there); bool (...).

    Compiled (:func:`_pixels_clear`): it is called for a handful of points at a time, where
    NumPy's per-call overhead was most of the cost. :func:`pixel_clear_reference` is the plain
    version.
    """
    q = np.asarray(p, dtype=float)
    flat = np.ascontiguousarray(q.reshape(-1, 2))
    grid = _NO_OCC if occ is None else occ
    out = _pixels_clear(flat, camera.width, camera.height, grid, occ is not None)
    return out.reshape(q.shape[:-1]) if q.ndim > 1 else out[0]


#: Stands in for "no obstacle map" in the compiled :func:`_pixels_clear`.
_NO_OCC = np.zeros((1, 1), np.float32)


@njit(cache=True)
def _pixels_clear(p: np.ndarray, width: int, height: int, occ: np.ndarray, use_occ: bool) -> np.ndarray:
    """(N,) bool for points ``p`` (N, 2): rounded (half to even) inside the image and, with
    ``use_occ``, where ``occ`` is not finite."""
    out = np.empty(p.shape[0], dtype=np.bool_)
    for i in range(p.shape[0]):
        u = np.rint(p[i, 0])
        v = np.rint(p[i, 1])
        ok = 0 <= u < width and 0 <= v < height
        if ok and use_occ:
            ok = not np.isfinite(occ[int(v), int(u)])
        out[i] = ok
    return out


def pixel_clear_reference(camera: Camera, occ: np.ndarray | None, p: np.ndarray) -> np.ndarray:
    """:func:`pixel_clear` in plain NumPy, the version it is tested against."""
    q = np.round(p).astype(int)
    u, v = q[..., 0], q[..., 1]
    inside = (u >= 0) & (u < camera.width) & (v >= 0) & (v < camera.height)
    if occ is None:
        return inside
    return inside & ~np.isfinite(occ[np.clip(v, 0, camera.height - 1), np.clip(u, 0, camera.width - 1)])


def triangulate_height(rays: list[tuple[np.ndarray, np.ndarray]], xy: np.ndarray, max_offset_m: float = 0.5,
                       min_angle_deg: float = 25.0,
                       height_range_m: tuple[float, float] = (1.2, 2.2),
                       max_ray_gap_m: float = float("inf")) -> float | None:
    """Height of the point nearest to the head rays of several cameras, or None.

    Two cameras looking from different directions pin the top of the head in 3-D without the
    feet: the least-squares point closest to all rays. None when the rays' directions on the
    floor differ by less than ``min_angle_deg`` (nearly parallel rays pin nothing), the point
    is more than ``max_offset_m`` from the person's floor position ``xy``, or some ray passes
    farther than ``max_ray_gap_m`` from it: rays through the tops of two different heads (one
    view's top of the region is a taller person's behind) still have a nearest point, at the
    wrong height.

    Parameters
    ----------
    rays : list of (origin (3,), unit direction (3,)) — head rays, metres
    xy : (2,) — the person's floor position, metres
    max_offset_m, max_ray_gap_m : float, metres
    min_angle_deg : float, degrees
    height_range_m : (min, max) metres — plausible heights
    """
    if len(rays) < 2:
        return None
    flat = [d[:2] / np.linalg.norm(d[:2]) for _, d in rays if np.linalg.norm(d[:2]) > 1e-6]
    if len(flat) < 2:
        return None
    spread = max(np.degrees(np.arccos(np.clip(abs(a @ b), -1, 1))) for i, a in enumerate(flat) for b in flat[i + 1:])
    if spread < min_angle_deg:
        return None
    # Each ray's projector onto the plane normal to it: M·(p − o) is p's offset from the ray.
    normal = [np.eye(3) - np.outer(d, d) for _, d in rays]
    p = np.linalg.solve(sum(normal), sum(M @ o for M, (o, _) in zip(normal, rays)))
    lo, hi = height_range_m
    if np.hypot(*(p[:2] - xy)) > max_offset_m or not lo <= p[2] <= hi:
        return None
    if max(np.linalg.norm(M @ (p - o)) for M, (o, _) in zip(normal, rays)) > max_ray_gap_m:
        return None
    return float(p[2])


#: Fewer foreground pixels than this in a person's region: no ends are looked for.
_MIN_PIXELS = 30


def _ends(camera: Camera, labels: np.ndarray, region: np.ndarray, box: tuple[int, int, int, int],
          down: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Top and bottom (pixels) of the foreground in ``region`` along the image's world-down
    direction, and that direction; None with fewer than ``_MIN_PIXELS`` pixels.

    The ends are the means of the extreme 1 % of the pixels along ``down`` (:func:`extreme_ends`),
    moved half a pixel outwards.
    """
    u0, u1, v0, v1 = (int(b) for b in box)
    if down is None:
        fg = (labels[v0:v1, u0:u1] == 1) & region
        vs, us = np.nonzero(fg)
        if len(vs) < _MIN_PIXELS:
            return None
        down = camera.image_down_direction(np.array([[us.mean() + u0, vs.mean() + v0]]))[0]
    if not np.isfinite(down).all():
        return None
    n, top, bottom = extreme_ends(labels, region, u0, v0, float(down[0]), float(down[1]))
    if n < _MIN_PIXELS:
        return None
    return top - 0.5 * down, bottom + 0.5 * down, down


@njit(cache=True)
def extreme_ends(labels: np.ndarray, region: np.ndarray, u0: int, v0: int, dx: float,
                 dy: float) -> tuple[int, np.ndarray, np.ndarray]:
    """The foreground pixels (``labels == 1``) of ``region`` and their two ends along (dx, dy).

    Parameters
    ----------
    labels : (H, W) uint8 — foreground labels of the whole image
    region : (h, w) bool — where to look, its top-left pixel at (u0, v0) of ``labels``
    dx, dy : float — unit image direction

    Returns
    -------
    n : int — foreground pixels in the region
    first, last : (2,) float — image coordinates (u, v), the mean of the ``max(1, n // 100)``
        pixels lowest / highest along (dx, dy) (their coordinate along it taken from the pixels'
        centroid); ties at the cut are taken in row-major order (a stable sort's). NaN when n = 0.
    """
    h, w = region.shape
    us = np.empty(h * w, np.int64)
    vs = np.empty(h * w, np.int64)
    n = 0
    su = 0.0
    sv = 0.0
    for r in range(h):
        for c in range(w):
            if region[r, c] and labels[v0 + r, u0 + c] == 1:
                us[n] = u0 + c
                vs[n] = v0 + r
                su += u0 + c
                sv += v0 + r
                n += 1
    first = np.full(2, np.nan)
    last = np.full(2, np.nan)
    if n == 0:
        return n, first, last
    cu = su / n
    cv = sv / n
    along = np.empty(n)
    for i in range(n):
        along[i] = (us[i] - cu) * dx + (vs[i] - cv) * dy
    n_end = max(1, n // 100)
    for out, lowest in ((first, True), (last, False)):
        tu = 0.0
        tv = 0.0
        for i in extreme_indices(along, n_end, lowest):
            tu += us[i]
            tv += vs[i]
        out[0] = tu / n_end
        out[1] = tv / n_end
    return n, first, last


def extreme_ends_reference(labels: np.ndarray, region: np.ndarray, u0: int, v0: int, dx: float,
                           dy: float) -> tuple[int, np.ndarray, np.ndarray]:
    """Plain NumPy version of :func:`extreme_ends` (a stable sort instead of selection)."""
    h, w = region.shape
    vs, us = np.nonzero((labels[v0:v0 + h, u0:u0 + w] == 1) & region)
    n = len(us)
    if n == 0:
        return 0, np.full(2, np.nan), np.full(2, np.nan)
    us, vs = us + u0, vs + v0
    along = (us - us.mean()) * dx + (vs - vs.mean()) * dy
    n_end = max(1, n // 100)
    order = np.argsort(along, kind="stable")
    low = order[:n_end]
    # The highest: strictly above the n_end-th largest value, then its ties in row-major order.
    cut = along[order[n - n_end]]
    above = np.flatnonzero(along > cut)
    high = np.concatenate([above, np.flatnonzero(along == cut)[:n_end - len(above)]])
    return n, np.array([us[low].mean(), vs[low].mean()]), np.array([us[high].mean(), vs[high].mean()])
