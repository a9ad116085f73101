"""One tall person, or two people on one line of sight? The head's size tells.

From one camera, a short person with somebody farther away behind them on the same line of sight
makes one silhouette whose top is the *farther* person's head: read as one person, the head
above the near person's feet gives a height that is wrong but plausible (2.05 m for 1.69 m), the
tall ellipse then explains the farther head, and that person is never born (issue 37).

A head has about the same size on everybody (``HEAD_WIDTH_M``, 15–18 cm with hair). The width of
the silhouette's top, just under its highest point, measured in pixels, against the width a head
would have at the depth the *feet* give: about 1 for one person, about ``d_near / d_far`` (0.5–0.8)
when the top is somebody farther away.

How well it separates them (``benchmarks/two_on_ray_cue.py``: people in clear view read at their
true place on the line-of-sight scenario, the renderer saying whose head tops the silhouette):
below 0.8 for 55–71 % of the readings topped by somebody else's head and 5 cm or more wrong, and
for 1.4–2.3 % of those topped by the person's own. Not enough to decide alone, measured in the
tracker (issue 37, line-of-sight scenario, development seeds 20–39 / never-used 140–149):
taking no height from a silhouette below 0.8 lost MOTA (0.740 → 0.717 / 0.738 → 0.686), none
from a birth blob below it was neutral (0.747 / 0.728), and proposing a person along the top's
ray made phantoms that took over tracks (0.666 on 20–39). So nothing in the tracker uses it yet;
a model selection that also renders the two hypotheses (paper 000's analysis by synthesis) would.

>>> import numpy as np
>>> from worldtrack.geometry import Camera
>>> cam = Camera.look_at("c", 640, 480, position=(0, 0, 2.8), target=(0, 7, 0.6), hfov_deg=62)
>>> feet, top = np.array([0.0, 5.0, 0.0]), np.array([0.0, 5.0, 1.7])
>>> w = head_width_px(cam, feet, cam.project(top[None])[0])   # a head 5 m away: ~17 px wide
>>> bool(15 < w < 19)
True
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from worldtrack.geometry.camera import Camera
from worldtrack.trackers.ellipsoid.cameras import CameraView
from worldtrack.trackers.ellipsoid.height import silhouette_ends

#: Width of a head seen from any side, hair included, m (adults' head breadth 0.15–0.16 m, length 0.19–0.20 m).
HEAD_WIDTH_M = 0.16
#: The top of a silhouette is the mean of this many of its highest foreground pixels.
TOP_PIXELS = 5
#: The head band: the silhouette's rows from this far below its top ...
BAND_FROM_M = 0.04
#: ... to this far, in metres at the feet's depth (at a farther person's depth it is still their head).
BAND_TO_M = 0.13


class TopOfSilhouette(NamedTuple):
    """The top of a silhouette: its highest pixel (2,) (u, v) and the width (px) of its head band."""

    top: np.ndarray
    width_px: float


def top_of_silhouette(labels: np.ndarray, region: np.ndarray, box: tuple[int, int, int, int], down: np.ndarray,
                      band_px: tuple[float, float]) -> TopOfSilhouette | None:
    """The highest foreground pixel of ``region`` along ``down`` and the silhouette's median width
    over the band ``band_px`` = (from, to) px below it, or None with too few pixels.

    Parameters
    ----------
    labels : (H, W) uint8 — foreground labels of the whole image (1 = foreground)
    region : (v1 − v0, u1 − u0) bool — where the person's pixels may be
    box : (u0, u1, v0, v1) — the region's place in the image
    down : (2,) — unit image direction of world-down there
    band_px : (from, to) — the head band, px below the top along ``down``

    The top is the mean of the :data:`TOP_PIXELS` highest foreground pixels (not a share of them, as
    :func:`.height.extreme_ends` takes: a far head is a small part of a merged silhouette); the width of one 1-px slice across ``down`` is the extent of its pixels that are not background
    (foreground or "unsure": a face or dark hair is often the latter).
    """
    u0, u1, v0, v1 = (int(b) for b in box)
    crop = labels[v0:v1, u0:u1]
    vs, us = np.nonzero((crop == 1) & region)
    if len(us) < 30:
        return None
    dx, dy = float(down[0]), float(down[1])
    along = (us + u0) * dx + (vs + v0) * dy
    n_end = min(TOP_PIXELS, len(along))
    first = np.argpartition(along, n_end - 1)[:n_end]
    top_along = float(along[first].mean())
    top = np.array([us[first].mean() + u0, vs[first].mean() + v0]) - 0.5 * np.array([dx, dy])
    # The band's slices, on every pixel that is not background (a face or dark hair is often "unsure").
    vs, us = np.nonzero((crop > 0) & region)
    us, vs = us + u0, vs + v0
    rel = us * dx + vs * dy - top_along
    lo, hi = band_px
    in_band = (rel >= lo) & (rel < max(hi, lo + 1.0))
    if not in_band.any():
        return None
    slices = np.floor(rel[in_band] - lo).astype(np.int64)
    across = (vs * dx - us * dy)[in_band]
    n = int(slices.max()) + 1
    left = np.full(n, np.inf)
    right = np.full(n, -np.inf)
    np.minimum.at(left, slices, across)
    np.maximum.at(right, slices, across)
    seen = np.isfinite(left)
    return TopOfSilhouette(top, float(np.median(right[seen] - left[seen] + 1.0)))


def head_width_px(camera: Camera, feet: np.ndarray, top_px: np.ndarray, width_m: float = HEAD_WIDTH_M) -> float:
    """Width (px) a head ``width_m`` wide would have with its top at pixel ``top_px`` (2,) over the
    floor point ``feet`` (2+,): at the depth the feet give (nan where the top's ray does not pass over
    the feet)."""
    origin, d = camera.rays(np.asarray(top_px, float)[None])
    d = d[0]
    flat = float(d[:2] @ d[:2])
    if not np.isfinite(d).all() or flat < 1e-9:
        return float("nan")
    s = float((np.asarray(feet[:2], float) - origin[:2]) @ d[:2] / flat)
    if s <= 0:
        return float("nan")
    head = origin + s * d
    side = np.array([-d[1], d[0], 0.0]) / np.sqrt(flat)
    uv = camera.project(np.array([head - 0.5 * width_m * side, head + 0.5 * width_m * side]))
    return float(np.hypot(*(uv[1] - uv[0])))


def band_px(camera: Camera, feet: np.ndarray, top_px: np.ndarray) -> tuple[float, float]:
    """The head band (from, to) in px below the top, for a person whose feet are at ``feet``: ``BAND_FROM_M``
    and ``BAND_TO_M`` at the depth the feet give (the head's width in px scales the same way)."""
    scale = head_width_px(camera, feet, top_px, 1.0)
    return BAND_FROM_M * scale, BAND_TO_M * scale


def head_scale(camera: Camera, labels: np.ndarray, region: np.ndarray, box: tuple[int, int, int, int],
               down: np.ndarray, feet: np.ndarray, top_px: np.ndarray) -> float:
    """The silhouette's head width over the width of a head at the feet's depth: ~1 for one person,
    ~``d_near / d_far`` when its top is somebody farther along the ray; nan when not measurable.

    ``top_px`` is the top the caller found (it sets the band's size; the band is measured from the top
    found here).
    """
    band = band_px(camera, feet, top_px)
    if not np.isfinite(band).all():
        return float("nan")
    found = top_of_silhouette(labels, region, box, down, band)
    if found is None:
        return float("nan")
    return found.width_px / head_width_px(camera, feet, found.top)


def silhouette_ratio(view: CameraView, labels: np.ndarray, region: np.ndarray, box: tuple[int, int, int, int],
                     down: np.ndarray) -> tuple[float, np.ndarray | None, np.ndarray | None]:
    """(:func:`head_scale`, the top pixel (2,), the feet's floor point (3,)) of the silhouette in
    ``region``; (nan, None, None) where the region touches the image border or shows too few pixels."""
    cam = view.camera
    u0, u1, v0, v1 = box
    if u0 <= 0 or v0 <= 0 or u1 >= cam.width or v1 >= cam.height:
        return float("nan"), None, None
    ends = silhouette_ends(cam, labels, region, box, down)
    if ends is None:
        return float("nan"), None, None
    top, bottom, down = ends
    feet = cam.backproject(bottom[None], 0.0)[0]
    if not np.isfinite(feet).all():
        return float("nan"), None, None
    return head_scale(cam, labels, region, box, down, feet, top), top, feet


__all__ = ["BAND_FROM_M", "BAND_TO_M", "HEAD_WIDTH_M", "TOP_PIXELS", "TopOfSilhouette", "band_px", "head_scale",
           "head_width_px", "silhouette_ratio", "top_of_silhouette"]
