"""What the colour identity sees in one camera: who owns each pixel, who stands clear of the
others, and the colours of the upper and lower body of the people it asks about.

Per camera and frame, :func:`look` draws the ellipses grown by the ring **once** into one owner
map (which one person's ellipse covers each pixel) to tell who stands clear of the others and who
met whom. :func:`colours_of` then measures only the people it is asked about (those who can learn
their colours, and those in a pair that is checked for a swap): the owner map of their ellipses
over their boxes, and the histograms of all of them from **one** ``np.bincount`` over the
foreground pixels they own, indexed by (person, body part, HSV bin). The bins are OpenCV's own
(:func:`cv2.calcHist`'s, read from it once), so each histogram equals ``cv2.calcHist`` on that
person's masked crop — :func:`part_histograms_reference`, the per-person version the tests
compare against.

>>> hist = np.zeros(HIST_BINS, np.float32); hist[0, 0, 0] = 1
>>> Colours([hist, hist]).distance(Colours([hist, hist]))
0.0
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple, Sequence

import cv2
import numpy as np

from worldtrack.trackers.base import Person
from worldtrack.trackers.ellipsoid.args import Forms
from worldtrack.trackers.ellipsoid.cameras import CameraView
from worldtrack.trackers.ellipsoid.forms import ellipse_crop, owner_crop

#: Histogram bins: hue, saturation, value (value keeps dark and light grey clothes apart).
HIST_BINS = (8, 4, 4)
#: Upper ends of the 8-bit HSV channels' ranges (OpenCV's hue runs 0–179).
HSV_RANGES = (180, 256, 256)
#: The body parts, as shares of the image axis from the top of the head (0) to the feet (1):
#: the upper body without the head, the lower body without the feet (and their shadow).
PARTS = ((0.18, 0.5), (0.5, 0.9))


def hist_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Bhattacharyya distance of two normalised histograms (OpenCV's ``HISTCMP_BHATTACHARYYA``)."""
    return float(cv2.compareHist(a, b, cv2.HISTCMP_BHATTACHARYYA))


@dataclass
class Colours:
    """One person's colours in one camera: a histogram (``HIST_BINS``, float32, sums to 1) per
    body part; ``alone``: seen clearly isolated (else from the pixels nobody else's ellipse covers)."""

    parts: list[np.ndarray]
    updates: int = 1
    alone: bool = True

    def distance(self, other: "Colours") -> float:
        """Mean Bhattacharyya distance over the body parts."""
        return float(np.mean([hist_distance(a, b) for a, b in zip(self.parts, other.parts)]))

    def blend(self, seen: "Colours", rate: float) -> None:
        """Move the model towards ``seen`` by ``rate`` (the first updates count more)."""
        w = max(rate, 1.0 / (self.updates + 1))
        self.parts = [(1 - w) * a + w * b for a, b in zip(self.parts, seen.parts)]
        self.updates += 1


class Sight(NamedTuple):
    """The people of one frame as one camera sees them (N people).

    Attributes
    ----------
    forms : Forms — their ellipses
    xy : (N, 2) — their floor positions when looked at, m
    heights : (N,) — their heights, m
    shown : (N,) bool — drawn (in front of the camera, a non-empty box in the image)
    alone : (N,) bool — shown, and no other person's ellipse grown by the ring overlaps theirs
    met : list of (id, id) — the pairs whose grown ellipses crowd each other, smaller id first, in
        the order of the people (a person who is not alone meets everyone whose box meets theirs)
    """

    forms: Forms
    xy: np.ndarray
    heights: np.ndarray
    shown: np.ndarray
    alone: np.ndarray
    met: list


def _bin_table(bins: int, high: int) -> np.ndarray:
    """(256,) int64: the bin ``cv2.calcHist`` puts each 8-bit value in (uniform bins over
    [0, ``high``)), −1 outside. Read from OpenCV itself: one of each value, binned, in order."""
    counts = cv2.calcHist([np.arange(256, dtype=np.uint8)[None, :]], [0], None, [bins], [0, high])
    counts = counts.ravel().astype(np.int64)
    table = np.full(256, -1, np.int64)
    table[:counts.sum()] = np.repeat(np.arange(bins), counts)
    return table


#: cv2.calcHist's bin of each value of H, S and V.
_BIN_TABLES = tuple(_bin_table(b, r) for b, r in zip(HIST_BINS, HSV_RANGES))
_N_BINS = int(np.prod(HIST_BINS))


def _union(box: np.ndarray, which: np.ndarray) -> np.ndarray:
    """(4,) int64: the smallest window ``u0, u1, v0, v1`` holding the boxes ``box[which]``."""
    b = box[which]
    return np.array([b[:, 0].min(), b[:, 1].max(), b[:, 2].min(), b[:, 3].max()], np.int64)


def look(view: CameraView, people: Sequence[Person], isolation: str = "ring") -> Sight:
    """Who stands clear of the others, for ``people`` in one camera.

    A person is clearly isolated when no other person's box meets theirs, or no pixel of their
    box is covered by two ellipses grown by the ring (one owner map of the grown ellipses over
    the boxes of the people who have a neighbour). With ``isolation="ellipse"`` a person whose
    own ellipse no other ellipse overlaps is isolated too (their rings may). ``Sight.met`` is the
    same either way.
    """
    cam = view.camera
    n = len(people)
    xy = np.array([[p.x, p.y] for p in people], float).reshape(n, 2)
    hs = np.array([p.height for p in people], float)
    forms = view.forms(xy, hs, np.array([p.width for p in people], float))
    box = forms.box
    shown = forms.valid & (box[:, 0] < box[:, 1]) & (box[:, 2] < box[:, 3])
    u0, u1, v0, v1 = box.T
    # Boxes that meet: (N, N), a person does not meet themselves.
    meets = (forms.valid[None, :] & (u0[None, :] < u1[:, None]) & (u1[None, :] > u0[:, None])
             & (v0[None, :] < v1[:, None]) & (v1[None, :] > v0[:, None]))
    np.fill_diagonal(meets, False)
    near = shown & meets.any(axis=1)
    alone = shown.copy()
    if not near.any():
        return Sight(forms, xy, hs, shown, alone, [])
    w = _union(box, near)
    grown = owner_crop(w, forms._replace(inner=forms.ring), view.grid, cam.has_distortion)
    shared = cv2.integral((grown == -2).view(np.uint8))      # shared pixels above and left of each
    k = np.flatnonzero(near)
    a0, a1, b0, b1 = u0[k] - w[0], u1[k] - w[0], v0[k] - w[2], v1[k] - w[2]
    crowded = k[(shared[b1, a1] - shared[b0, a1] - shared[b1, a0] + shared[b0, a0]) > 0]
    alone[crowded] = False
    ids = np.array([p.id for p in people])
    rows, cols = np.nonzero(meets[crowded])                   # in the order of the people, then of j
    a, b = ids[crowded[rows]], ids[cols]
    met = list(zip(np.minimum(a, b).tolist(), np.maximum(a, b).tolist()))
    if isolation == "ellipse" and len(crowded):
        alone[crowded] = _unoverlapped(view, forms, crowded)
    return Sight(forms, xy, hs, shown, alone, met)


def _unoverlapped(view: CameraView, forms: Forms, which: np.ndarray) -> np.ndarray:
    """For the people ``which``: whether every pixel of their ellipse is theirs alone."""
    w = _union(forms.box, which)
    owner = owner_crop(w, forms, view.grid, view.camera.has_distortion)
    owned = np.bincount(owner.ravel() + 2, minlength=len(forms.box) + 2)[2:]
    drawn = np.array([ellipse_crop(forms.inner[k], forms.box[k], view.grid, view.camera.has_distortion).sum()
                      for k in which])
    return owned[which] == drawn


def _own_foreground(view: CameraView, labels: np.ndarray, forms: Forms, ask: np.ndarray):
    """The foreground pixels (``labels`` 1) that the people asked about (``ask[k + 2]``) alone
    cover: (owner k, u, v), each (P,) int64. The owner map is drawn over each one's box when those
    are smaller together than the window holding them all (people spread over the image), else
    once over that window."""
    asked = np.flatnonzero(ask[2:])
    box = forms.box
    areas = (box[asked, 1] - box[asked, 0]) * (box[asked, 3] - box[asked, 2])
    w = _union(box, asked)
    pieces = [(w, ask)] if areas.sum() >= (w[1] - w[0]) * (w[3] - w[2]) else \
        [(box[j], np.arange(-2, len(box)) == j) for j in asked]
    out = []
    for (u0, u1, v0, v1), mine in pieces:
        owner = owner_crop(np.array([u0, u1, v0, v1], np.int64), forms, view.grid, view.camera.has_distortion)
        flat = np.flatnonzero(mine[owner.ravel() + 2] & (labels[v0:v1, u0:u1].ravel() == 1))
        v, u = np.divmod(flat, u1 - u0)
        out.append((owner.ravel()[flat].astype(np.int64), u + u0, v + v0))
    return tuple(np.concatenate(c) for c in zip(*out))


def colours_of(view: CameraView, image: np.ndarray, labels: np.ndarray, sight: Sight, wanted: Sequence[int],
               min_pixels: int) -> dict[int, Colours]:
    """The colours of the people ``wanted`` (indices into the people ``sight`` looked at), by
    index, in index order.

    A person's pixels are the foreground pixels (``labels`` 1) their ellipse alone covers, split
    into :data:`PARTS` along the image of their vertical axis; a part with fewer than
    ``min_pixels`` pixels (or a person whose axis is not in the image) leaves the person out.
    ``Colours.alone`` is ``sight.alone``.
    """
    n = len(sight.xy)
    ask = np.zeros(n + 2, bool)                       # by owner index + 2 (−2 several, −1 nobody)
    ask[np.asarray(wanted, np.int64) + 2] = True
    ask[2:] &= sight.shown
    # The axis from the head's top to the feet, relative to each box's corner (as in a crop), of
    # the people asked about, at the places they were looked at (a swap moves people).
    idx = np.flatnonzero(ask[2:])
    if not len(idx):
        return {}
    xy, hs = sight.xy[idx], sight.heights[idx]
    ends = view.camera.project(np.stack([np.c_[xy, hs], np.c_[xy, np.zeros(len(idx))]], axis=1).reshape(-1, 3))
    ends = ends.reshape(len(idx), 2, 2)
    corner = sight.forms.box[:, [0, 2]]
    head, axis, length2 = np.zeros((n, 2)), np.zeros((n, 2)), np.ones(n)
    head[idx] = ends[:, 0] - corner[idx].astype(float)
    axis[idx] = (ends[:, 1] - corner[idx].astype(float)) - head[idx]
    length2[idx] = [float(a @ a) for a in axis[idx]]   # person by person, as the reference does
    ask[idx + 2] &= np.isfinite(ends).all(axis=(1, 2)) & (length2[idx] >= 1.0)
    if not ask.any():
        return {}
    k, u, v = _own_foreground(view, labels, sight.forms, ask)
    share = ((u - corner[k, 0] - head[k, 0]) * axis[k, 0] + (v - corner[k, 1] - head[k, 1]) * axis[k, 1]) / length2[k]
    part = np.full(len(k), -1, np.int64)
    for p, (lo, hi) in enumerate(PARTS):
        part[(share >= lo) & (share < hi)] = p
    keep = part >= 0
    k, part, u, v = k[keep], part[keep], u[keep], v[keep]
    slot = k * len(PARTS) + part
    pixels = np.bincount(slot, minlength=n * len(PARTS)).reshape(n, len(PARTS))
    bgr = image[v, u]
    hsv = cv2.cvtColor(bgr[None], cv2.COLOR_BGR2HSV)[0] if len(bgr) else bgr   # pixel by pixel
    b = [t[hsv[:, c]] for c, t in enumerate(_BIN_TABLES)]
    binned = (b[0] >= 0) & (b[1] >= 0) & (b[2] >= 0)
    bins = (b[0] * HIST_BINS[1] + b[1]) * HIST_BINS[2] + b[2]
    counts = np.bincount(slot[binned] * _N_BINS + bins[binned], minlength=n * len(PARTS) * _N_BINS)
    counts = counts.reshape(n, len(PARTS), *HIST_BINS).astype(np.float32)
    out: dict[int, Colours] = {}
    for i in np.flatnonzero(ask[2:]):
        if (pixels[i] < min_pixels).any():
            continue
        out[int(i)] = Colours([h / max(float(h.sum()), 1.0) for h in counts[i]], alone=bool(sight.alone[i]))
    return out


def part_histograms_reference(camera, crop: np.ndarray, mask: np.ndarray, origin: tuple[int, int], xy: np.ndarray,
                              height: float, min_pixels: int) -> list[np.ndarray] | None:
    """One person's part histograms by ``cv2.calcHist`` on their masked crop (``crop`` BGR, ``mask``
    their own foreground pixels, ``origin`` the crop's top-left pixel): the plain per-person version
    :func:`colours_of` is tested against."""
    ends = camera.project(np.array([[xy[0], xy[1], height], [xy[0], xy[1], 0.0]]))
    if not np.isfinite(ends).all():
        return None
    head, feet = ends[0] - np.asarray(origin, float), ends[1] - np.asarray(origin, float)
    axis = feet - head
    length2 = float(axis @ axis)
    if length2 < 1.0:
        return None
    u, v = np.arange(crop.shape[1])[None, :], np.arange(crop.shape[0])[:, None]
    share = ((u - head[0]) * axis[0] + (v - head[1]) * axis[1]) / length2
    hsv = cv2.cvtColor(crop, cv2.COLOR_BGR2HSV)
    parts = []
    for lo, hi in PARTS:
        part = (mask & (share >= lo) & (share < hi)).astype(np.uint8)
        if cv2.countNonZero(part) < min_pixels:
            return None
        h = cv2.calcHist([hsv], [0, 1, 2], part, list(HIST_BINS), [0, HSV_RANGES[0], 0, HSV_RANGES[1], 0, HSV_RANGES[2]])
        parts.append(h / max(float(h.sum()), 1.0))
    return parts


__all__ = ["Colours", "HIST_BINS", "HSV_RANGES", "PARTS", "Sight", "colours_of", "hist_distance", "look",
           "part_histograms_reference"]
