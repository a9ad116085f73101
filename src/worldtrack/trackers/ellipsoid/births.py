"""New people: foreground that the simulated image of everybody already known does not explain.

Paper 000 §5.2 starts a person entering the view in *capture mode*; it does not say where the
person comes from. Here each camera's foreground minus everybody's ellipses (slightly dilated),
cleaned of speckle and with the holes of one body closed, is cut into blobs; a blob large enough
to be (the visible part of) a person standing at its foot point proposes one there. Where they may
appear is a component chosen by name (``ellipsoid.births.where``, :data:`BIRTH_PLACES`).

>>> BIRTH_PLACES["none"]().proposes, BIRTH_PLACES["anywhere"]().proposes
(False, True)
"""

from __future__ import annotations

from functools import lru_cache
from typing import Callable, Mapping, NamedTuple, Protocol

import cv2
import numpy as np

from worldtrack.foreground.components import blob_extent, blobs
from worldtrack.registry import Registry
from worldtrack.trackers.ellipsoid.args import People
from worldtrack.trackers.ellipsoid.cameras import CameraView, pixel_clear
from worldtrack.trackers.ellipsoid.config import BirthConfig
from worldtrack.trackers.ellipsoid.crowd_config import CrowdConfig
from worldtrack.trackers.ellipsoid.forms import ellipse_crop
from worldtrack.trackers.ellipsoid.head_bands import blob_clear, confirmed_images, head_px, is_head_band
from worldtrack.trackers.ellipsoid.in_front import in_front_proposals
from worldtrack.trackers.ellipsoid.people_edges import covered_share, ends_on_people, unexplained_pixels

class Proposal(NamedTuple):
    """A new person: a floor place (2,) m, the camera whose foreground proposed it, and the height
    (m) its blob shows from the feet to the top of the head (None where the blob shows no both)."""

    xy: np.ndarray
    camera: str
    height: float | None = None


class BirthPlaces(Protocol):
    """Where new people may appear: ``proposes`` (False: never), and which proposals to keep."""

    proposes: bool

    def keep(self, proposals: list[Proposal], scene, first_frame: bool) -> list[Proposal]:
        ...


#: :class:`BirthPlaces` by name (``ellipsoid.births.where``).
BIRTH_PLACES: Registry[type] = Registry("ellipsoid.births.where")


@BIRTH_PLACES.register("anywhere")
class Anywhere:
    """Anywhere in view."""

    proposes = True

    def keep(self, proposals: list[Proposal], scene, first_frame: bool) -> list[Proposal]:
        return proposals


@BIRTH_PLACES.register("entry")
class InEntryRegions:
    """Only in the scene's entry regions (doors), and anywhere on the first frame (people already in
    the room); anywhere in a scene without entry regions."""

    proposes = True

    def keep(self, proposals: list[Proposal], scene, first_frame: bool) -> list[Proposal]:
        if first_frame or not scene.entry_regions:
            return proposals
        return [q for q in proposals if scene.entry_region_index([q[0]])[0] >= 0]


@BIRTH_PLACES.register("none")
class Nowhere:
    """Never: people only from ``--init``."""

    proposes = False

    def keep(self, proposals: list[Proposal], scene, first_frame: bool) -> list[Proposal]:
        return []


class BlobPlace(NamedTuple):
    """Where a blob puts a person: floor point (3,) m, the height it shows (m, or None) and the share
    of the person's length in the image it covers (1 unless its lower end is not the feet)."""

    xy: np.ndarray
    height: float | None
    share: float


class Births:
    """Proposes new people in the cameras of one tracker.

    Parameters
    ----------
    views : {camera_id: CameraView}
    scene : Scene — its walkable floor, entry regions and default person size
    walkable : callable — (M, 2) floor points → (M,) bool
    config : BirthConfig
    height_range : (min, max) plausible heights, m (``ellipsoid.height.range_m``), or None when
        heights are not measured (blobs then place people by their lower end, as before issue 37)
    min_px : a blob tells a height only when it is at least this long, px (``ellipsoid.height.min_px``,
        the rule the tracker's own height measurements follow: small, a pixel is centimetres)
    past_people : a blob's end on the known people's ellipses is hidden, and the size test expects
        only what they leave unexplained (``crowd.births_past_people``, :mod:`.people_edges`)
    head_bands : a blob too small for a person that is the top of one above known people is proposed
        (``crowd.births_head_bands``, :mod:`.head_bands`)
    crowd : CrowdConfig or None — also read here: ``births_in_front`` (legs below a confirmed
        person propose one in front of them, :mod:`.in_front`) ``head_bands_confirmed`` (head
        bands only above confirmed people, with ``head_bands_tallest_m`` topping out above them drawn
        that tall, :func:`~.head_bands.confirmed_images`), ``births_heights_clear`` (a height only from a blob
        with background beyond both ends, :func:`~.head_bands.blob_clear`); None: all off
    """

    def __init__(self, views: Mapping[str, CameraView], scene, walkable: Callable[[np.ndarray], np.ndarray],
                 config: BirthConfig, height_range: tuple[float, float] | None = (1.3, 2.1), min_px: int = 60,
                 past_people: bool = False, head_bands: bool = False, crowd: CrowdConfig | None = None):
        self.views = views
        self.scene = scene
        self.walkable = walkable
        self.config = config
        self.height_range = height_range
        self.min_px = min_px
        self.past_people = past_people
        self.head_bands = head_bands
        self.in_front = crowd.births_in_front if crowd is not None else 0.0
        self.bands_confirmed = crowd is not None and crowd.head_bands_confirmed
        self.bands_tallest = crowd.head_bands_tallest_m if crowd is not None else 0.0
        self.heights_clear = crowd is not None and crowd.births_heights_clear
        self.places: BirthPlaces = BIRTH_PLACES[config.where]()
        self._floor: np.ndarray | None = None

    def propose(self, masks: Mapping[str, np.ndarray], people: People, first_frame: bool,
                confirmed: np.ndarray | None = None) -> list[Proposal]:
        """Places of new people in this frame's foreground ``masks`` ({camera_id: (H, W) uint8}),
        clear of ``people`` and of each other by ``min_separation_m``, in proposal order
        (``confirmed`` (N,) bool: which of ``people`` are; None: all)."""
        if not self.places.proposes:
            return []
        proposals: list[Proposal] = []
        for cid in masks:
            proposals += self._in_camera(cid, masks[cid], people, confirmed)
        if not proposals:
            return []
        proposals = self.places.keep(proposals, self.scene, first_frame)
        # Each proposal is already clear of the existing people; keep the proposals apart too.
        kept: list[Proposal] = []
        for q in proposals:
            if not any(np.hypot(*(k[0] - q[0])) < self.config.min_separation_m for k in kept):
                kept.append(q)
        return kept

    def _in_camera(self, cid: str, mask: np.ndarray, people: People,
                   confirmed: np.ndarray | None = None) -> list[Proposal]:
        """Proposals from one camera's foreground that ``people`` do not explain."""
        cfg, view = self.config, self.views[cid]
        cam = view.camera
        xy = people.xy
        explained = np.zeros_like(mask)
        if len(xy):
            inner, _, box, valid, _ = view.forms(*people)
            render_union(explained, inner, box, valid, view.grid, cam.has_distortion)
            explained = cv2.dilate(explained, disc(2))
        un = mask & (1 - explained)
        # Remove speckle, then join the pieces of one body that holes in the mask split.
        r_open, r_close = 1, max(1, view.ring_px // 2)
        un = cv2.morphologyEx(un, cv2.MORPH_OPEN, disc(r_open))
        un = cv2.morphologyEx(un, cv2.MORPH_CLOSE, np.ones((2 * r_close + 1, 2 * r_close + 1), np.uint8))
        if not cv2.countNonZero(un):
            return []
        h0, w0 = self.scene.people.height, self.scene.people.width
        min_area = max(10 * cam.width * cam.height / (160 * 120),
                       0.1 * view.smallest_person_px(self.walkable_floor(), h0, w0))
        out: list[Proposal] = []
        # Components found at ~320 px wide (each blob then read back at full resolution):
        # labelling the whole 640x480 frame was a third of the births' time.
        bands = self.head_bands and len(xy) > 0   # small blobs too: the tops of people behind known ones
        sure = np.ones(len(xy), bool) if confirmed is None else np.asarray(confirmed, bool)
        under, tall = confirmed_images(view, people, sure, self.bands_tallest) if bands and self.bands_confirmed \
            else (explained, None)
        for area, (x0, y0, bw, bh), centroid, blob in blobs(un, 10 if bands else min_area, max(1, cam.width // 320)):
            band = area < min_area
            if band and not is_head_band(mask, under, blob, (x0, y0), view.down_direction(centroid),
                                         head_px(cam, centroid, h0), tall):
                continue
            found = blob_position(view, blob, (x0, y0), centroid, h0, self.height_range, self.min_px,
                                  known=explained if cfg.people_occlude and not band else None,
                                  explained=explained if (self.past_people or band) and len(xy) else None)
            if found is None:
                continue
            p, height, share = found
            if height is not None and self.heights_clear and \
                    not blob_clear(mask, blob, (x0, y0), view.down_direction(centroid)):
                height = None   # a blob cut by foreground at an end: its length is not a height
            pxy = self.nearest_walkable(p[:2], 0.6)
            if pxy is None or (len(xy) and np.min(np.hypot(*(xy - pxy).T)) < cfg.min_separation_m):
                continue  # off the floor, or somebody already there
            # Is the blob big enough to be (the visible part of) a person standing there?
            expected = (unexplained_pixels(view, pxy, h0, w0, explained) if self.past_people and len(xy)
                        else view.visible_pixels(pxy, h0, w0))
            if not band and (expected <= 0 or area < cfg.min_blob_fraction * expected * share):
                continue
            out.append(Proposal(pxy, cid, height))
        if self.in_front > 0 and len(xy):   # people in front of confirmed ones, shown by their legs below
            out += [Proposal(q, cid, None) for q in in_front_proposals(
                view, mask, people, sure, explained, h0, w0, self.in_front, cfg.min_separation_m)]
        return out

    def walkable_floor(self) -> np.ndarray:
        """(N, 2) walkable points of the scene on a 0.25 m grid (computed once)."""
        if self._floor is None:
            x0, x1, y0, y1 = self.scene.walkable.bounds
            gx, gy = np.meshgrid(np.arange(x0, x1, 0.25), np.arange(y0, y1, 0.25))
            xy = np.column_stack([gx.ravel(), gy.ravel()])
            self._floor = xy[self.walkable(xy)]
        return self._floor

    def nearest_walkable(self, xy: np.ndarray, radius: float) -> np.ndarray | None:
        """``xy`` if walkable, else the nearest walkable point within ``radius`` m (5 cm grid), else
        None. A proposal from a head seen above a desk can land on the desk's footprint."""
        if self.walkable([xy])[0]:
            return np.asarray(xy, float)
        offsets = disc_offsets(radius)
        cand = xy + offsets
        ok = self.walkable(cand)
        if not ok.any():
            return None
        d = np.hypot(offsets[ok, 0], offsets[ok, 1])
        return cand[ok][int(np.argmin(d))]


def blob_position(view: CameraView, blob: np.ndarray, origin: tuple[int, int], centroid: np.ndarray,
                  height: float, height_range: tuple[float, float] | None = (1.3, 2.1), min_px: float = 0,
                  known: np.ndarray | None = None, explained: np.ndarray | None = None) -> BlobPlace | None:
    """Floor position (3,) of a person seen as ``blob``, the height (m) the blob shows and the share
    of the person it shows, or None.

    ``blob`` is a boolean crop of the image whose top-left pixel is ``origin`` (u, v);
    ``centroid`` is in full-image pixels.

    The feet are the end of the blob in the direction in which world verticals point down in
    the image — the bottom for an oblique camera, the end nearest the image centre for one that
    looks straight down. They are back-projected to the floor, unless the blob ends there at the
    image border or on an obstacle (a desk hides the feet): then its other end, the top of the
    head, is back-projected to the default ``height`` (m).

    Where both ends are in view, the height of the top-of-head ray above the foot point is the
    person's height. Below ``height_range``'s minimum the blob is too short to be a person standing
    at its lower end — legs in clothes the colour of the floor, a hole in the mask — and its lower
    end would put the person too far along the line of sight: the head places them instead (at
    the default ``height``), no height is given, and the share is the blob's length over the
    length of a person of that height standing there. Above the maximum, no height is given either.
    ``height_range=None`` (heights not measured, as in the paper's preset), or a blob shorter
    than ``min_px`` or touching the image border: no height, and the lower end always.

    ``known`` (H, W), nonzero where people already known are drawn (``births.people_occlude``): a
    blob whose top stops against them is a person whose upper body a known one's ellipse covers (in
    front of them, or behind a farther one on the same line of sight): its lower end, the feet,
    places the person, no height is given, and the share is the blob's length over the person's
    there. (Its mirror — the feet hidden by a known person, the head placing them at the default
    height — lost on crowd 10's dev seeds, and is not done.)
    ``explained`` ((H, W) uint8, the known people's ellipses; None: not looked at): an end on them
    is hidden as one on an obstacle (:func:`~.people_edges.ends_on_people`).
    """
    cam = view.camera
    down = view.down_direction(centroid)
    if down is None:
        return None
    # The ends: the extreme pixel along ``down``, laterally at the mean of the extreme 2 %.
    along_min, along_max, spread_min, spread_max, spread_low, spread_high = blob_extent(
        blob, int(origin[0]), int(origin[1]), float(centroid[0]), float(centroid[1]), float(down[0]),
        float(down[1]), 50)
    across = np.array([-down[1], down[0]])
    foot = centroid + (along_max + 0.5) * down + spread_high * across
    head = centroid + (along_min - 0.5) * down + spread_low * across
    # Just beyond the feet, across the blob's width: image border or obstacle → feet hidden.
    half = max(1.0, 0.4 * (spread_max - spread_min))  # most of the blob's width
    beyond = foot + 2 * down + np.linspace(-half, half, 9)[:, None] * across
    feet_hidden = not pixel_clear(cam, None, beyond).all() or (~pixel_clear(cam, view.occ, beyond)).mean() > 0.5
    head_seen = bool(pixel_clear(cam, None, (head - 2 * down)[None]).all())
    if explained is not None:   # an end on somebody already known: hidden by (or hiding) them
        feet_on, head_on = ends_on_people(explained, foot, head, down, half)
        feet_hidden, head_seen = feet_hidden or feet_on, head_seen and not head_on
    shown, share = None, 1.0
    above = None if known is None else head - 2 * down + np.linspace(-half, half, 9)[:, None] * across
    if above is not None and not feet_hidden and covered_share(known, above) > 0.5:
        # The top stops against a known person: their ellipse hides the rest; the feet place them.
        p = cam.backproject(foot[None], 0.0)[0]
        return BlobPlace(p, None, length_share(cam, p[:2], height, along_max - along_min + 1.0)) \
            if np.isfinite(p).all() else None
    if not feet_hidden:
        p = cam.backproject(foot[None], 0.0)[0]
        # Only oblique views tell the height (as in height.py): from above, the ends of the blob
        # are the head and the shoulders, not the head and the feet.
        oblique = np.isfinite(p).all() and np.hypot(*(p[:2] - cam.centre[:2])) >= cam.centre[2] - 0.5 * height
        # Small, a pixel is centimetres of height; at the border, the blob may go on beyond it.
        inside = bool(pixel_clear(cam, None, np.array([head - 3 * down, foot + 3 * down])).all())
        readable = height_range is not None and head_seen and oblique and inside and along_max - along_min >= min_px
        shown = head_height(cam, head, p) if readable else None
        if shown is not None and shown < height_range[0]:
            p, shown = cam.backproject(head[None], height)[0], None
            share = length_share(cam, p[:2], height, along_max - along_min + 1.0)
        elif shown is not None and shown > height_range[1]:
            shown = None
    elif head_seen:
        p = cam.backproject(head[None], height)[0]
    else:
        return None
    return BlobPlace(p, shown, share) if np.isfinite(p).all() else None


def length_share(cam, xy: np.ndarray, height: float, length_px: float) -> float:
    """``length_px`` over the image length (px) of a person ``height`` m tall standing at floor point
    ``xy`` (2,) m, at most 1 (1 where they have no length in the image)."""
    ends = cam.project(np.array([[xy[0], xy[1], 0.0], [xy[0], xy[1], height]]))
    length = float(np.hypot(*(ends[0] - ends[1])))
    return min(1.0, length_px / length) if length > 0 else 1.0


def head_height(cam, head_px: np.ndarray, foot: np.ndarray) -> float | None:
    """Height (m) of the viewing ray through pixel ``head_px`` (2,) where it passes over the floor
    point ``foot`` (2+,), or None for a camera not above it (the ray does not come down to it).

    >>> from worldtrack.geometry import Camera
    >>> import numpy as np
    >>> cam = Camera.look_at("c", 640, 480, position=(0, 0, 3.0), target=(0, 5, 0), hfov_deg=60)
    >>> px = cam.project(np.array([[0.0, 5.0, 1.8]]))[0]
    >>> round(head_height(cam, px, np.array([0.0, 5.0])), 3)
    1.8
    """
    origin, d = cam.rays(np.asarray(head_px, float)[None])
    d = d[0]
    flat = d[:2] @ d[:2]
    if not np.isfinite(d).all() or flat < 1e-9:
        return None
    s = float((np.asarray(foot[:2], float) - origin[:2]) @ d[:2] / flat)
    if s <= 0:
        return None
    return float(origin[2] + s * d[2])


@lru_cache(maxsize=8)
def disc_offsets(radius: float) -> np.ndarray:
    """(K, 2) floor offsets (m) on a 5 cm grid within ``radius`` of the origin, row by row."""
    g = np.arange(-radius, radius + 1e-9, 0.05)
    offsets = np.array([(a, b) for a in g for b in g])
    offsets = offsets[np.hypot(offsets[:, 0], offsets[:, 1]) <= radius]
    offsets.setflags(write=False)
    return offsets


def disc(radius: int) -> np.ndarray:
    """Elliptical structuring element of the given radius (pixels)."""
    return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * radius + 1, 2 * radius + 1))


def render_union(out: np.ndarray, forms: np.ndarray, boxes: np.ndarray, valid: np.ndarray,
                 grid: np.ndarray, has_dist: bool) -> None:
    """Set ``out`` to 1 inside the given ellipses (normal forms (N, 5)), within their boxes (in place)."""
    for k in range(len(forms)):
        if not valid[k]:
            continue
        u0, u1, v0, v1 = boxes[k]
        if u0 >= u1 or v0 >= v1:
            continue
        out[v0:v1, u0:u1] |= ellipse_crop(forms[k], boxes[k], grid, has_dist).astype(np.uint8)


__all__ = ["BIRTH_PLACES", "BirthPlaces", "Births", "Proposal", "blob_position", "disc_offsets",
           "length_share"]
