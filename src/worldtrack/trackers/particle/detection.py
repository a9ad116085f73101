"""Detection filters (seed 004, §3.2): particle filters over where new objects appear.

Particles are scattered uniformly over each entry region (in a scene without entry regions, over the
walkable floor in view). A detection filter is a particle filter too and concentrates on what enters:
each frame it is resampled by last frame's weights, jittered, and a share scattered afresh; when the
share of its *likely* particles exceeds α it fires — the tracker starts tracking filters from them —
and is scattered afresh.

Beyond the paper (``particle.detection``): an entry region covers the walkable floor near it
(``entry_margin_m``; people show fully near a door, not in it); a door partly or wholly out of view is
watched where its floor comes into view (``entry_reach_m``); and with ``births="entry+lost"`` a
detection filter watches, for ``lost_hold_s``, the floor round where a tracking filter ended by the β
rule, so an object that stopped showing enough is found again, under its old id, when it shows.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Callable, Mapping, Sequence

import numpy as np
from scipy.spatial import cKDTree

from worldtrack.errors import InputError
from worldtrack.scene.model import Scene
from worldtrack.trackers.particle.cloud import Cloud
from worldtrack.trackers.particle.floor import FloorRegion, polygon_distance
from worldtrack.trackers.particle.likelihood.camera import CameraLikelihood
from worldtrack.trackers.particle.motion import HeightState
from worldtrack.trackers.particle.resample import Resampler, particle_weights

if TYPE_CHECKING:
    from worldtrack.trackers.base import Person
    from worldtrack.trackers.particle.config import ParticleConfig


class Detection:
    """The detection filters of a tracker and the floor they watch.

    Parameters
    ----------
    cfg : ParticleConfig; scene : Scene; cameras : {camera_id: CameraLikelihood}
    rng : numpy.random.Generator — the tracker's
    heights : HeightState — draws and walks the particles' object heights
    resample : Resampler — the tracker's resampling

    Attributes
    ----------
    births : str — where detection filters scatter (``auto`` resolved)
    detectors : list of Cloud
    """

    def __init__(self, cfg: "ParticleConfig", scene: Scene, cameras: Mapping[str, CameraLikelihood],
                 rng: np.random.Generator, heights: HeightState, resample: Resampler):
        d = cfg.detection
        self.cfg, self.scene, self.cameras, self.rng = d, scene, cameras, rng
        self.heights, self.resample, self.power = heights, resample, cfg.weights.power
        self.min_height, self.max_height = cfg.column.min_height_m, cfg.column.max_height_m
        self.births = d.births if d.births != "auto" else ("entry+lost" if scene.entry_regions else "anywhere")
        self.watches_lost = self.births == "entry+lost" and d.lost_radius_m > 0 and d.lost_hold_s > 0
        self.detectors = [Cloud(np.zeros((0, 3)), np.zeros((0, 3)), region=r, h=np.zeros(0))
                          for r in self._regions()]

    # ------------------------------------------------------------------ where
    def in_view(self, xy: np.ndarray) -> np.ndarray:
        """(N,) bool: floor points ``xy`` (N, 2), metres, are walkable and a column of ``min_height``
        there is inside some camera's image."""
        xy = np.asarray(xy, dtype=float).reshape(-1, 2)
        seen = np.zeros(len(xy), dtype=bool)
        for cl in self.cameras.values():
            seen |= cl.camera.sees_standing(xy, self.min_height)
        return self.scene.walkable.contains(xy) & seen

    def _regions(self) -> list[FloorRegion]:
        """Where detection filters scatter: entry regions grown by ``entry_margin``, or all floor; in view."""
        scene, births = self.scene, self.births
        if births == "none":
            return []
        if births == "anywhere":
            reg = FloorRegion.rasterise("walkable", scene.walkable.bounds, 0.05, self.in_view)
            if reg.empty:
                raise InputError(f"particle tracker: no walkable floor of scene {scene.name!r} is in view of "
                                 f"{', '.join(self.cameras)}")
            return [reg]
        if not scene.entry_regions:
            raise InputError(f"particle tracker: births={births!r} but scene {scene.name!r} has no entry regions")
        regions = []
        m = self.cfg.entry_margin_m
        for er in scene.entry_regions:
            p = er.polygon
            near = self._unseen_near(p)
            bounds = _grown_bounds(p, m + (self.cfg.entry_reach_m if near is not None else 0.0))

            def test(xy: np.ndarray, p: np.ndarray = p, near: "cKDTree | None" = near) -> np.ndarray:
                close = polygon_distance(xy, p) <= m
                if near is not None:                 # where the door's floor comes into view
                    close |= np.isfinite(near.query(xy, distance_upper_bound=m + 1e-9)[0])
                return close & self.in_view(xy)

            reg = FloorRegion.rasterise(er.name, bounds, 0.02, test)
            if not reg.empty:
                regions.append(reg)
        if not regions:
            raise InputError(f"particle tracker: no entry region of scene {scene.name!r} is in view of "
                             f"{', '.join(self.cameras)} (use births='anywhere')")
        return regions

    def _unseen_near(self, polygon: np.ndarray, cell: float = 0.05) -> "cKDTree | None":
        """The walkable floor out of every view within ``entry_reach`` of an entry region's ``polygon``
        (a grid of ``cell`` m), as a KD-tree of cell centres; None if there is none or the reach is 0."""
        reach = self.cfg.entry_reach_m
        if reach <= 0:
            return None
        p = polygon
        unseen = FloorRegion.rasterise("unseen", _grown_bounds(p, reach), cell,
                                       lambda xy: (polygon_distance(xy, p) <= reach)
                                       & self.scene.walkable.contains(xy) & ~self.in_view(xy))
        if unseen.empty:
            return None
        j, i = np.nonzero(unseen.raster.inside)
        return cKDTree(unseen.origin + (np.column_stack([i, j]) + 0.5) * cell)

    # ------------------------------------------------------------------ each frame
    def expire(self, t: float) -> None:
        """Drop the lost tracks' watches whose time is over at ``t`` (s)."""
        self.detectors = [d for d in self.detectors if d.until is None or t <= d.until]

    def move(self, dt: float) -> None:
        """Resample each detection filter by last frame's weights, jitter, and scatter a share afresh."""
        n = self.cfg.particles
        for d in self.detectors:
            if d.logw is None:
                d.xyz, d.v, d.h = self._scatter(d.region, n), np.zeros((n, 3)), self.heights.draw(n)
                continue
            keep = self.resample(particle_weights(d.logw, self.power), n, self.rng)
            d.xyz, d.h = d.xyz[keep], d.h[keep]
            d.xyz[:, :2] += self.rng.standard_normal((n, 2)) * (self.cfg.noise * math.sqrt(max(dt, 0.0)))
            d.h = self.heights.walk(d.h, dt)
            fresh = (self.rng.random(n) < self.cfg.reseed) | ~d.region.contains(d.xyz[:, :2])
            k = int(fresh.sum())
            if k:
                d.xyz[fresh] = self._scatter(d.region, k)
                d.h[fresh] = self.heights.draw(k)

    def _scatter(self, region: FloorRegion, n: int) -> np.ndarray:
        """(n, 3) particles uniform over the region's floor and over heights [0, max_height]."""
        return np.column_stack([region.sample(n, self.rng), self.rng.random(n) * self.max_height])

    def update(self, t: float, fire: Callable[[Cloud, float], None]) -> None:
        """Each detection filter whose share of likely particles exceeds α fires (``fire(d, t)``) and is
        scattered afresh; the others keep their weights for next frame."""
        for d in self.detectors:
            share = float(d.likely.mean()) if len(d.likely) else 0.0
            if share > self.cfg.alpha:
                fire(d, t)
                d.logw = None
                if d.until is not None:          # a lost track's watch: found, dropped next frame
                    d.until = -math.inf
                continue
            d.logw = d.logpi if np.isfinite(d.logpi).any() else None

    def watch_lost(self, persons: Sequence["Person"], t: float) -> None:
        """``births="entry+lost"``: watch where each of ``persons`` (ended by the β rule at ``t``, s) was
        last, unless an entry region's detection filter covers that place already: a detection filter
        over the floor in view within ``lost_radius_m`` of it, kept for ``lost_hold_s`` or until it
        starts a track."""
        c = self.cfg
        if not self.watches_lost or not persons:
            return
        xy = np.array([[p.x, p.y] for p in persons], dtype=float)
        covered = np.zeros(len(xy), dtype=bool)
        for d in self.detectors:
            if d.until is None:
                covered |= d.region.contains(xy)
        r = c.lost_radius_m
        for k in np.flatnonzero(~covered):
            at = xy[k]
            reg = FloorRegion.rasterise(f"lost {persons[k].id}", (at[0] - r, at[0] + r, at[1] - r, at[1] + r), 0.05,
                                        lambda q, at=at: (np.hypot(q[:, 0] - at[0], q[:, 1] - at[1]) <= r)
                                        & self.in_view(q))
            if not reg.empty:
                self.detectors.append(Cloud(np.zeros((0, 3)), np.zeros((0, 3)), region=reg, h=np.zeros(0),
                                            until=t + c.lost_hold_s, lost_id=persons[k].id))


def _grown_bounds(polygon: np.ndarray, margin: float) -> tuple[float, float, float, float]:
    """(x0, x1, y0, y1) metres: the bounding box of ``polygon`` (N, 2) grown by ``margin`` on each side."""
    (x0, y0), (x1, y1) = polygon.min(axis=0), polygon.max(axis=0)
    return (x0 - margin, x1 + margin, y0 - margin, y1 + margin)


__all__ = ["Detection"]
