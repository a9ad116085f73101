"""Births in a crowd one camera sees: a small head band above somebody known is a person.

In a crowd seen from one corner, somebody standing behind a tracked person often shows no more
than the top of the head and the shoulders above that person's ellipse; what the births' residual
(:mod:`.births`: the foreground less everybody's dilated ellipses, opened) leaves of it is a sliver,
mostly under the births' smallest blob (issue 37, crowd 50 seed 109: of the people at least half
visible with no track, 22 % had their head top on foreground no ellipse explains, in pieces of
median 35 px against a smallest blob of 160 px), and they are never proposed.

With ``crowd.births_head_bands`` a blob below that size is still a person where it looks like the
top of one (:func:`is_head_band`):

* nothing is above it — the pixels just above its top are background (the top of the silhouette,
  not a gap between two known ellipses inside it);
* its lower end lies on known people's ellipses (:func:`~.people_edges.ends_on_people`): the rest
  of the person is behind them;
* it holds at least :data:`MIN_HEAD_SHARE` of a head's square at that place (the head's width at
  the default height along the top's ray: :func:`head_px`).

It is placed by its top at the default height (:func:`~.births.blob_position` with the known people
given), as a head band past people is.

Head bands cost the cold start (false positives: a candidate's own head above a track drawn
shorter than the person, a band on a candidate's ellipse). With ``crowd.head_bands_confirmed`` the
lower end must lie on *confirmed* people's ellipses and the top must be outside those ellipses drawn
at the tallest plausible height (:func:`confirmed_images`): a band that a confirmed person's own head
could be is not somebody behind.

>>> import numpy as np
>>> mask = np.zeros((30, 20), np.uint8); mask[10:30, 5:15] = 1          # a silhouette
>>> explained = np.zeros_like(mask); explained[14:, :] = 1               # a known person below row 14
>>> band = mask[10:14, 5:15].astype(bool)                                 # what is left above them
>>> is_head_band(mask, explained, band, (5, 10), np.array([0.0, 1.0]), head=4.0)
True
>>> is_head_band(mask, np.zeros_like(mask), band, (5, 10), np.array([0.0, 1.0]), head=4.0)
False
"""

from __future__ import annotations

import cv2
import numpy as np

from worldtrack.trackers.ellipsoid.args import People
from worldtrack.trackers.ellipsoid.forms import ellipse_crop
from worldtrack.trackers.ellipsoid.people_edges import BEYOND_PX, covered_share, ends_on_people

#: A head band holds at least this share of the square of a head's width (px) at its place.
MIN_HEAD_SHARE = 0.25
#: A head's width, m (with hair; as :mod:`.two_on_ray`'s 15–18 cm).
HEAD_WIDTH_M = 0.17
#: The tallest person (m): ``height.range_m``'s maximum (the default's).
TALLEST_M = 2.1


def head_px(cam, top_px: np.ndarray, height: float) -> float:
    """Width (px) of a head whose top is at image point ``top_px`` (2,), the person standing where
    that ray is ``height`` m above the floor (NaN where the ray does not come down there)."""
    p = cam.backproject(np.asarray(top_px, float)[None], height)[0]
    if not np.isfinite(p).all():
        return float("nan")
    ends = cam.project(np.array([[p[0], p[1], height - 0.1], [p[0] + HEAD_WIDTH_M, p[1], height - 0.1],
                                 [p[0], p[1] + HEAD_WIDTH_M, height - 0.1]]))
    return float(max(np.hypot(*(ends[1] - ends[0])), np.hypot(*(ends[2] - ends[0]))))


def is_head_band(mask: np.ndarray, explained: np.ndarray, blob: np.ndarray, origin: tuple[int, int],
                 down: np.ndarray | None, head: float, tall: np.ndarray | None = None) -> bool:
    """Whether ``blob`` ((h, w) bool crop at ``origin`` (u, v) px) is the top of a person behind
    known people.

    Parameters
    ----------
    mask : (H, W) uint8 — the foreground (nonzero)
    explained : (H, W) uint8 — nonzero where the known people's ellipses lie
    blob : (h, w) bool — the band's pixels
    origin : (u, v) — the crop's top-left pixel
    down : (2,) — unit image direction of world-down there (None: not known, not a band)
    head : float — a head's width at the band's place, px (:func:`head_px`)
    tall : (H, W) bool or None — nonzero where the people under the band would be at their tallest
        (:func:`confirmed_images`): the band's top must be outside (None: not looked at)
    """
    if down is None or not np.isfinite(head) or blob.sum() < MIN_HEAD_SHARE * head * head:
        return False
    v, u = np.nonzero(blob)
    pts = np.column_stack([u + origin[0], v + origin[1]]).astype(float)
    along = pts @ down
    across = np.array([-down[1], down[0]])
    top, bottom = pts[np.argmin(along)], pts[np.argmax(along)]
    half = max(1.0, 0.4 * float(np.ptp(pts @ across)))
    feet_on, _ = ends_on_people(explained, bottom, top, down, half)
    above = top - BEYOND_PX * down + np.linspace(-half, half, 9)[:, None] * across
    clear = tall is None or covered_share(tall, top[None]) == 0.0
    return bool(feet_on and clear and covered_share(mask, above) == 0.0)


def blob_clear(mask: np.ndarray, blob: np.ndarray, origin: tuple[int, int], down: np.ndarray | None) -> bool:
    """Whether both ends of ``blob`` ((h, w) bool crop at ``origin`` (u, v) px) along ``down`` (2,)
    have background just beyond them in ``mask`` ((H, W), nonzero foreground), as a head band's top:
    the blob is a whole silhouette from head to feet, whose length may be read as a height
    (``crowd.births_heights_clear``). In a crowd a birth blob ending against foreground (that the
    known people's ellipses explain, or a neighbour's) is cut there, and its length is not the person's.

    >>> mask = np.zeros((30, 20), np.uint8); mask[5:25, 5:15] = 1
    >>> blob_clear(mask, mask[5:25, 5:15].astype(bool), (5, 5), np.array([0.0, 1.0]))
    True
    >>> blob_clear(mask, mask[5:20, 5:15].astype(bool), (5, 5), np.array([0.0, 1.0]))   # the legs go on
    False
    """
    if down is None:
        return False
    v, u = np.nonzero(blob)
    pts = np.column_stack([u + origin[0], v + origin[1]]).astype(float)
    along = pts @ down
    across = np.array([-down[1], down[0]])
    half = max(1.0, 0.4 * float(np.ptp(pts @ across)))
    spread = np.linspace(-half, half, 9)[:, None] * across
    top, bottom = pts[np.argmin(along)], pts[np.argmax(along)]
    return covered_share(mask, top - BEYOND_PX * down + spread) == 0.0 and \
        covered_share(mask, bottom + BEYOND_PX * down + spread) == 0.0


def confirmed_images(view, people: People, confirmed: np.ndarray,
                     tallest: float = 0.0) -> tuple[np.ndarray, np.ndarray | None]:
    """The confirmed people's ellipses (uint8 (H, W), dilated 2 px as the births' own) and, where
    ``tallest`` > 0, the same people drawn at least ``tallest`` m tall (else None: not looked at).

    Parameters
    ----------
    view : CameraView — the camera
    people : People — everybody known, (N,) each
    confirmed : (N,) bool — which of them are confirmed
    tallest : float — m (``crowd.head_bands_tallest_m``; :data:`TALLEST_M`, the height range's
        maximum: a band no confirmed person's own head can be)
    """
    cam = view.camera
    out = [np.zeros((cam.height, cam.width), np.uint8), np.zeros((cam.height, cam.width), np.uint8)]
    keep = np.asarray(confirmed, bool)
    xy, h, w = np.asarray(people.xy)[keep], np.asarray(people.heights, float)[keep], np.asarray(people.widths)[keep]
    for image, heights in zip(out, (h, np.maximum(h, tallest)) if tallest > 0 else (h,)):
        inner, _, box, valid, _ = view.forms(xy, heights, w)
        for k in np.nonzero(valid)[0]:
            u0, u1, v0, v1 = box[k]
            if u0 < u1 and v0 < v1:
                image[v0:v1, u0:u1] |= ellipse_crop(inner[k], box[k], view.grid, view.args.has_dist).astype(np.uint8)
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))
    return cv2.dilate(out[0], kernel), out[1] if tallest > 0 else None


__all__ = ["HEAD_WIDTH_M", "MIN_HEAD_SHARE", "TALLEST_M", "blob_clear", "confirmed_images", "head_px", "is_head_band"]
