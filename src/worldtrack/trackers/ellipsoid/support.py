"""How much of each person's ellipse is foreground that nobody else explains (their *support*).

Eq. 5 rates candidates; it does not say whether a track still has a person under it. A track
whose own pixels — visible, not hidden by obstacles, covered by nobody else — are mostly
background explains nothing the others do not: a ghost left beside the person it duplicated, or a
track that lost its person. :func:`track_support` counts, per person and camera, the visible
pixels, the own pixels and the own foreground pixels; the life cycle (:mod:`.life`) confirms and
ends people on these shares.

:func:`track_support` is compiled (a loop over sampled pixels and the people covering them);
:func:`track_support_reference` is the whole-box NumPy version it is tested against.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from typing import Callable, Mapping, NamedTuple, Sequence

from worldtrack.geometry.camera import Camera
from worldtrack.trackers.base import Person
from worldtrack.trackers.ellipsoid.args import CameraArgs, Forms
from worldtrack.trackers.lifecycle import counts_for
from worldtrack.trackers.ellipsoid.forms import ideal_position, inside

#: Pixels a person must show (in all cameras together) to count as seen, or as its own.
MIN_OWN_PIXELS = 40


@njit(cache=True)
def track_support(cam, mask, forms, target_pixels, covers):
    """How much foreground each person alone explains, in one camera.

    For every person k, over the visible pixels of its ellipse (not hidden by obstacles) that no
    other person's visible ellipse covers: the number of such pixels and how many of them are
    foreground.

    Parameters
    ----------
    cam : CameraArgs — ``grid``, ``has_dist``, ``occ`` are read
    mask : (H, W) uint8 — foreground (1) / background (0) / unsure (2, not counted)
    forms : Forms — the people's ellipses, boxes, floor distances and validity (N, …)
    target_pixels : int — sample about this many pixels per person (0 = all)
    covers : (N,) bool — which people take pixels away from the others (e.g. only confirmed
        tracks: two tentative ones on the same person must not cancel each other out)

    Returns
    -------
    visible : (N,) float64 — pixels of the ellipse inside the image and not hidden by obstacles
        (estimated from the samples: each sample counts stride² pixels)
    own : (N,) float64 — of those, the ones covered by nobody else (not counting unsure pixels)
    own_fg : (N,) float64 — of those, the foreground ones
    area : (N,) float64 — the whole ellipse's area in pixels, image border and obstacles ignored
    hidden : (N,) float64 — pixels of the ellipse inside the image that obstacles hide
    """
    inner, box, dist, valid = forms.inner, forms.box, forms.dist, forms.valid
    occ = cam.occ
    n = inner.shape[0]
    visible = np.zeros(n)
    own = np.zeros(n)
    own_fg = np.zeros(n)
    area = np.zeros(n)
    hidden = np.zeros(n)
    for k in range(n):
        if not valid[k]:
            continue
        area[k] = math.pi / math.sqrt(max(inner[k, 2] * inner[k, 4] - inner[k, 3] ** 2, 1e-300))
        u0, u1, v0, v1 = box[k, 0], box[k, 1], box[k, 2], box[k, 3]
        if u0 >= u1 or v0 >= v1:
            continue
        stride = 1
        if target_pixels > 0:
            stride = max(1, int(math.sqrt((u1 - u0) * (v1 - v0) / target_pixels)))
        for v in range(v0, v1, stride):
            for uu in range(u0, u1, stride):
                x, y = ideal_position(cam.grid, cam.has_dist, v, uu)
                o = occ[v, uu]
                if not inside(inner[k], x, y):
                    continue
                if o < dist[k]:
                    hidden[k] += stride * stride
                    continue
                visible[k] += stride * stride
                covered = False
                for m in range(n):
                    if m == k or not valid[m] or not covers[m] or o < dist[m]:
                        continue
                    if uu < box[m, 0] or uu >= box[m, 1] or v < box[m, 2] or v >= box[m, 3]:
                        continue
                    if inside(inner[m], x, y):
                        covered = True
                        break
                if not covered and mask[v, uu] != 2:
                    own[k] += stride * stride
                    if mask[v, uu] == 1:
                        own_fg[k] += stride * stride
    return visible, own, own_fg, area, hidden


def track_support_reference(cam: CameraArgs, mask: np.ndarray, forms: Forms, target_pixels: int,
                            covers: np.ndarray) -> tuple[np.ndarray, ...]:
    """:func:`track_support` with whole-box masks in NumPy: the version it is tested against."""
    n = len(forms.valid)
    visible, own, own_fg, area, hidden = (np.zeros(n) for _ in range(5))
    for k in np.flatnonzero(forms.valid):
        a11, a12, a22 = forms.inner[k, 2:]
        area[k] = math.pi / math.sqrt(max(a11 * a22 - a12 ** 2, 1e-300))
        u0, u1, v0, v1 = (int(b) for b in forms.box[k])
        if u0 >= u1 or v0 >= v1:
            continue
        stride = max(1, int(math.sqrt((u1 - u0) * (v1 - v0) / target_pixels))) if target_pixels > 0 else 1
        vv, uu = np.meshgrid(np.arange(v0, v1, stride), np.arange(u0, u1, stride), indexing="ij")
        x, y = _ideal(cam, vv, uu)
        occ = cam.occ[vv, uu]
        ellipse = _inside(forms.inner[k], x, y)
        mine = (occ >= forms.dist[k]) & ellipse
        covered = np.zeros_like(mine)
        for m in np.flatnonzero(forms.valid & covers):
            if m != k:
                bu0, bu1, bv0, bv1 = forms.box[m]
                in_box = (uu >= bu0) & (uu < bu1) & (vv >= bv0) & (vv < bv1)
                covered |= in_box & (occ >= forms.dist[m]) & _inside(forms.inner[m], x, y)
        labels = mask[vv, uu]
        alone = mine & ~covered & (labels != 2)
        weight = stride * stride
        visible[k] = weight * np.count_nonzero(mine)
        own[k] = weight * np.count_nonzero(alone)
        own_fg[k] = weight * np.count_nonzero(alone & (labels == 1))
        hidden[k] = weight * np.count_nonzero(ellipse & ~mine)
    return visible, own, own_fg, area, hidden


def _ideal(cam: CameraArgs, vv: np.ndarray, uu: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    if cam.has_dist:
        return cam.grid[vv, uu, 0].astype(np.float64), cam.grid[vv, uu, 1].astype(np.float64)
    return uu.astype(np.float64), vv.astype(np.float64)


def _inside(f: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    du, dv = x - f[0], y - f[1]
    return f[2] * du * du + 2.0 * f[3] * du * dv + f[4] * dv * dv < 1.0


class Support(NamedTuple):
    """Per person (N,), over a tracker's cameras.

    Attributes
    ----------
    visible : float — pixels of the ellipse in view and not hidden by obstacles, all cameras
    support : float — share of the person's own pixels (visible, nobody else's) that are
        foreground, in the camera where it is lowest among those showing at least
        :data:`MIN_OWN_PIXELS` of them (a real person is foreground in every view; a ghost that
        explains a tall neighbour's legs in one view stands on floor in another); NaN when no
        camera shows enough
    own_share : float — fraction of the visible pixels that nobody else covers
    seen_share : float — the largest fraction of the whole ellipse some camera shows
    evidence : float — the largest fraction of the whole ellipse that is own foreground or
        explained by others (low for a track past the image border or on empty floor) — or, with
        ``obstacles_explain``, by the obstacles that hide it
    views : int — cameras that show at least :data:`MIN_OWN_PIXELS` own pixels
    seen_by : tuple of tuple of str — per person, the cameras whose view holds some of it
    """

    visible: np.ndarray
    support: np.ndarray
    own_share: np.ndarray
    seen_share: np.ndarray
    evidence: np.ndarray
    views: np.ndarray
    seen_by: tuple


def measure_support(cams: Mapping[str, tuple[CameraArgs, Forms]], labels: Mapping[str, np.ndarray],
                    target_pixels: int, covers: np.ndarray, obstacles_explain: bool = False,
                    obstacles_confirm: bool = True) -> Support:
    """:class:`Support` of N people from their ellipses in each camera.

    Parameters
    ----------
    cams : {camera_id: (CameraArgs, Forms of the N people)}
    labels : {camera_id: (H, W) uint8} — the cameras' foreground labels (1 fg, 0 bg, 2 unsure)
    target_pixels : int — samples per person (0: every pixel)
    covers : (N,) bool — who takes pixels away from the others (tracked people)
    obstacles_explain : bool — pixels an obstacle hides count as explained in the evidence, as
        those somebody else covers do, and the seen share is of what the obstacles leave in view:
        a person standing behind a sign is neither failing nor unconfirmable for showing only
        their head and legs (``support.obstacles_explain``)
    obstacles_confirm : bool — with ``obstacles_explain``, the seen share is of what the obstacles
        leave in view; false: of the whole ellipse, as without it (``support.obstacles_confirm``)
    """
    n = len(covers)
    visible, own_total, seen_share, evidence = (np.zeros(n) for _ in range(4))
    support = np.full(n, np.nan)
    views = np.zeros(n, dtype=int)
    seen: list[list[str]] = [[] for _ in range(n)]
    for cid, mask in labels.items():
        args, forms = cams[cid]
        vis, own, own_fg, area, hidden = track_support(args, mask, forms, target_pixels, covers)
        visible += vis
        own_total += own
        # Seen: of the ellipse, or with ``obstacles_explain`` of what the obstacles leave to see.
        can_see = area - hidden if obstacles_explain and obstacles_confirm else area
        seen_share = np.maximum(seen_share, np.where(can_see > 0, vis / np.maximum(can_see, 1), 0.0))
        # Evidence: foreground of its own plus what others (and, as an option, obstacles) explain,
        # over the whole ellipse.
        explained = vis - own + (hidden if obstacles_explain else 0.0)
        evidence = np.maximum(evidence, np.where(area > 0, (own_fg + explained) / np.maximum(area, 1), 0.0))
        with np.errstate(invalid="ignore", divide="ignore"):
            here = np.where(own >= MIN_OWN_PIXELS, own_fg / np.maximum(own, 1), np.nan)
        support = np.fmin(support, here)
        views += own >= MIN_OWN_PIXELS
        for k in np.flatnonzero(vis > 0):
            seen[k].append(cid)
    own_share = np.where(visible > 0, own_total / np.maximum(visible, 1), np.nan)
    return Support(visible, support, own_share, seen_share, evidence, views, tuple(tuple(s) for s in seen))


def flag_unmeasurable(people: Sequence[Person], cameras: Sequence[Camera], occlusion: Callable[[str], object],
                      t: float) -> None:
    """Flag people whose head and feet are both hidden in every camera (paper 000 Table 2 (b)).

    Such a person's place along the line of sight is unknown: ``unmeasurable``, and their σ
    along it is at least 1 m instead of a confident wrong place (:mod:`.uncertainty`).
    Vectorised over people. Trackers sharing a map
    flag a person only if none of them sees its head or feet at ``t`` (counter ``hidden``).

    Parameters
    ----------
    people : the people to flag
    cameras : the tracker's cameras
    occlusion : camera id → the scene's occlusion map of that camera (``scene.occlusion``)
    t : float — time stamp, s
    """
    if not people:
        return
    n = len(people)
    pts = np.array([[[p.x, p.y, 0.0], [p.x, p.y, p.height]] for p in people]).reshape(-1, 3)
    seen = np.zeros(n, dtype=bool)
    head_or_feet = np.zeros(n, dtype=bool)
    for cam in cameras:
        uv = cam.project(pts)
        inside = cam.in_image(uv)
        visible = inside & ~occlusion(cam.id).hidden(uv, cam.floor_distance(pts) - 0.05)
        seen |= inside.reshape(n, 2).any(axis=1)
        head_or_feet |= visible.reshape(n, 2).any(axis=1)
    for k, p in enumerate(people):
        if counts_for(p, "hidden", t, bool(seen[k] and not head_or_feet[k])) > 0:
            p.flags.add("unmeasurable")
        else:
            p.flags.discard("unmeasurable")


__all__ = ["MIN_OWN_PIXELS", "Support", "flag_unmeasurable", "measure_support", "track_support",
           "track_support_reference"]
