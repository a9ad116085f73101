"""Measuring a person's height from a clear view, for the ellipsoid model.

>>> import numpy as np
>>> o1, o2, head = np.array([0.0, 0.0, 3.5]), np.array([4.0, 0.5, 3.2]), np.array([1.0, 2.0, 1.78])
>>> rays = [(o, (head - o) / np.linalg.norm(head - o)) for o in (o1, o2)]
>>> round(triangulate_height(rays, np.array([1.0, 2.0])), 3)        # two views of the head
1.78

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

from typing import Mapping, Sequence

from worldtrack.foreground.components import extreme_indices
from worldtrack.geometry.camera import Camera
from worldtrack.trackers.base import Person
from worldtrack.trackers.ellipsoid.border import cut_by_border
from worldtrack.trackers.ellipsoid.cameras import CameraView, pixel_clear
from worldtrack.trackers.ellipsoid.config import HeightConfig
from worldtrack.trackers.ellipsoid.forms import ellipse_crop, owner_crop
from worldtrack.trackers.ellipsoid.height_reset import watch_samples
from worldtrack.trackers.ellipsoid.height_sigma import height_estimate
from worldtrack.trackers.ellipsoid.height_views import add_samples

#: A person's height is measured in a view where others' ellipses cover at most this share of its region.
MAX_COVERED_FOR_HEIGHT = 0.3


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
    found = measure_feet(camera, labels, occ, xy, region, box, max_offset_m, down, max_depth_offset_m)
    if found is None:
        return None
    h = found[1]
    lo, hi = height_range_m
    return h if lo <= h <= hi else None


def measure_feet(camera: Camera, labels: np.ndarray, occ: np.ndarray, xy: np.ndarray,
                 region: np.ndarray, box: tuple[int, int, int, int], max_offset_m: float = 0.4,
                 down: np.ndarray | None = None, max_depth_offset_m: float | None = None,
                 border: str = "box") -> tuple[np.ndarray, float] | None:
    """The feet's floor point (3,) and the height (m) of the top of the head's ray above it, of
    the person whose foreground lies in ``region`` of ``box``, or None (parameters and the
    conditions as :func:`measure_height`, which is this without a height range). ``border``: how
    a person at the image's edge is told (:func:`cut_by_border`)."""
    if cut_by_border(camera, labels, region, box, border=border):
        return None  # the person may extend past the image border
    ends = silhouette_ends(camera, labels, region, box, down)
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
    return feet, float(origin[2] + s * d[2])


def head_ray(camera: Camera, labels: np.ndarray, occ: np.ndarray, region: np.ndarray,
             box: tuple[int, int, int, int], down: np.ndarray | None = None,
             border: str = "box") -> tuple[np.ndarray, np.ndarray] | None:
    """Viewing ray (origin (3,), unit direction (3,)) through the top of a person's head, or None.

    Needs the top of the region inside the image and not on an obstacle; the feet may be hidden.
    ``border`` as :func:`measure_feet`'s.
    """
    if cut_by_border(camera, labels, region, box, bottom=False, border=border):
        return None
    ends = silhouette_ends(camera, labels, region, box, down)
    if ends is None:
        return None
    top = ends[0]
    if not pixel_clear(camera, occ, top):
        return None
    origin, d = camera.rays(top[None])
    return (origin, d[0]) if np.isfinite(d).all() else None


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


def silhouette_ends(camera: Camera, labels: np.ndarray, region: np.ndarray, box: tuple[int, int, int, int],
          down: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Top and bottom pixels (2,) of the foreground (label 1) in ``region`` along the image's world-down
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


# ---------------------------------------------------------------- the tracker's running estimate


def heights_due(people: Sequence[Person], config: HeightConfig, frame: int) -> list[int]:
    """Indices of ``people`` whose height is measured this frame (``frame``: the tracker's count).

    Every frame until a person has 10 measurements (or 20 frames were tried: someone always in a
    group rarely gives one), then one frame in five until ``config.samples`` are in: a person's
    height does not change, and the median of that many is final — unless ``config.prefer_large``:
    then one frame in five for as long as they are tracked, so that nearer views can replace far
    ones (:mod:`.height_views`), or ``config.reset_sigmas`` > 0: to see a new height (:mod:`.height_reset`).
    """
    return [k for k, p in enumerate(people) if p.mode == "tracking"
            and (len(p.height_samples) < config.samples or config.prefer_large or config.reset_sigmas > 0)
            and ((len(p.height_samples) < 10 and p.height_tries < 20) or (frame + p.id) % 5 == 0)]


def update_heights(people: Sequence[Person], due: Sequence[int], views: Mapping[str, CameraView],
                   labels: Mapping[str, np.ndarray], default_height, config: HeightConfig) -> None:
    """Measure the heights of ``people[k]`` for ``k`` in ``due``; keep each one's running median.

    In one camera, a tracked person is measured when others' ellipses cover at most
    :data:`MAX_COVERED_FOR_HEIGHT` of its region (the tallest plausible person's ellipse with its
    ring), on the pixels nobody else covers; the feet found may be up to ``depth_offset_m`` from
    the track along the line of sight (a wrong model height puts it there). Head rays of two
    cameras or more are triangulated instead. The measured median replaces a person's height
    once 3 samples are in and it differs from ``default_height(id)`` (m) by more than
    ``deadband_m``; a person never measured keeps the default (the paper's 1.65 m).

    Parameters
    ----------
    people : the people on the map this tracker sees (their ellipses own the pixels)
    due : indices into ``people`` (:func:`heights_due`)
    views, labels : the tracker's cameras and their foreground labels, by camera id
    default_height : callable — person id → default height, m
    config : HeightConfig
    """
    if not due:
        return
    for k in due:
        people[k].height_tries += 1
    xy = np.array([[p.x, p.y] for p in people], dtype=float).reshape(-1, 2)
    hs = np.array([p.height for p in people], dtype=float)
    ws = np.array([p.width for p in people], dtype=float)
    samples_now: dict[int, list[tuple[float, float]]] = {}
    rays: dict[int, list] = {}
    for cid, image_labels in labels.items():
        _measure_in_view(views[cid], image_labels, (xy, hs, ws), due, config, len(labels) >= 2, (samples_now, rays))
    lo, hi = config.range_m
    for k, p in enumerate(people):
        # Two views of the head from different sides beat any single view.
        head_rays = rays.get(k, [])
        h3 = triangulate_height(head_rays, xy[k], height_range_m=(lo, hi), max_ray_gap_m=config.ray_gap_m)
        if h3 is not None:
            new = [(h3, np.inf)]
        elif len(head_rays) >= 2:
            # Head rays from two views or more that give no height (they miss each other, or meet
            # off the person or outside the plausible range): some view's "head" is most likely
            # somebody else's, and that view's single-camera measurement would be no better.
            new = []
        else:
            new = samples_now.get(k, [])
        if not new:
            continue
        add_samples(p, watch_samples(p, new, config), config)
        if len(p.height_samples) >= 3:
            p.height = height_estimate(p.height_samples, default_height(p.id), config)


def _measure_in_view(view: CameraView, labels: np.ndarray, people: tuple[np.ndarray, np.ndarray, np.ndarray],
                     due: Sequence[int], config: HeightConfig, triangulate: bool,
                     out: tuple[dict[int, list[tuple[float, float]]], dict[int, list]]) -> None:
    """One camera's height measurements (height m, the view's size px, into ``out[0]``) and head rays (``out[1]``, with
    ``triangulate``) of the people ``due``, by index; ``people`` = (xy (N, 2), heights, widths)."""
    samples_now, rays = out
    xy, hs, ws = people
    lo, hi = config.range_m
    cam = view.camera
    # Where a person's pixels may be: the ellipse of the tallest plausible person (a 1.9 m person
    # sticks out of a 1.65 m ellipse), with its ring.
    _, ring, box, valid, _ = view.forms(xy, np.full(len(xy), hi), 1.25 * ws)
    current = view.forms(xy, hs, ws)
    for k in due:
        if not valid[k]:
            continue
        b = box[k]
        u0, u1, v0, v1 = b
        if u0 >= u1 or v0 >= v1:
            continue
        region = ellipse_crop(ring[k], b, view.grid, cam.has_distortion)
        down = view.down_direction(np.array([(u0 + u1) / 2, (v0 + v1) / 2]))
        if down is None:
            continue
        # Who each pixel of the box belongs to (current ellipses): −1 nobody, −2 several people.
        owner = owner_crop(b, current, view.grid, cam.has_distortion)
        free = (owner == k) | (owner == -1)
        if triangulate:
            ray = head_ray(cam, labels, view.occ, region & free, tuple(b), down)
            if ray is not None:
                rays.setdefault(k, []).append(ray)
        # Clear enough in this view: others' ellipses cover little of the region; their pixels
        # are left out of it.
        if np.count_nonzero(region & ~free) > MAX_COVERED_FOR_HEIGHT * np.count_nonzero(region):
            continue
        region = region & free
        # One camera alone: only oblique views that show the person large — from above, height is
        # neither measurable nor needed; small, it is noise.
        flat = np.hypot(*(xy[k] - cam.centre[:2]))
        if flat < cam.centre[2] - 0.5 * hs[k] or (b[3] - b[2]) < config.min_px:
            continue
        h = measure_height(cam, labels, view.occ, xy[k], region, tuple(b), height_range_m=(lo, hi), down=down,
                           max_depth_offset_m=config.depth_offset_m)
        if h is not None:
            samples_now.setdefault(k, []).append((h, float(v1 - v0)))


__all__ = ["MAX_COVERED_FOR_HEIGHT", "extreme_ends", "extreme_ends_reference", "head_ray", "heights_due",
           "measure_feet", "measure_height", "silhouette_ends", "triangulate_height", "update_heights"]
