"""The likelihoods a configuration names (``particle.likelihood.model``), each a component chosen once.

* ``column-ratio`` (:class:`ColumnRatio`, worldtrack's default) — the likelihood ratio of "an object
  stands here, up to its best top" against "no object", from the height column with its ring of
  samples below the floor and above the top, the height prior and the top edge, and the colour
  penalty; sharp along the line of sight, where the count is nearly flat;
* ``column-count`` (:class:`ColumnCount`, the paper's eq. 11) — ``π ∝`` the samples on ``F > γ``;
* ``point`` (:class:`Point`, eq. 7) — ``π = F`` at the particle's own point.

Each is called with the particles of one or more filters (:class:`Readers`: each particle's filter,
each filter's colours, pixel scales and hidden samples) and one frame (:class:`FrameView`: per
camera the image it reads, and the objects' boxes and occluders), and multiplies over the cameras
that see a particle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Mapping, Protocol, Sequence

import numpy as np

from worldtrack.registry import Registry
from worldtrack.scene.floor import WalkableRaster
from worldtrack.trackers.particle.appearance import column_penalties
from worldtrack.trackers.particle.floor import raster_blocks, raster_contains
from worldtrack.trackers.particle.likelihood.camera import CameraLikelihood
from worldtrack.trackers.particle.likelihood.column import column_heights, column_spec
from worldtrack.trackers.particle.likelihood.fused import observe_column
from worldtrack.trackers.particle.likelihood.images import Occluders
from worldtrack.trackers.particle.likelihood.point import F_MAX
from worldtrack.trackers.particle.likelihood.reading import ReadAs
from worldtrack.trackers.particle.likelihood.sums import Sums, add_camera, close_sums
from worldtrack.trackers.particle.likelihood.top_edge import edge_spec, top_edge_offsets

if TYPE_CHECKING:
    from worldtrack.trackers.particle.config import ParticleConfig

#: No colour term (an empty penalty array for :func:`~.sums.add_camera`).
_NO_PENALTY = np.zeros(0)


@dataclass
class FrameView:
    """One frame as the likelihood reads it, per camera id.

    Attributes
    ----------
    images : {camera: (H, W)} — what the likelihood reads (:meth:`Likelihood.image`)
    owners : {camera: (H, W) uint8} or None — the objects' boxes per pixel (explaining away)
    boxes : {camera: F boxes} or None — each filter's own box among them (None: no own box)
    occluders : {camera: Occluders} or None — the same boxes by depth
    colour : {camera: (H, W, 3) uint8} — the BGR frames, for the colour term (empty: none)
    """

    images: Mapping[str, np.ndarray]
    owners: Mapping[str, np.ndarray] | None = None
    boxes: Mapping[str, Sequence] | None = None
    occluders: Mapping[str, Occluders] | None = None
    colour: Mapping[str, np.ndarray] = field(default_factory=dict)


@dataclass
class Readers:
    """Whose particles are read: N particles of F filters.

    Attributes
    ----------
    which : (N,) int — each particle's filter, 0 … F − 1
    mes : (F,) int — each filter's index among the boxes of :class:`FrameView`
    colours : F {camera: ColourModel} (or None) — each filter's colours, or None for none
    px_scale : {camera: (F,) float} or None — pixel-weight scales (None: the camera's default)
    k_lo : {camera: (F,) int} or None — lowest samples read as no evidence (None: none)
    """

    which: np.ndarray
    mes: Sequence[int]
    colours: Sequence[Mapping | None] | None = None
    px_scale: Mapping[str, np.ndarray] | None = None
    k_lo: Mapping[str, np.ndarray] | None = None

    @staticmethod
    def one(n: int, colours: Mapping | None = None) -> "Readers":
        """N particles of one filter that has no box of its own."""
        return Readers(np.zeros(n, dtype=np.int64), [-1], [colours])


class Likelihood(Protocol):
    """The likelihood of particles, summed over the cameras that see them."""

    #: what it reads: the labels (column) or the background difference (point)
    reads_difference: bool
    #: the column likelihoods: each particle's z is drawn below its column's top after resampling,
    #: the region's height is its column's, the lowest hidden samples are reported
    column: bool
    #: the column ratio: ring samples, pixel weights, the height prior, a region as wide as the person
    ratio: bool
    #: (S,) metres: the column's sample heights, ring samples included
    samples: np.ndarray
    #: metres: σ of the prior of a column's top about the particle's height (0: the heights are no state)
    top_sigma: float

    def image(self, labels: np.ndarray, difference: np.ndarray | None) -> np.ndarray:
        """(H, W) what it reads of a camera's frame, from the labels and the difference F."""
        ...

    def __call__(self, xyz: np.ndarray, h: np.ndarray | None, frame: FrameView, readers: Readers,
                 hidden: dict | None = None, top_edge: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(logpi, likely, col_h) of particles ``xyz`` (N, 3) m with object heights ``h`` (N,) m: the log
        likelihood up to a constant (−inf where no camera sees the particle or it is off the floor),
        whether it sees enough object in every camera that sees it, and its column height (m; 0 for the
        point). ``hidden`` is filled with {camera: (N,) hidden samples}; ``top_edge`` adds the top edge."""
        ...


#: Likelihoods by the name ``particle.likelihood.model`` gives.
LIKELIHOODS: Registry[type] = Registry("particle.likelihood.model")

#: Depth (m) at which a column sample weighs 1 with ``pixel_weights="depth"``: weights are the
#: sample's image length over that of a sample this far from the camera.
REFERENCE_DEPTH = 5.0


class _Common:
    """What every likelihood holds: the cameras, the walkable floor, the settings."""

    reads_difference = False
    column = True
    ratio = False

    def __init__(self, cfg: "ParticleConfig", cameras: Mapping[str, CameraLikelihood], walkable: WalkableRaster):
        lk, col = cfg.likelihood, cfg.column
        self.cameras, self.raster, self.blocks = cameras, walkable, raster_blocks(walkable)
        self.max_height = col.max_height_m
        self.likely_count, self.dz = col.likely_count, col.dz_m
        self.surface_offset, self.colour_weight = col.surface_offset_m, cfg.appearance.weight
        self.margin = cfg.explain.occlusion_margin_m
        a, b = lk.hit_rate_object, lk.hit_rate_background
        self.on, self.off = math.log(a / b), math.log((1 - a) / (1 - b))
        self.heights = column_heights(col.max_height_m, col.dz_m)
        n_below, n_above = (col.foot_samples, col.head_samples) if self.ratio else (0, 0)
        self.samples = np.concatenate([-col.dz_m * np.arange(n_below, 0, -1), self.heights,
                                       self.heights[-1] + col.dz_m * np.arange(1, n_above + 1)])
        k_min = n_below + min(self.likely_count, len(self.heights) - 1)
        self.top_sigma = cfg.height.prior_sigma_m if self.ratio else 0.0
        self.spec = column_spec(self.samples, self.on, self.off, k_min, col.radius_m, -self.on, n_below, n_above,
                                self.top_sigma, lk.out_of_view == "unknown")
        depth = self.ratio and lk.pixel_weights == "depth"
        # Pixel weights relative to a sample REFERENCE_DEPTH from a camera (0: unweighted).
        self.default_scale = {cid: REFERENCE_DEPTH / (cl.K[1, 1] * col.dz_m) if depth else 0.0
                              for cid, cl in cameras.items()}

    def image(self, labels: np.ndarray, difference: np.ndarray | None) -> np.ndarray:
        return labels

    def _read(self, cid: str, frame: FrameView, readers: Readers) -> ReadAs:
        """How ``readers`` read camera ``cid``'s image of ``frame``."""
        owner = frame.owners.get(cid) if frame.owners is not None else None
        box = frame.boxes.get(cid) if frame.boxes is not None else [None] * len(readers.mes)
        return ReadAs(owner, box, readers.mes, readers.which,
                      frame.occluders.get(cid) if frame.occluders is not None else None, self.margin,
                      self.default_scale[cid] if readers.px_scale is None else readers.px_scale[cid],
                      readers.k_lo[cid] if readers.k_lo is not None else 0)

    def near_surface(self, xy: np.ndarray, cl: CameraLikelihood) -> np.ndarray:
        """Where camera ``cl``'s column stands for particles at ``xy`` (N, ≥ 2): ``surface_offset``
        nearer to it."""
        return xy[:, :2] if self.surface_offset <= 0 else cl.near_surface(xy, self.surface_offset)


@LIKELIHOODS.register("column-ratio")
class ColumnRatio(_Common):
    """The likelihood ratio of the best object top (worldtrack's), one compiled call per camera."""

    ratio = True

    def __init__(self, cfg: "ParticleConfig", cameras: Mapping[str, CameraLikelihood], walkable: WalkableRaster):
        super().__init__(cfg, cameras, walkable)
        h = cfg.height
        self.edge = (edge_spec(top_edge_offsets(h.edge_step_m, h.edge_samples), h.edge_weight, self.on, self.off)
                     if self.top_sigma > 0 and h.edge_weight > 0 else None)
        self.edge_explain = h.edge_explain

    def __call__(self, xyz, h, frame, readers, hidden=None, top_edge=False):
        n = len(xyz)
        sums = Sums.start(n)
        spec = self.spec if h is not None else self.spec._replace(top_sigma=0.0)
        colours = readers.colours if readers.colours is not None else [None] * len(readers.mes)
        for cid, img in frame.images.items():
            cl = self.cameras[cid]
            hid = np.empty(n, dtype=np.int32)
            image = frame.colour.get(cid)
            reading = cl.reading(img, n, self._read(cid, frame, readers), h)
            observe_column(cl, xyz, self.surface_offset, spec, reading, img, image,
                           [c.get(cid) if c else None for c in colours] if image is not None else (),
                           self.colour_weight, self.likely_count, sums, hid)
            if hidden is not None:
                hidden[cid] = hid
            if top_edge and h is not None and self.edge is not None:
                # Raw labels unless edge_explain: no boxes, so codes are the labels themselves.
                cl.top_edge(reading if self.edge_explain else cl.reading(img, n), xyz, h, self.edge, sums.logpi)
        # −inf, not likely off the walkable floor or where no camera sees; col over the cameras that see
        close_sums(sums.n_seen, xyz, self.raster, sums.logpi, sums.likely, sums.col, self.blocks)
        return sums.logpi, sums.likely, sums.col


@LIKELIHOODS.register("column-count")
class ColumnCount(_Common):
    """Eq. 11: ``π ∝`` the column's samples on ``F > γ`` (as a share of its T + 1 samples)."""

    def __call__(self, xyz, h, frame, readers, hidden=None, top_edge=False):
        n = len(xyz)
        sums = Sums.start(n)
        colours = readers.colours if readers.colours is not None else [None] * len(readers.mes)
        S = len(self.heights)
        with np.errstate(divide="ignore"):
            for cid, img in frame.images.items():
                cl = self.cameras[cid]
                surface = self.near_surface(xyz, cl)
                counts, _, _, seen, hid = cl.column(img, surface, self.spec, self._read(cid, frame, readers), h)
                if hidden is not None:
                    hidden[cid] = hid
                penalty = _NO_PENALTY
                if cid in frame.colour:
                    # Each particle's colour column under its filter's model (0 where nothing is learnt).
                    models = [c.get(cid) if c else None for c in colours]
                    penalty = column_penalties(cl, frame.colour[cid], img, surface, models, readers.which)
                add_camera(seen, np.log(counts / S), penalty, float(self.colour_weight), counts * self.dz,
                           counts >= self.likely_count, *sums)
        close_sums(sums.n_seen, xyz, self.raster, sums.logpi, sums.likely, sums.col, self.blocks)
        return sums.logpi, sums.likely, sums.col


@LIKELIHOODS.register("point")
class Point(_Common):
    """Eq. 7: ``π = F(u, v)`` at the particle's own point where the foreground says object (0 elsewhere:
    F ≤ γ, γ being the foreground's threshold), over ``F_MAX``."""

    reads_difference = True
    column = False

    def image(self, labels: np.ndarray, difference: np.ndarray | None) -> np.ndarray:
        return object_difference(labels, difference)

    def __call__(self, xyz, h, frame, readers, hidden=None, top_edge=False):
        n = len(xyz)
        sums = Sums.start(n)
        with np.errstate(divide="ignore"):
            for cid, img in frame.images.items():
                read = self._read(cid, frame, readers)
                values, seen = self.cameras[cid].point(img, xyz, read.owner, read.box, readers.which)
                add_camera(seen, np.log(values / F_MAX), _NO_PENALTY, float(self.colour_weight), np.zeros(n),
                           values > 0, *sums)
        logpi, likely, n_seen, col = sums
        valid = (n_seen > 0) & raster_contains(self.raster, xyz, self.blocks)
        valid &= (xyz[:, 2] >= 0) & (xyz[:, 2] <= self.max_height)
        return np.where(valid, logpi, -np.inf), likely & valid, col / np.maximum(n_seen, 1)


def object_difference(labels: np.ndarray, difference: np.ndarray) -> np.ndarray:
    """(H, W) float32, C-contiguous: the background difference F where ``labels`` say object, 0 elsewhere
    (what the point likelihood reads)."""
    return np.ascontiguousarray(np.where(labels == 1, np.asarray(difference, dtype=np.float32), np.float32(0.0)))


__all__ = ["LIKELIHOODS", "REFERENCE_DEPTH", "object_difference", "ColumnCount", "ColumnRatio", "FrameView", "Likelihood", "Point",
           "Readers"]

