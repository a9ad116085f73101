"""3-D particle filters with the height-column likelihood (seed 004).

One particle filter per object, in world coordinates (metres, Z up). Every frame each filter

1. **predicts** every particle with a velocity and Gaussian noise (eqs. 1–2, in real time)::

       x_t = x_{t−1} + v·dt + w,   w ~ N(0, σ²·dt)      (σ in m/√s, dt in seconds)

   with ``v`` each particle's own velocity state (default, ``velocity="state"``: constant
   velocity, walking by ``noise_v``, which stops while the filter's columns are mostly hidden),
   each particle's own ``(x_{t−1} − x_{t−2}) / dt`` (the paper) or the object's;
2. **observes** the likelihood π_i of each particle (:mod:`~worldtrack.trackers.particle.likelihood`:
   the height column of eq. 11 or the point of eq. 7, multiplied over the cameras that see the
   particle; 0 off the walkable floor or out of every view) and weights ``g_i = π_i / Σ π`` (eq. 8);
3. **resamples** in proportion to the weights (systematic, see :class:`ParticleConfig`);
4. reports the **object region** from the resampled particles: centre ``O = mean`` (eq. 9) and size
   ``σ_x, σ_y, σ_z`` (eq. 10), the box ``O ± σ``. The paper's particles fill the object; with the
   sharp ``ratio`` weighting ours gather on the object's axis, so the region adds the object's
   own extent: z drawn uniformly below the top each column sees (see below), and in x and y a
   disc of the person's width, ``σ_x² = var(x) + (width/4)²``.

The tracking filters go through these steps together: each holds ``particles`` particles, so their
arrays stack to (filters, particles, …), one likelihood call per camera reads the particles of all
of them (each with its own filter's box, occluder index and colours) and one resampling call draws
every filter's particles from its own weights. The detection filters share one likelihood call too.

New objects are found by **detection filters** (§3.2): particles scattered uniformly over each entry
region (in a scene without entry regions, over the walkable floor in view). A detection filter is a
particle filter too and concentrates on what enters; when the share of its *likely* particles
exceeds α it hands them over to a new tracking filter and is scattered afresh. A **tracking filter**
ends when the share of its likely particles falls to β or below. Likely: the column sees at least
``min_height`` of object (``π·dz ≥ min_height``) in every camera that sees the particle; for the
point likelihood, ``F > γ`` there.

Beyond the paper (on by default; :meth:`ParticleConfig.paper` is the method as published):

* objects that enter together and then part (§6's future work): a filter whose particles have become
  two lumps on the floor is split into two tracks, a detection filter that fires on two lumps starts
  two, and filters that settle on one object are merged (after a longer wait if they stand apart on
  the floor, one behind the other in the image: two people passing);
* explaining away: pixels inside another tracked object's image box read as background, so a filter
  cannot take over a neighbour that shows more foreground, and a detection filter sees only what no
  track explains; where that object stands nearer to the camera they read as occluded (no
  evidence), so a person walking behind another is neither penalised nor pushed off;
* a sharper column weight (the likelihood ratio of an object standing there), a column with a small
  radius standing on the body's near side, floor contact, and cast shadows removed by colour and
  texture — see :class:`ParticleConfig`;
* several cameras: the likelihood multiplies over the cameras that see the particle;
* leaving through an exit: a filter walking off the floor's edge inside an entry region ends at
  once instead of living on with whoever stands in front of the door on its line of sight, and its
  last box stays explained to the detection filters for a moment (``exit_*`` in
  :class:`ParticleConfig`);
* doors out of view: an entry region that the cameras do not see (or see in part) is entered into
  view across the view's edge, so its detection filter also covers the floor in view next to the
  floor out of view near the door (``entry_reach``);
* lost tracks (``births="entry+lost"``, the default where the scene has entry regions): where a
  tracking filter ended by the β rule away from the entry regions, a detection filter watches the
  floor round its last position for a while, so an object that stopped showing enough (a person
  with the feet below the image's edge, or out of the image for a few seconds) is found again,
  under its old id, when it shows, not only when it comes back to a door;
* the particles' z: the column does not depend on it, so after resampling each particle's z is
  drawn uniformly below the top its column sees — the particles then fill the object's height.

A track reports: ``x, y`` the region's centre on the floor; ``z, sx, sy, sz`` (metres, in
``Track.extra`` and the extra columns of ``tracks.csv``) the box ``(x, y, z) ± (sx, sy, sz)``;
``sigma = sqrt((sx² + sy²) / 2)``; ``height`` the mean top the particles' columns see (column
likelihood; the scene's person height for the point likelihood); ``width`` the scene's person width
(a particle cloud says where an object is, not how wide); ``score`` the share of likely particles;
``vx, vy`` the prediction velocity (m/s).

Example
-------
>>> from worldtrack.foreground.background import StaticBackground
>>> tracker = ParticleTracker(scene, {"cam1": StaticBackground(bg, mode="colour")})   # doctest: +SKIP
>>> for index, t, frames in source:                                                 # doctest: +SKIP
...     tracks = tracker.step(frames, t)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np
from scipy.spatial import cKDTree
from scipy.spatial.distance import cdist

from worldtrack.errors import InputError
from worldtrack.scene.model import Scene
from worldtrack.trackers.base import PositionMap, Track, TrackerBase
from worldtrack.foreground.shadows import floor_pixels, hit_image, hit_labels, thresholded_difference
from worldtrack.trackers.particle.appearance import ColourModel, column_penalties, learn_columns
from worldtrack.trackers.particle.likelihood.boxes import Box, boxes_on_one_object, image_box, image_boxes, overlap
from worldtrack.trackers.particle.config import ParticleConfig
from worldtrack.trackers.particle.floor import FloorRegion, polygon_distance, raster_blocks, raster_contains
from worldtrack.trackers.particle.likelihood import (F_MAX, CameraLikelihood, ReadAs, Sums, add_camera, close_sums,
                                                     column_spec, edge_spec, occluder_layers, owner_image,
                                                     top_edge_offsets)
from worldtrack.trackers.particle.likelihood.fused import observe_column
from worldtrack.trackers.particle.likelihood.hidden import inverse_lengths, order_statistic, quantile_rank
from worldtrack.trackers.particle.motion import HeightWalk, jitter_reflect, predict_walk
from worldtrack.trackers.particle.region import cloud_mean, region_sizes
from worldtrack.trackers.particle.resample import Particles, gather_particles, particle_weights, resampler, take_rows
from worldtrack.trackers.particle.split import bimodal_split, splittable

#: The per-particle arrays of a :class:`_Filter`, all indexed alike: the state (``xyz, v, h``) and
#: this frame's observation (``logpi, likely, col_h``).
PARTICLE_FIELDS = ("xyz", "v", "h", "logpi", "likely", "col_h")

#: No colour term (an empty penalty array for :func:`add_camera`).
_NO_PENALTY = np.zeros(0)
#: No random draws (an empty array for a kernel's optional draws).
_NO_DRAWS = np.zeros(0)

#: Depth (m) at which a column sample weighs 1 with ``pixel_weights``: weights are the sample's
#: image length over that of a sample this far from the camera.
REFERENCE_DEPTH = 5.0


@dataclass(eq=False)
class _Filter:
    """One particle filter: a tracking filter, or a detection filter when ``track`` is None.

    ``xyz`` (P, 3) particle positions (m) and ``v`` (P, 3) their own velocities (m/s); ``V`` (2,)
    the object's floor velocity (m/s); ``centre`` (2,) the floor mean after resampling; ``region``
    the area a detection filter scatters over; ``logw`` a detection filter's log weights of the
    last frame (None: scatter afresh); ``until`` (s) the time after which a detection filter that
    watches a lost track's place is dropped (None: kept for good). ``logpi, likely, col_h`` hold
    this frame's observation; ``h`` (P,) each particle's object height (m), where its column's top
    is expected. ``k_lo`` {camera_id: int}: how many of the lowest column samples of this filter's
    particles were hidden (occluded or out of view) last frame, as an order statistic over them (the
    ``common_view`` share, else the median); read by ``pixel_weights="hidden"``, ``coast_hidden``
    and, as the samples that read no evidence, by ``common_view``.
    """

    xyz: np.ndarray
    v: np.ndarray
    track: Track | None = None
    region: FloorRegion | None = None
    V: np.ndarray = field(default_factory=lambda: np.zeros(2))
    centre: np.ndarray | None = None
    logw: np.ndarray | None = None
    until: float | None = None
    lost_id: int | None = None
    low_since: float | None = None
    t_update: float | None = None
    split_count: int = 0
    logpi: np.ndarray | None = None
    likely: np.ndarray | None = None
    col_h: np.ndarray | None = None
    h: np.ndarray | None = None
    colours: dict = field(default_factory=dict)
    k_lo: dict = field(default_factory=dict)

    def take(self, idx: np.ndarray) -> None:
        """Keep the particles ``idx`` (with repeats), this frame's observation included."""
        for name in PARTICLE_FIELDS:
            a = getattr(self, name)
            if a is not None:
                setattr(self, name, a[idx])

    def subset(self, idx: np.ndarray, **fields) -> "_Filter":
        """A new filter of the particles ``idx`` (index array or mask), this frame's observation
        included; ``fields`` set the new filter's other fields or replace its per-particle ones."""
        own = {name: getattr(self, name)[idx] for name in PARTICLE_FIELDS
               if name not in fields and getattr(self, name) is not None}
        return _Filter(**own, **fields)


class ParticleTracker(TrackerBase):
    """Multi-object tracker: one 3-D particle filter per object, detection filters for new ones.

    Parameters
    ----------
    scene : Scene
    foregrounds : {camera_id: foreground model}
        Each needs ``difference(image) -> (H, W) float`` (the Euclidean RGB distance F), e.g.
        :class:`~worldtrack.foreground.background.StaticBackground`; with ``shadows`` also a
        background image (``.background``, or ``.model.getBackgroundImage()``).
    config : ParticleConfig, optional
    position_map : PositionMap, optional — share one between trackers or processes
    rng : numpy.random.Generator, optional — default ``default_rng(config.seed)``

    Attributes
    ----------
    extra_columns : tuple of str — the columns ``tracks.csv`` gets besides the standard ones
    last_masks : {camera_id: (H, W) uint8} — this frame's ``F > γ`` (for overlays)
    filters : list — the tracking filters; ``detectors`` — the detection filters
    """

    extra_columns = ("sigma", "z", "sx", "sy", "sz")

    def __init__(self, scene: Scene, foregrounds: Mapping[str, object], config: ParticleConfig | None = None,
                 position_map: PositionMap | None = None, rng: np.random.Generator | None = None):
        self.scene = scene
        self.config = cfg = config or ParticleConfig()
        self.position_map = position_map if position_map is not None else PositionMap()
        self.rng = rng if rng is not None else np.random.default_rng(cfg.seed)
        if not foregrounds:
            raise InputError("particle tracker: expected at least one camera with a foreground model")
        self.foregrounds = dict(foregrounds)
        for cid, fg in self.foregrounds.items():
            scene.camera(cid)
            if not callable(getattr(fg, "difference", None)):
                raise InputError(f"particle tracker: the foreground model of {cid} has no difference(image)")
            if cfg.shadows != "object" and _background_image(fg) is None:
                raise InputError(f"particle tracker: shadows={cfg.shadows!r} needs the background image of {cid}'s "
                                 "foreground model (use a static background, or set shadows='object')")
        self._cams = {cid: CameraLikelihood(scene.camera(cid)) for cid in self.foregrounds}
        # (C, 2) metres: the cameras' floor positions, for the depth-scaled merge distance.
        self._camera_floor = np.array([cl.camera.centre[:2] for cl in self._cams.values()], dtype=float).reshape(-1, 2)
        self._floor: dict[str, np.ndarray] = {}
        if cfg.shadows != "object":
            walk = scene.walkable.raster(0.01)
            for cid in self.foregrounds:
                occ = scene.occlusion(cid).floor_distance if scene.obstacles else None
                self._floor[cid] = floor_pixels(scene.camera(cid), walk, occ)
        a, b = cfg.hit_rate_object, cfg.hit_rate_background
        self._on, self._off = math.log(a / b), math.log((1 - a) / (1 - b))
        self._n_below = cfg.foot_samples if cfg.weighting == "ratio" else 0
        self._n_above = cfg.head_samples if cfg.weighting == "ratio" else 0
        self.heights = cfg.heights
        self._column = np.concatenate([-cfg.dz * np.arange(self._n_below, 0, -1), self.heights,
                                       self.heights[-1] + cfg.dz * np.arange(1, self._n_above + 1)])
        self._k_min = self._n_below + min(cfg.likely_count, len(self.heights) - 1)
        # Pixel weights: a column sample REFERENCE_DEPTH from a camera weighs 1.
        self._px_scale = {cid: (REFERENCE_DEPTH / (cl.K[1, 1] * cfg.dz)
                                if cfg.pixel_weights == "depth" and cfg.weighting == "ratio" else 0.0)
                          for cid, cl in self._cams.items()}
        self._top_sigma = cfg.top_sigma if cfg.weighting == "ratio" and cfg.likelihood == "column" else 0.0
        # Top-edge samples about each particle's own height: below it on the object, above it over it.
        self._edge = (edge_spec(top_edge_offsets(cfg.top_edge_step, cfg.top_edge_samples), cfg.top_edge, self._on,
                                self._off) if self._top_sigma > 0 and cfg.top_edge > 0 else None)
        self._column_spec = column_spec(self._column, self._on, self._off, self._k_min, cfg.column_radius, -self._on,
                                        self._n_below, self._n_above, self._top_sigma, cfg.out_of_view == "unknown")
        self._resample = resampler(cfg.resampling)
        self._walkable_raster = scene.walkable.raster(0.01)
        self._walkable_blocks = raster_blocks(self._walkable_raster)
        self._walkable = self._walkable_raster.contains
        self.filters: list[_Filter] = []
        self._births = cfg.births if cfg.births != "auto" else ("entry+lost" if scene.entry_regions else "anywhere")
        self.detectors = [_Filter(np.zeros((0, 3)), np.zeros((0, 3)), region=r, h=np.zeros(0))
                          for r in self._detection_regions()]
        self._last_t: float | None = None
        self._close: dict[tuple[int, int], int] = {}
        self._layers: dict = {}          # per camera, the occluder layers reused frame to frame
        self._rows: dict = {}            # per particle field, the tracking filters' rows and their array
        self._which: dict = {}           # (F, N) -> each of F·N particles' filter index
        self._owner_buffers: dict = {}   # per camera, the owner image reused frame to frame and its boxes
        self._frames: dict[str, np.ndarray] = {}  # per camera, this frame's image (appearance)
        self._leaving: list[tuple[Track, float]] = []  # tracks ended at an exit, and when
        self.last_masks: dict[str, np.ndarray] = {}

    # ------------------------------------------------------------------ set-up
    def _detection_regions(self) -> list[FloorRegion]:
        """Where detection filters scatter: entry regions grown by ``entry_margin``, or all floor; in view."""
        cfg, scene = self.config, self.scene
        births = self._births
        if births == "none":
            return []
        in_view = self._in_view
        if births == "anywhere":
            reg = FloorRegion.rasterise("walkable", scene.walkable.bounds, 0.05, in_view)
            if reg.empty:
                raise InputError(f"particle tracker: no walkable floor of scene {scene.name!r} is in view of "
                                 f"{', '.join(self._cams)}")
            return [reg]
        if not scene.entry_regions:
            raise InputError(f"particle tracker: births={births!r} but scene {scene.name!r} has no entry regions")
        regions = []
        m = cfg.entry_margin
        for er in scene.entry_regions:
            p = er.polygon
            near = self._unseen_near(p)
            grow = m + (cfg.entry_reach if near is not None else 0.0)
            bounds = _grown_bounds(p, grow)

            def test(xy: np.ndarray, p: np.ndarray = p, near: "cKDTree | None" = near) -> np.ndarray:
                close = polygon_distance(xy, p) <= m
                if near is not None:                 # where the door's floor comes into view
                    close |= np.isfinite(near.query(xy, distance_upper_bound=m + 1e-9)[0])
                return close & in_view(xy)

            reg = FloorRegion.rasterise(er.name, bounds, 0.02, test)
            if not reg.empty:
                regions.append(reg)
        if not regions:
            raise InputError(f"particle tracker: no entry region of scene {scene.name!r} is in view of "
                             f"{', '.join(self._cams)} (use births='anywhere')")
        return regions

    def _unseen_near(self, polygon: np.ndarray, cell: float = 0.05) -> "cKDTree | None":
        """The walkable floor out of every view within ``entry_reach`` of an entry region's
        ``polygon`` (a grid of ``cell`` m), as a KD-tree of cell centres; None if there is none
        or ``entry_reach`` is 0."""
        reach = self.config.entry_reach
        if reach <= 0:
            return None
        p = polygon
        bounds = _grown_bounds(p, reach)
        unseen = FloorRegion.rasterise("unseen", bounds, cell, lambda xy: (polygon_distance(xy, p) <= reach)
                                       & self.scene.walkable.contains(xy) & ~self._in_view(xy))
        if unseen.empty:
            return None
        j, i = np.nonzero(unseen.raster.inside)
        return cKDTree(unseen.origin + (np.column_stack([i, j]) + 0.5) * cell)

    def _in_view(self, xy: np.ndarray) -> np.ndarray:
        """(N,) bool: floor points ``xy`` (N, 2), metres, are walkable and a column of ``min_height``
        there is inside some camera's image."""
        xy = np.asarray(xy, dtype=float).reshape(-1, 2)
        seen = np.zeros(len(xy), dtype=bool)
        for cl in self._cams.values():
            seen |= cl.camera.sees_standing(xy, self.config.min_height)
        return self.scene.walkable.contains(xy) & seen

    # ------------------------------------------------------------------ public
    def init_track(self, x: float, y: float, track_id: int | None = None, mode: str = "tracking",
                   t: float = 0.0, spread: float = 0.1) -> Track:
        """Start a tracking filter at floor position ``(x, y)`` (m), particles spread ``spread`` (m, 1-σ).

        ``mode`` is there for the signature the trackers share; a particle filter only tracks, so it
        must be ``"tracking"``.
        """
        if mode != "tracking":
            raise InputError(f"particle tracker: init_track mode must be 'tracking' (a particle filter has no "
                             f"other mode), got {mode!r}")
        cfg = self.config
        n = cfg.particles
        xyz = np.column_stack([x + spread * self.rng.standard_normal(n), y + spread * self.rng.standard_normal(n),
                               self.rng.random(n) * cfg.max_height])
        h, w = self.scene.people.size_of(track_id or 0)
        tr = self.position_map.add(x, y, h, w, mode="tracking", time=t, track_id=track_id)
        f = _Filter(xyz, self._draw_velocities(n), track=tr, h=self._draw_heights(n, h))
        self._update_region([f], t)
        self.filters.append(f)
        return tr

    @property
    def tracks(self) -> list[Track]:
        """Copies of the tracking filters' tracks, in id order."""
        return sorted((f.track.copy() for f in self.filters), key=lambda tr: tr.id)

    def step(self, frames: Mapping[str, object], t: float) -> list[Track]:
        """Update every filter with one synchronised bundle of frames taken at time ``t``.

        Parameters
        ----------
        frames : {camera_id: Frame or (H, W, 3) uint8 BGR image}
        t : float, seconds — must not decrease from call to call

        Returns
        -------
        list of Track — the tracking filters' objects (never the detection filters), ids from 1
        """
        cfg = self.config
        t = float(t)
        if not math.isfinite(t):
            raise InputError(f"particle tracker: time stamp must be a finite number of seconds, got {t}")
        if self._last_t is not None and t < self._last_t:
            raise InputError(f"particle tracker: time went backwards ({t} s after {self._last_t} s)")
        dt = 0.0 if self._last_t is None else t - self._last_t
        self._leaving = [(tr, t0) for tr, t0 in self._leaving if t - t0 <= cfg.exit_hold_s]
        self.detectors = [d for d in self.detectors if d.until is None or t <= d.until]
        images = self._images(frames)
        self._last_t = t
        if not images:
            return self.tracks

        # The tracking filters, all at once: they hold ``particles`` particles each, so their
        # arrays stack to (filters, particles, ...) and one likelihood call per camera reads them all.
        fs = list(self.filters)
        if fs:
            self._predict(fs, dt)
            owners = boxes = occluders = centres = None
            if cfg.explain == "all" and len(fs) > 1:      # a lone filter has nothing to explain away
                centres = cloud_mean(self._stacked(fs, "xyz")[:, :, :2])
                boxes = self._boxes([f.track for f in fs], centres, cfg.box_margin)
                owners = self._owner_images(images, boxes)
                if cfg.occlusion:
                    occluders = {cid: occluder_layers(img.shape[:2], boxes[cid], self._cams[cid].distances(centres),
                                                      self._layers.get(cid))
                                 for cid, img in images.items()}
                    self._layers.update(occluders)
            self._observe(fs, images, owners, boxes, occluders, centres)
            self._update_tracking(fs, t)
        if cfg.appearance_weight > 0:
            self._learn_colours(images)

        # Splits and merges first, so a filter that just split into two objects hides both of them
        # from the detection filters below (otherwise the second object is also "detected").
        if cfg.split:
            self._split(t)
        if cfg.merge:
            self._merge()

        # Detection filters read past every track's box (at the updated positions, stretched along
        # the line of sight), so the object just handed over does not fire the fresh detection
        # filter again even where its track sits at the wrong depth.
        if cfg.explain != "none" and self.detectors:
            # Objects that just left through an exit may still show at the floor's edge: their
            # last boxes stay explained for ``exit_hold_s``.
            left = [tr for tr, _ in self._leaving]
            boxes = self._boxes([f.track for f in self.filters] + left,
                                [f.centre for f in self.filters] + [np.array([tr.x, tr.y]) for tr in left],
                                cfg.box_margin, cfg.exclusion_depth)
            owners = self._owner_images(images, boxes)
        if self.detectors:
            for d in self.detectors:
                self._move_detector(d, dt)
            self._observe(self.detectors, images, owners if cfg.explain != "none" else None)
            for d in self.detectors:
                self._update_detector(d, t)

        for f in self.filters:
            f.track.age_frames += 1
        return self.tracks

    # ------------------------------------------------------------------ observation
    def _images(self, frames: Mapping[str, object]) -> dict[str, np.ndarray]:
        """What the likelihood reads, per camera: ``F > γ`` (column) or thresholded F (point)."""
        cfg = self.config
        out = {}
        self.last_masks = {}
        for cid, frame in frames.items():
            if cid not in self.foregrounds:
                continue
            image = frame.image if hasattr(frame, "image") else frame
            cam = self._cams[cid].camera
            if getattr(image, "shape", (0, 0))[:2] != (cam.height, cam.width):
                raise InputError(f"{cid}: frame is {image.shape[1]}x{image.shape[0]} but the camera is "
                                 f"{cam.width}x{cam.height}")
            fg = self.foregrounds[cid]
            F = fg.difference(image) if (cfg.likelihood == "point" or cfg.shadows == "object") else None
            if cfg.shadows != "object":
                hit = hit_labels(image, _background_image(fg), cfg.gamma, where=self._floor[cid],
                                 shadow=2 if cfg.shadows == "unknown" else 0)
            else:
                hit = hit_image(F, cfg.gamma)
            self.last_masks[cid] = hit
            if cfg.appearance_weight > 0:
                self._frames[cid] = image
            out[cid] = hit if cfg.likelihood == "column" else thresholded_difference(np.where(hit == 1, F, 0), cfg.gamma)
        return out

    def _owner_images(self, images: Mapping[str, np.ndarray], boxes: Mapping[str, list]) -> dict[str, np.ndarray]:
        """Per camera, :func:`owner_image` of ``boxes[camera_id]``, in one image per camera reused
        frame to frame (valid until the next call)."""
        out = {}
        for cid, img in images.items():
            buf, previous = self._owner_buffers.get(cid, (None, ()))
            out[cid] = owner_image(img.shape[:2], boxes[cid], buf, previous)
            self._owner_buffers[cid] = (out[cid], list(boxes[cid]))
        return out

    def _boxes(self, tracks: list[Track], centres: list[np.ndarray], margin: float,
               depth: float = 0.0) -> dict[str, list[Box | None]]:
        """Per camera, each track's object box in the image at ``centres`` (:func:`image_boxes`, by
        its kernel :meth:`CameraLikelihood.boxes`)."""
        xy = np.array(centres, dtype=float).reshape(-1, 2)
        widths = np.array([tr.width for tr in tracks], dtype=float)
        heights = np.array([tr.height for tr in tracks], dtype=float)
        return {cid: cl.boxes(xy, widths, heights, margin, depth) for cid, cl in self._cams.items()}

    def likelihood(self, xyz: np.ndarray, images: Mapping[str, np.ndarray],
                   owners: Mapping[str, np.ndarray] | None = None,
                   boxes: Mapping[str, Box | None] | None = None,
                   h: np.ndarray | None = None, occluders: Mapping[str, object] | None = None,
                   me: int | Sequence[int] = -1, colours: Mapping[str, ColourModel] | None = None,
                   which: np.ndarray | None = None,
                   px_scale: Mapping[str, np.ndarray] | None = None, k_lo: Mapping[str, np.ndarray] | None = None,
                   hidden: dict | None = None, top_edge: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Log-likelihood of particles, summed over the cameras that see them.

        The particles of one filter, or (``which``) of several filters in one call: the kernels
        read each particle with its own filter's box, occluder index and colours.

        Parameters
        ----------
        xyz : (N, 3) float, metres
        images : {camera_id: image} — ``F > γ`` (uint8) for the column, thresholded F for the point
        owners : {camera_id: (H, W) uint8}, optional — object boxes per pixel (:func:`owner_image`);
            pixels in a box other than ``boxes[camera_id]`` read as background
        boxes : {camera_id: box or None}, optional — the filter's own object box
        h : (N,) float, metres, optional — the particles' object heights: with ``top_sigma > 0``
            each column's top gets the log prior ``−(top − h)² / (2·top_sigma²)``
        occluders : {camera_id: Occluders}, optional — :func:`occluder_layers` of the same boxes as
            ``owners``, with ``me`` the filter's index among them: a column sample in the box of an
            object nearer to the camera by more than ``occlusion_margin`` is occluded (no evidence)
            rather than background
        colours : {camera_id: ColourModel}, optional — the object's learnt colours: each particle
            adds ``appearance_weight`` times the colour log-ratio of its colour column (see
            :mod:`~worldtrack.trackers.particle.appearance`)
        which : (N,) int, optional — each particle's filter, 0 … F − 1, for the particles of F
            filters: then ``boxes`` maps each camera to a sequence of F boxes (or None), ``me`` is a
            sequence of F indices and ``colours`` a sequence of F mappings (or None), one per filter
        px_scale : {camera_id: (F,) float}, optional — per filter, the pixel-weight scale (1 / pixels,
            0 = unweighted; :meth:`_filter_pixel_scales`); default the camera's ``pixel_weights="depth"``
            scale (0 otherwise) for every particle
        k_lo : {camera_id: (F,) int}, optional — per filter, the lowest column samples that read no
            evidence (``common_view``); default none
        hidden : dict, optional — filled with {camera_id: (N,) int}, how many of each particle's
            lowest column samples are hidden (occluded or out of view)
        top_edge : bool — with ``h``, add ``ParticleConfig.top_edge`` times the top-edge terms at each
            particle's own height (:func:`top_edge_terms`; tracking filters, whose heights have
            settled on their object's), read from the labels as they are, or with
            ``top_edge_explain`` as the column reads them (``owners``, ``boxes``, ``occluders``)

        Returns
        -------
        logpi : (N,) float — log π up to a constant: ``weighting="count"``, the log of the column's
            share of samples on the object (eq. 11 / (T + 1)); ``"ratio"``, the log-likelihood ratio
            of the best object top; point, ``log(F / F_MAX)`` (eq. 7). −inf if no camera sees the
            particle, it is off the walkable floor, or (point) outside [0, max_height]
        likely : (N,) bool — the column sees ≥ ``min_height`` of object (point: ``F > γ``) in every
            camera that sees the particle
        col_h : (N,) float, metres — mean over the seeing cameras of the best top (ratio) or of
            ``π·dz`` (count); 0 for the point
        """
        cfg = self.config
        n = len(xyz)
        if which is None:               # one filter: the case of F = 1
            which = np.zeros(n, dtype=np.int64)
            boxes = {cid: [b] for cid, b in boxes.items()} if boxes is not None else None
            me, colours = [me], [colours]
        if colours is None:
            colours = [None] * len(me)
        sums = Sums.start(n)
        logpi, likely, n_seen, col = sums
        S = len(self.heights)
        spec = self._column_spec if h is not None else self._column_spec._replace(top_sigma=0.0)
        with np.errstate(divide="ignore"):
            for cid, img in images.items():
                cl = self._cams[cid]
                owner = owners.get(cid) if owners is not None else None
                box = boxes.get(cid) if boxes is not None else [None] * len(me)
                read = ReadAs(owner, box, me, which, occluders.get(cid) if occluders is not None else None,
                              cfg.occlusion_margin, self._px_scale[cid] if px_scale is None else px_scale[cid],
                              k_lo[cid] if k_lo is not None else 0)
                if cfg.likelihood == "column" and cfg.weighting == "ratio":
                    # The default: the whole camera's share in one compiled call (observe_column).
                    hid = np.empty(n, dtype=np.int32)
                    frame = self._frames.get(cid)
                    reading = cl.reading(img, n, read, h)
                    observe_column(cl, xyz, cfg.surface_offset, spec, reading, img, frame,
                                   [c.get(cid) if c else None for c in colours] if frame is not None else (),
                                   cfg.appearance_weight, cfg.likely_count, sums, hid)
                    if hidden is not None:
                        hidden[cid] = hid
                    if top_edge and h is not None and self._edge is not None:
                        # Raw labels unless top_edge_explain: no boxes, so codes are the labels themselves.
                        edge_reading = reading if cfg.top_edge_explain else cl.reading(img, n)
                        cl.top_edge(edge_reading, xyz, h, self._edge, logpi)
                    continue
                if cfg.likelihood == "column":
                    surface = self._near_surface(xyz, cl)
                    counts, ratio, top, seen, hid = cl.column(img, surface, spec, read, h)
                    if hidden is not None:
                        hidden[cid] = hid
                    if cfg.weighting == "count":
                        lv, col_h = np.log(counts / S), counts * cfg.dz
                    else:
                        lv, col_h = ratio, self._column[top]
                    ok = counts >= cfg.likely_count
                    penalty = _NO_PENALTY
                    if cid in self._frames:
                        models = [c.get(cid) if c else None for c in colours]
                        # Each particle's colour column under its filter's model (0 where nothing is learnt).
                        penalty = column_penalties(cl, self._frames[cid], img, surface, models, which)
                else:
                    values, seen = cl.point(img, xyz, owner, box, which)
                    lv, col_h, penalty = np.log(values / F_MAX), np.zeros(n), _NO_PENALTY
                    ok = values > 0
                # logpi += lv (+ the colour term) where seen; likely &= ok | ~seen; n_seen += seen
                add_camera(seen, lv, penalty, float(cfg.appearance_weight), col_h, ok, logpi, likely, n_seen, col)
        if cfg.likelihood == "column":
            # −inf, not likely off the walkable floor or where no camera sees; col over the cameras that see
            close_sums(n_seen, xyz, self._walkable_raster, logpi, likely, col, self._walkable_blocks)
            return logpi, likely, col
        valid = (n_seen > 0) & raster_contains(self._walkable_raster, xyz, self._walkable_blocks)
        valid &= (xyz[:, 2] >= 0) & (xyz[:, 2] <= cfg.max_height)
        logpi = np.where(valid, logpi, -np.inf)
        return logpi, likely & valid, col / np.maximum(n_seen, 1)

    def _learn_colours(self, images: Mapping[str, np.ndarray]) -> None:
        """Teach each filter the colours on its column, in the cameras where its box overlaps no other's.

        The column at the particles' mean and two beside it (±width/4 across the line of sight),
        object samples only; filters with fewer than half their particles likely learn nothing.
        """
        cfg = self.config
        fs = self.filters
        # More than half likely (the mean of the booleans above 0.5, with integers).
        learners = np.array([f.likely is not None and 2 * np.count_nonzero(f.likely) > len(f.likely) for f in fs],
                            dtype=bool)
        if not learners.any():
            return
        centres = np.array([f.centre for f in fs], dtype=float).reshape(-1, 2)
        widths = np.array([f.track.width for f in fs], dtype=float)
        heights = np.array([f.track.height for f in fs], dtype=float)
        for cid, hit in images.items():
            # The boxes (box_margin), those overlapping no other, the three columns of each, their
            # colour bins and the histograms' blend: learn_columns, one compiled call.
            models = [f.colours.get(cid) for f in fs]
            given = [m if m is not None else ColourModel() for m in models]
            chosen = learn_columns(self._cams[cid], self._frames[cid], hit, centres, widths, heights, learners,
                                   cfg.box_margin, cfg.surface_offset, given, cfg.appearance_rate)
            for f, m, new, taught in zip(fs, models, given, chosen.tolist()):
                if taught and m is None:                # a filter taught for the first time keeps its model
                    f.colours[cid] = new

    def _near_surface(self, xy: np.ndarray, cl: CameraLikelihood) -> np.ndarray:
        """Where a camera's column stands for particles at ``xy`` (N, 2) (or the floor positions of
        ``xyz`` (N, 3)): ``surface_offset`` m nearer to it."""
        r = self.config.surface_offset
        if r <= 0:
            return xy[:, :2]
        return cl.near_surface(xy, r)

    # ------------------------------------------------------------------ prediction
    def _predict(self, fs: list[_Filter], dt: float) -> None:
        """Eqs. 1–2 in real time, for tracking filters ``fs`` at once: ``x_t = x_{t−1} + v·dt + w``,
        ``w ~ N(0, σ²·dt)``; and the random walk of the particles' heights."""
        cfg = self.config
        if dt <= 0:
            return
        old = self._stacked(fs, "xyz")
        noise = np.array([cfg.noise_xy, cfg.noise_xy, cfg.noise_z]) * math.sqrt(dt)
        a = self.rng.standard_normal(old.shape)
        if cfg.velocity == "state":
            # Constant velocity: each particle's own velocity walks by noise_v·√dt, then moves it;
            # and the heights' walk (_jitter_heights), all in one call with the draws in their order.
            v = self._stacked(fs, "v")                      # walked in place
            scale = cfg.noise_v * math.sqrt(dt) * self._coasting(fs)
            xyz = np.empty_like(old)
            walk = self.rng.standard_normal(v.shape[:2] + (2,))
            h = np.ascontiguousarray(self._stacked(fs, "h"), dtype=np.float64)
            jitter = self._top_sigma > 0 and cfg.noise_h > 0 and h.size
            h_out = np.empty(h.shape) if jitter else h
            heights = HeightWalk(h, self.rng.standard_normal(h.shape) if jitter else _NO_DRAWS,
                                 cfg.noise_h * math.sqrt(dt), float(cfg.min_height), float(cfg.max_height), h_out)
            predict_walk(old, a, noise, v, walk, scale, float(cfg.max_speed), float(dt), xyz, heights)
            self._set_rows(fs, "v", v)
        else:
            step = a * noise
            if cfg.velocity == "particle":
                step += self._stacked(fs, "v") * dt
            elif cfg.velocity == "object":
                step[..., :2] += np.array([f.V for f in fs])[:, None, :] * dt
            xyz = old + step
            h_out = None
        if cfg.likelihood == "point":
            xyz[..., 2] = _reflect(xyz[..., 2], 0.0, cfg.max_height)
        self._set_rows(fs, "h", self._jitter_heights(self._stacked(fs, "h"), dt) if h_out is None else h_out)
        self._set_rows(fs, "xyz", xyz)
        if cfg.velocity == "particle":
            # v_t = (x_t − x_{t−1}) / dt, each particle's velocity for the next frame (eq. 2).
            v = (xyz - old) / dt
            _clip_speed(v, cfg.max_speed)
            self._set_rows(fs, "v", v)

    def _coasting(self, fs: list[_Filter]) -> np.ndarray:
        """(F,) factor of the velocity walk of filters ``fs``: ``1 − hidden / coast_hidden`` clipped to
        [0, 1], ``hidden`` the share of column samples hidden (``k_lo``) in the camera that sees
        most of the object; 1 with ``coast_hidden = 0``."""
        cfg = self.config
        if cfg.coast_hidden <= 0:
            return np.ones(len(fs))
        n = len(self._column)
        return np.array([min(max(1.0 - (min(f.k_lo.values(), default=0) / n) / cfg.coast_hidden, 0.0), 1.0)
                         for f in fs])

    def _jitter_heights(self, h: np.ndarray, dt: float) -> np.ndarray:
        """Particles' object heights ``h`` (any shape) after a random walk of ``noise_h·√dt``, kept
        in [min_height, max_height] (a new array; ``h`` itself when there is no walk)."""
        cfg = self.config
        if self._top_sigma > 0 and cfg.noise_h > 0 and dt > 0 and h.size:
            out = np.empty(h.shape)
            jitter_reflect(np.ascontiguousarray(h, dtype=np.float64), self.rng.standard_normal(h.shape),
                           cfg.noise_h * math.sqrt(dt), float(cfg.min_height), float(cfg.max_height), out)
            return out
        return h

    def _stacked(self, fs: list[_Filter], name: str) -> np.ndarray:
        """(F, N, ...) the per-particle array ``name`` of filters ``fs`` holding N particles each:
        the array whose rows they hold, if :meth:`_set_rows` gave them those rows and they still
        hold them (not to be changed then, except as the filters' own arrays), else a stacked copy."""
        rows, a = self._rows.get(name, ((), None))
        if len(rows) == len(fs) and all(getattr(f, name) is r for f, r in zip(fs, rows)):
            return a
        return _stack(fs, name)

    def _set_rows(self, fs: list[_Filter], name: str, a: np.ndarray) -> None:
        """Give each of filters ``fs`` its row of ``a`` (F, N, ...) as its ``name`` (views), and
        remember them for :meth:`_stacked`."""
        rows = list(a)
        for f, r in zip(fs, rows):
            setattr(f, name, r)
        self._rows[name] = (rows, a)

    def _draw_velocities(self, n: int) -> np.ndarray:
        """(n, 3) velocities (m/s) of a new tracking filter's particles: with ``velocity="state"``
        ~ N(0, velocity_spread²) on each floor axis (the object's velocity is unknown yet), else 0."""
        cfg = self.config
        v = np.zeros((n, 3))
        if cfg.velocity == "state" and cfg.velocity_spread > 0:
            v[:, :2] = cfg.velocity_spread * self.rng.standard_normal((n, 2))
            _clip_speed(v, cfg.max_speed)
        return v

    def _draw_heights(self, n: int, centre: float | None = None) -> np.ndarray:
        """(n,) object heights ~ N(centre, height_spread²) in [min_height, max_height] (default centre:
        the scene's person height)."""
        cfg = self.config
        c = self.scene.people.height if centre is None else centre
        return _reflect(c + cfg.height_spread * self.rng.standard_normal(n), cfg.min_height, cfg.max_height)

    def _move_detector(self, d: _Filter, dt: float) -> None:
        """Resample a detection filter by last frame's weights, jitter, and scatter a share afresh."""
        cfg = self.config
        n = cfg.detection_particles
        if d.logw is None:
            d.xyz, d.v, d.h = self._scatter(d.region, n), np.zeros((n, 3)), self._draw_heights(n)
            return
        keep = self._resample(self._weights(d.logw), n, self.rng)
        d.xyz, d.h = d.xyz[keep], d.h[keep]
        d.xyz[:, :2] += self.rng.standard_normal((n, 2)) * (cfg.detection_noise * math.sqrt(max(dt, 0.0)))
        d.h = self._jitter_heights(d.h, dt)
        fresh = (self.rng.random(n) < cfg.detection_reseed) | ~d.region.contains(d.xyz[:, :2])
        k = int(fresh.sum())
        if k:
            d.xyz[fresh] = self._scatter(d.region, k)
            d.h[fresh] = self._draw_heights(k)

    def _scatter(self, region: FloorRegion, n: int) -> np.ndarray:
        """(n, 3) particles uniform over the region's floor and over heights [0, max_height]."""
        return np.column_stack([region.sample(n, self.rng), self.rng.random(n) * self.config.max_height])

    # ------------------------------------------------------------------ tracking filters
    def _weights(self, logpi: np.ndarray) -> np.ndarray:
        """Eq. 8 up to its sum (the resampler normalises), along the last axis of ``logpi`` (one row
        per filter): ``g ∝ π^κ``; uniform in a row whose every π is 0."""
        return particle_weights(logpi, self.config.likelihood_power)

    def _resampled(self, parts: dict[str, np.ndarray], weights: np.ndarray, n: int) -> dict[str, np.ndarray]:
        """The particles of F filters resampled to ``n`` each in proportion to ``weights`` (F, M).

        ``parts`` maps each per-particle field to its (F, M, ...) array; returns them (F, n, ...).
        With the column likelihood each particle's z is then drawn uniformly below the top its column
        sees (the column does not depend on z), so that the particles fill the object (the box's z
        extent)."""
        idx = self._resample(weights, n, self.rng)
        column = self.config.likelihood == "column"
        if tuple(parts) == PARTICLE_FIELDS and parts["likely"].dtype == np.bool_:
            # All six fields (as tracking filters hold them): one kernel, heights drawn in it.
            arrays = gather_particles(idx, Particles(*parts.values()), z=self.rng.random(idx.shape) if column else None)
            return dict(zip(PARTICLE_FIELDS, arrays))
        out = {name: take_rows(a, idx) for name, a in parts.items()}
        if column:
            out["xyz"][..., 2] = self.rng.random(idx.shape) * out["col_h"]
        return out

    def _resample_filter(self, f: _Filter, weights: np.ndarray, n: int) -> None:
        """:meth:`_resampled` of one filter, in place."""
        parts = {name: getattr(f, name)[None] for name in PARTICLE_FIELDS if getattr(f, name) is not None}
        for name, a in self._resampled(parts, weights[None], n).items():
            setattr(f, name, a[0])

    def _observe(self, fs: list[_Filter], images: Mapping[str, np.ndarray],
                 owners: Mapping[str, np.ndarray] | None = None,
                 boxes: Mapping[str, list[Box | None]] | None = None,
                 occluders: Mapping[str, object] | None = None, centres: np.ndarray | None = None) -> None:
        """This frame's observation (``logpi, likely, col_h``) of filters ``fs``, in one likelihood call.

        ``boxes`` and ``occluders`` (optional) are of the filters' objects in the order of ``fs``;
        ``centres`` (optional, (F, 2)) their particles' mean floor positions, if already at hand."""
        cfg = self.config
        tracking = fs[0].track is not None
        scales = k_lo = hidden = None
        if cfg.pixel_weights in ("filter", "hidden") and cfg.weighting == "ratio" and tracking:
            # "hidden": only where the lower body was hidden last frame (above the foot samples).
            nb = self._n_below
            if cfg.pixel_weights == "hidden" and not any(f.k_lo.get(cid, 0) > nb for f in fs for cid in images):
                scales = {cid: np.zeros(len(fs)) for cid in images}   # nobody hidden: no scales to compute
            else:
                use = ({cid: np.array([f.k_lo.get(cid, 0) > nb for f in fs]) for cid in images}
                       if cfg.pixel_weights == "hidden" else None)
                scales = self._filter_pixel_scales(self._centres(fs, centres), images)
                if use is not None:
                    scales = {cid: np.where(use[cid], s, 0.0) for cid, s in scales.items()}
        if ((cfg.common_view > 0 or cfg.coast_hidden > 0 or cfg.pixel_weights == "hidden")
                and cfg.likelihood == "column" and tracking):
            hidden = {}
            if cfg.common_view > 0 and cfg.weighting == "ratio":
                k_lo = {cid: np.array([f.k_lo.get(cid, 0) for f in fs], dtype=np.int64) for cid in images}
        if tracking:                                    # equal particle counts: (F, N) as (F·N,)
            n = len(fs[0].xyz)
            xyz, h = self._stacked(fs, "xyz").reshape(-1, 3), self._stacked(fs, "h").reshape(-1)
            which = self._which.get((len(fs), n))
            if which is None:
                which = self._which[(len(fs), n)] = np.repeat(np.arange(len(fs)), n)
        else:
            sizes = [len(f.xyz) for f in fs]
            xyz, h = np.concatenate([f.xyz for f in fs]), np.concatenate([f.h for f in fs])
            which = np.repeat(np.arange(len(fs)), sizes)
        out = self.likelihood(xyz, images, owners, boxes, h, occluders, np.arange(len(fs)), [f.colours for f in fs],
                              which, scales, k_lo, hidden, top_edge=tracking)
        if hidden:
            # Next frame's k_lo: the share ``common_view`` of the filter's columns see every sample
            # from there up (tracking filters hold equal particle counts).
            # (np.quantile(..., method="higher") of each row, as the order statistic it picks.)
            rank = quantile_rank(n, cfg.common_view or 0.5)
            for cid, hid in hidden.items():
                for f, v in zip(fs, order_statistic(hid.reshape(len(fs), n), rank).tolist()):
                    f.k_lo[cid] = v
        if tracking:
            for name, a in zip(("logpi", "likely", "col_h"), out):
                self._set_rows(fs, name, a.reshape(len(fs), -1))
            return
        ends = np.cumsum(sizes).tolist()
        for name, a in zip(("logpi", "likely", "col_h"), out):
            for f, start, end in zip(fs, [0] + ends, ends):
                setattr(f, name, a[start:end])

    def _centres(self, fs: list[_Filter], centres: np.ndarray | None) -> np.ndarray:
        """(F, 2) the mean floor position of each filter's particles (``centres`` if given)."""
        return cloud_mean(self._stacked(fs, "xyz")[:, :, :2]) if centres is None else centres

    def _filter_pixel_scales(self, centres: np.ndarray, cameras) -> dict[str, np.ndarray]:
        """``pixel_weights="filter"``: per camera, (F,) 1 / the mean image length (pixels) of a body
        sample of the column at each of ``centres`` (F, 2), metres; 0 where it does not project."""
        out = {}
        top = float(self.heights[-1])
        for cid in cameras:
            cl = self._cams[cid]
            xy = self._near_surface(centres, cl)
            ends = np.empty((2, len(xy), 3))            # the column's foot and top points, (2F, 3)
            ends[:, :, :2] = xy
            ends[0, :, 2], ends[1, :, 2] = 0.0, top
            uv = cl.camera.project(ends.reshape(-1, 3)).reshape(2, len(xy), 2)
            out[cid] = np.empty(len(xy))
            inverse_lengths(uv, len(self.heights) - 1, out[cid])
        return out

    def _update_tracking(self, fs: list[_Filter], t: float) -> None:
        """Share of likely particles (end at ≤ β), weights (eq. 8), resampling and object region of
        the tracking filters ``fs`` (equal particle counts), at once."""
        cfg = self.config
        parts = {name: self._stacked(fs, name) for name in PARTICLE_FIELDS if getattr(fs[0], name) is not None}
        # The share of likely particles (a count over N: the mean of the booleans, exactly).
        shares = (parts["likely"].sum(axis=1) / parts["likely"].shape[1]).tolist()
        resampled = self._resampled(parts, self._weights(parts["logpi"]), cfg.particles)
        kept, lost = [], []
        for f, share in zip(fs, shares):
            if share <= cfg.beta:
                if f.low_since is None:
                    f.low_since = t
                if t - f.low_since >= cfg.end_after_s:
                    self._end(f)
                    lost.append(f.track)
                    continue
            else:
                f.low_since = None
                f.track.last_seen = t
            f.track.score = share
            kept.append(f)
        if len(kept) == len(fs):
            for name, a in resampled.items():
                self._set_rows(fs, name, a)
        else:
            rows = [i for i, f in enumerate(fs) if f in kept]
            for name, a in resampled.items():
                for i in rows:
                    setattr(fs[i], name, a[i])
        self._watch_lost(lost, t)
        if not kept:
            return
        self._update_region(kept, t)
        for f, leaving in zip(kept, self._left_through_exit([f.track for f in kept])):
            if leaving:
                self._leaving.append((f.track, t))
                self._end(f)

    def _update_region(self, fs: list[_Filter], t: float) -> None:
        """Object region (eqs. 9–10) and the track's fields, from the resampled particles, of filters
        ``fs`` at once (equal particle counts)."""
        cfg = self.config
        centre, sd = _mean_sd(self._stacked(fs, "xyz"))
        if cfg.velocity == "object":
            V = np.array([f.V for f in fs], dtype=float).reshape(-1, 2)
            prev = np.array([(np.nan, np.nan) if f.centre is None else f.centre for f in fs], dtype=float)
            since = np.array([np.nan if f.t_update is None else t - f.t_update for f in fs])
            moved = np.isfinite(prev[:, 0]) & (since > 0)
            if moved.any():
                a = cfg.velocity_smoothing
                V[moved] = (1 - a) * V[moved] + a * (centre[moved, :2] - prev[moved]) / since[moved, None]
                _clip_speed(V, cfg.max_speed)
        elif cfg.velocity in ("particle", "state"):
            V = cloud_mean(self._stacked(fs, "v")[..., :2])
        else:
            V = np.zeros((len(fs), 2))
        heights = None
        if cfg.likelihood == "column" and self._top_sigma > 0:
            heights = _mean_rows(self._stacked(fs, "h"))
        elif cfg.likelihood == "column" and all(f.col_h is not None for f in fs):
            heights = _mean_rows(self._stacked(fs, "col_h"))
        # sigma = sqrt((sx² + sy²) / 2); with the ratio weighting the particles are the object's axis
        # on the floor and the object fills a disc of radius width/2 round it (per-axis variance
        # r²/4), as its z fills the height below the top: then sx, sy = hypot(sx, width/4).
        widths = (np.array([f.track.width for f in fs], dtype=float)
                  if cfg.likelihood == "column" and cfg.weighting == "ratio" else _NO_WIDTHS)
        sigma = np.empty(len(fs))
        region_sizes(sd, widths, sigma)
        floor_centre = centre[:, :2].copy()
        rows = zip(fs, floor_centre, V, centre.tolist(), V.tolist(), sd.tolist(), sigma.tolist(),
                   heights.tolist() if heights is not None else [None] * len(fs))
        for f, c, v, (x, y, z), (vx, vy), (sx, sy, sz), s, height in rows:
            f.centre, f.t_update = c, t
            if cfg.velocity == "object":
                f.V = v
            tr = f.track
            tr.x, tr.y, tr.vx, tr.vy, tr.sigma = x, y, vx, vy, s
            if height is not None:
                tr.height = height
            tr.extra.update(z=z, sx=sx, sy=sy, sz=sz)

    def _left_through_exit(self, tracks: list[Track]) -> np.ndarray:
        """(F,) bool: whether each track's object is walking off the floor through an entry region: its
        centre is in one, it moves at ≥ ``exit_speed`` and the centre ``exit_lookahead_s`` ahead is off
        the walkable floor. Nobody can be beyond the floor's edge, so what the column still reads
        there is somebody else (in front of the door on the same line of sight), not the object."""
        cfg = self.config
        if cfg.exit_lookahead_s <= 0 or not self.scene.entry_regions or not tracks:
            return np.zeros(len(tracks), dtype=bool)
        here = np.array([[tr.x, tr.y] for tr in tracks], dtype=float)
        v = np.array([[tr.vx, tr.vy] for tr in tracks], dtype=float)
        return ((np.hypot(v[:, 0], v[:, 1]) >= cfg.exit_speed) & (self.scene.entry_region_index(here) >= 0)
                & ~self._walkable(here + cfg.exit_lookahead_s * v))

    # ------------------------------------------------------------------ detection filters
    def _update_detector(self, d: _Filter, t: float) -> None:
        """Fire when the share of likely particles exceeds α; else keep the weights for next frame."""
        cfg = self.config
        share = float(d.likely.mean()) if len(d.likely) else 0.0
        if share > cfg.alpha:
            self._spawn(d, np.flatnonzero(d.likely), t)
            d.logw = None
            if d.until is not None:          # a lost track's watch: found, dropped next frame
                d.until = -math.inf
            return
        d.logw = d.logpi if np.isfinite(d.logpi).any() else None

    def _watch_lost(self, tracks: list[Track], t: float) -> None:
        """``births="entry+lost"``: watch where each of ``tracks`` (ended by the β rule at time ``t``,
        seconds) was last, unless an entry region's detection filter covers that place already.

        The watch is a detection filter over the floor in view within ``lost_radius`` (m) of the
        track's last ``(x, y)``, kept until ``t + lost_hold_s`` or until it starts a track.
        """
        cfg = self.config
        if self._births != "entry+lost" or not tracks or cfg.lost_radius <= 0 or cfg.lost_hold_s <= 0:
            return
        xy = np.array([[tr.x, tr.y] for tr in tracks], dtype=float)
        covered = np.zeros(len(xy), dtype=bool)
        for d in self.detectors:
            if d.until is None:
                covered |= d.region.contains(xy)
        r = cfg.lost_radius
        for k in np.flatnonzero(~covered):
            c = xy[k]
            reg = FloorRegion.rasterise(f"lost {tracks[k].id}", (c[0] - r, c[0] + r, c[1] - r, c[1] + r), 0.05,
                                        lambda p, c=c: (np.hypot(p[:, 0] - c[0], p[:, 1] - c[1]) <= r)
                                        & self._in_view(p))
            if not reg.empty:
                self.detectors.append(_Filter(np.zeros((0, 3)), np.zeros((0, 3)), region=reg, h=np.zeros(0),
                                              until=t + cfg.lost_hold_s, lost_id=tracks[k].id))

    def _spawn(self, d: _Filter, idx: np.ndarray, t: float) -> None:
        """Start tracking filters from a detection filter's likely particles, one per lump."""
        cfg = self.config
        lumps = self._lumps(d.xyz, idx, depth=2) if cfg.split else [idx]
        # A lost track's watch (``lost_same_id``): its biggest lump is that object found again.
        same = (d.lost_id if cfg.lost_same_id and d.lost_id is not None and d.lost_id not in self.position_map
                else None)
        big = max(range(len(lumps)), key=lambda i: len(lumps[i]))
        for i, g in enumerate(lumps):
            f = d.subset(g, v=self._draw_velocities(len(g)))
            self._resample_filter(f, self._weights(f.logpi), cfg.particles)
            self._new_track(f, t, score=float(d.likely.mean()), track_id=same if i == big else None)

    def _new_track(self, f: _Filter, t: float, score: float, track_id: int | None = None) -> None:
        c = f.xyz.mean(axis=0)
        tr = self.position_map.add(c[0], c[1], mode="tracking", time=t, track_id=track_id)
        tr.height, tr.width = self.scene.people.size_of(tr.id)
        tr.score = score
        f.track = tr
        self._update_region([f], t)
        self.filters.append(f)

    def _lumps(self, xyz: np.ndarray, idx: np.ndarray, depth: int) -> list[np.ndarray]:
        """Split particle indices ``idx`` into lumps on the floor, recursively (up to 2^depth)."""
        side = self._two_objects(xyz[idx, :2])
        if side is None or depth == 0:
            return [idx]
        return self._lumps(xyz, idx[~side], depth - 1) + self._lumps(xyz, idx[side], depth - 1)

    def _two_objects(self, xy: np.ndarray, principal: tuple | None = None) -> np.ndarray | None:
        """Which side of a two-lump cloud each particle is on, or None for one object.

        Two lumps (:func:`~worldtrack.trackers.particle.sampling.bimodal_split`) are two objects only
        if the cameras can tell them apart: their image boxes must overlap less than
        ``merge_overlap`` in some camera that sees both (lumps one behind the other on a single
        camera's line of sight are the depth ambiguity of one object, not two objects). ``principal``:
        the cloud's row of :func:`~worldtrack.trackers.particle.sampling.splittable`'s, if at hand.
        """
        cfg = self.config
        side = bimodal_split(xy, cfg.split_distance, cfg.split_dip, cfg.split_min_mass, principal=principal)
        if side is None:
            return None
        h, w = self.scene.people.height, self.scene.people.width
        lumps = np.array([xy[~side].mean(axis=0), xy[side].mean(axis=0)])
        for cl in self._cams.values():
            p, q = cl.boxes(lumps, w, h, 0.0)
            if p is not None and q is not None and overlap(p, q) < cfg.merge_overlap:
                return side
        return None

    # ------------------------------------------------------------------ split and merge
    def _split(self, t: float) -> None:
        """:meth:`_maybe_split` every tracking filter; the cheap first test of the two-lump check
        (:func:`~worldtrack.trackers.particle.sampling.splittable`) for all of them at once."""
        cfg = self.config
        fs = list(self.filters)
        if fs:
            wide, principal = splittable(self._stacked(fs, "xyz")[:, :, :2], cfg.split_distance,
                                         cfg.split_min_mass, principal=True)
            for f, w, pc in zip(fs, wide.tolist(), principal):
                self._maybe_split(f, t, w, pc)

    def _maybe_split(self, f: _Filter, t: float, wide: bool = True, principal: tuple | None = None) -> None:
        """Split a filter whose particles have been two lumps for ``split_frames`` frames (``wide``
        False: its cloud failed :func:`~worldtrack.trackers.particle.sampling.splittable`, one lump;
        ``principal``: its cloud's row of splittable's, if at hand)."""
        cfg = self.config
        side = self._two_objects(f.xyz[:, :2], principal) if wide else None
        f.split_count = f.split_count + 1 if side is not None else 0
        if f.split_count < cfg.split_frames:
            return
        f.split_count = 0
        keep, other = (~side, side) if (~side).sum() >= side.sum() else (side, ~side)
        new = f.subset(other, V=f.V.copy(), centre=f.centre.copy(), t_update=f.t_update)
        f.take(np.flatnonzero(keep))
        for g in (f, new):
            self._resample_filter(g, np.ones(len(g.xyz)), cfg.particles)
        self._update_region([f], t)
        self._new_track(new, t, score=f.track.score)

    def _merge(self) -> None:
        """End the younger of two filters that have stayed on one object for ``merge_frames`` frames
        (``merge_far_frames`` while their centres stand more than ``merge_distance`` apart on the
        floor: one behind the other, which two people passing also are for a moment).

        On one object: their image boxes (:func:`image_box`) overlap by at least ``merge_overlap``
        (intersection over the smaller box) in every camera that sees both.
        """
        cfg = self.config
        fs = self.filters
        if len(fs) < 2:
            self._close = {}
            return
        c = np.array([f.centre for f in fs], dtype=float)
        xy, widths, heights = c, [f.track.width for f in fs], [f.track.height for f in fs]
        close = boxes_on_one_object(np.stack([cl.box_array(xy, widths, heights, 0.0) for cl in self._cams.values()]),
                                    float(cfg.merge_overlap))
        pairs = np.nonzero(close)
        if not len(pairs[0]):
            self._close = {}
            return
        far = cdist(c, c) > self._merge_distances(c)
        close_now, frames = set(), {}
        for i, j in zip(*pairs):
            a, b = fs[i].track.id, fs[j].track.id
            close_now.add((min(a, b), max(a, b)))
            # One behind the other on the floor: two people passing, unless it lasts.
            frames[(min(a, b), max(a, b))] = cfg.merge_far_frames if far[i, j] else cfg.merge_frames
        self._close = {k: self._close.get(k, 0) + 1 for k in close_now}
        by_id = {f.track.id: f for f in fs}
        for (ia, ib), n in list(self._close.items()):
            if n >= frames[(ia, ib)] and ia in by_id and ib in by_id:
                a, b = by_id[ia], by_id[ib]
                self._end(b if (b.track.born, b.track.id) > (a.track.born, a.track.id) else a)
                del self._close[(ia, ib)]

    def _merge_distances(self, centres: np.ndarray) -> np.ndarray:
        """(F, F) metres: how far apart on the floor two filters' centres (F, 2) may be and still
        count as one object for ``_merge``: ``merge_distance``, grown in proportion to the pair's
        floor distance from the nearest camera beyond ``merge_depth`` (one camera's depth error
        grows with distance; at 30 m a duplicate of one person stands a metre behind it)."""
        cfg = self.config
        depth = cdist(centres, self._camera_floor).min(axis=1)
        pair = 0.5 * (depth[:, None] + depth[None, :])
        return cfg.merge_distance * np.maximum(1.0, pair / cfg.merge_depth)

    def _end(self, f: _Filter) -> None:
        if f in self.filters:
            self.filters.remove(f)
        if f.track is not None and f.track.id in self.position_map:
            self.position_map.remove(f.track.id)


def _grown_bounds(polygon: np.ndarray, margin: float) -> tuple[float, float, float, float]:
    """(x0, x1, y0, y1) metres: the bounding box of ``polygon`` (N, 2) grown by ``margin`` on each side."""
    (x0, y0), (x1, y1) = polygon.min(axis=0), polygon.max(axis=0)
    return (x0 - margin, x1 + margin, y0 - margin, y1 + margin)


def _stack(fs: list[_Filter], name: str) -> np.ndarray:
    """(F, N, ...) the per-particle array ``name`` of filters holding N particles each."""
    return np.stack([getattr(f, name) for f in fs])


def _mean_rows(a: np.ndarray) -> np.ndarray:
    """(F,) the mean of each row of ``a`` (F, N): ``a.mean(axis=1)``, which is this sum over N."""
    return np.add.reduce(a, axis=1) / a.shape[1]


_NO_WIDTHS = np.zeros(0)


def _mean_sd(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`~worldtrack.trackers.particle.sampling.cloud_mean` and the standard deviation over the particles of each filter, two (F, C)."""
    mean = cloud_mean(x)
    d = x - mean[:, None, :]
    return mean, np.sqrt(cloud_mean(d * d))


def _background_image(fg: object) -> np.ndarray | None:
    """The background image of a foreground model: ``.model.getBackgroundImage()`` or ``.background``."""
    model = getattr(fg, "model", None)
    if model is not None and hasattr(model, "getBackgroundImage"):
        bg = model.getBackgroundImage()
        if bg is not None:
            return bg
    bg = getattr(fg, "background", None)
    return bg if isinstance(bg, np.ndarray) else None


def _reflect(z: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Fold values into [lo, hi] by reflection at the ends."""
    span = hi - lo
    r = np.mod(z - lo, 2 * span)
    return lo + np.where(r > span, 2 * span - r, r)


def _clip_speed(v: np.ndarray, max_speed: float) -> None:
    """Scale the velocities in ``v`` (..., ≥ 2) whose floor speed exceeds ``max_speed`` (in place)."""
    s = np.hypot(v[..., 0], v[..., 1])
    over = s > max_speed
    if over.any():
        v[over, :2] *= (max_speed / s[over])[:, None]


__all__ = ["ParticleConfig", "ParticleTracker", "image_box", "image_boxes"]
