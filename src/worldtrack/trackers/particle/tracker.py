"""The particle tracker (seed 004): one 3-D particle filter per object, detection filters for new ones.

Every frame each tracking filter

1. **predicts** its particles (eqs. 1–2 in real time, :mod:`.motion`);
2. **observes** the likelihood π_i of each particle (:mod:`.likelihood`: the height column of eq. 11
   or the point of eq. 7, multiplied over the cameras that see it; 0 off the walkable floor or out
   of every view) — all tracking filters in one call (:mod:`.observe`), reading past the other
   tracks' boxes (:mod:`.explain`);
3. is **weighed and resampled** (eq. 8, :mod:`.resample`), and ends by the β rule (:mod:`.life`);
4. reports the **object region** (eqs. 9–10, :mod:`.region`) on its person in the position map.

Then filters on two objects are split (:mod:`.split`), two filters on one object merged
(:mod:`.merge`), and the detection filters (§3.2, :mod:`.detection`) start tracking filters for new
objects. The variants a configuration names (motion model, likelihood, resampler, pixel weights)
are components chosen once, here, at construction.

Per-person state lives on the :class:`~worldtrack.trackers.base.Person` in the position map; the
tracker keeps only the method's working representation, one :class:`~.cloud.Cloud` per person id. A
person on a shared map that another tracker started is given a cloud here, seeded from the map.
"""

from __future__ import annotations

import math
from typing import Mapping

import numpy as np

from worldtrack.errors import InputError
from worldtrack.scene.model import Scene
from worldtrack.trackers.base import Frame, Overlay, Person, PositionMap, Track, TrackerBase
from worldtrack.trackers.particle.appearance import ColourLearning
from worldtrack.trackers.particle.cloud import PARTICLE_FIELDS, Cloud, CloudStack
from worldtrack.trackers.particle.config import ParticleConfig
from worldtrack.trackers.particle.detection import Detection
from worldtrack.trackers.particle.explain import Explainer
from worldtrack.trackers.particle.life import Life, seen_elsewhere
from worldtrack.trackers.particle.likelihood.camera import CameraLikelihood
from worldtrack.trackers.particle.likelihood.labels import FrameLabels
from worldtrack.trackers.particle.likelihood.models import LIKELIHOODS
from worldtrack.trackers.particle.merge import Merger
from worldtrack.trackers.particle.motion import MOTIONS, HeightState
from worldtrack.trackers.particle.observe import Observer
from worldtrack.trackers.particle.region import Regions
from worldtrack.trackers.particle.resample import RESAMPLERS, Resampling
from worldtrack.trackers.particle.split import Splitter


class ParticleTracker(TrackerBase):
    """Multi-object tracker: one 3-D particle filter per object, detection filters for new ones.

    Parameters
    ----------
    scene : Scene
    foregrounds : {camera_id: foreground model}
        Each needs ``difference(image) -> (H, W) float`` (the Euclidean RGB distance F), e.g.
        :class:`~worldtrack.foreground.background.StaticBackground`; unless
        ``likelihood.shadows="object"`` also a background image (``.background``, or
        ``.model.getBackgroundImage()``).
    config : ParticleConfig, optional
    position_map : PositionMap, optional — share one between trackers (each with its own cameras)
    rng : numpy.random.Generator, optional — default ``default_rng(config.seed)``

    Attributes
    ----------
    clouds : {person_id: Cloud} — the tracking filters; ``detection.detectors`` the detection filters
    extra_columns : tuple of str — the columns ``tracks.csv`` gets besides the standard ones
    """

    extra_columns = ("sigma", "z", "sx", "sy", "sz")

    def __init__(self, scene: Scene, foregrounds: Mapping[str, object], config: ParticleConfig | None = None,
                 position_map: PositionMap | None = None, rng: np.random.Generator | None = None):
        if config is not None and not isinstance(config, ParticleConfig):
            raise InputError(f"particle tracker: expected a ParticleConfig, got {type(config).__name__}")
        self.scene, self.config = scene, config or ParticleConfig()
        cfg = self.config
        self.position_map = position_map if position_map is not None else PositionMap()
        self.rng = rng if rng is not None else np.random.default_rng(cfg.seed)
        if not foregrounds:
            raise InputError("particle tracker: expected at least one camera with a foreground model")
        self.cameras = {cid: CameraLikelihood(scene.camera(cid)) for cid in foregrounds}
        self._mine = frozenset(self.cameras)
        walkable = scene.walkable.raster(0.01)
        self.likelihood = LIKELIHOODS[cfg.likelihood.model](cfg, self.cameras, walkable)
        lk = self.likelihood
        self.labels = FrameLabels(scene, foregrounds, cfg.likelihood.shadows, lk,
                                  colour=cfg.appearance.weight > 0)
        self.stack = CloudStack()
        self.heights = HeightState(cfg, scene.people.height, lk.top_sigma > 0, self.rng)
        self.motion = MOTIONS[cfg.motion.model](cfg, self.rng, self.stack, self.heights, not lk.column,
                                                len(lk.samples))
        self.resampling = Resampling(RESAMPLERS[cfg.weights.resampler], cfg.weights.power, self.rng, lk.column)
        self.regions = Regions(self.stack, self.motion,
                               ("h" if lk.top_sigma > 0 else "col_h") if lk.column else None, lk.ratio)
        self.observer = Observer(cfg, lk, self.stack)
        self.explainer = Explainer(cfg, self.cameras)
        self.life = Life(cfg, scene, walkable)
        self.colours = ColourLearning(cfg, self.cameras) if cfg.appearance.weight > 0 else None
        self.splitter = Splitter(cfg, (scene.people.height, scene.people.width), self.cameras)
        self.merger = Merger(cfg, self.cameras) if cfg.merge.enabled else None
        self.detection = Detection(cfg, scene, self.cameras, self.rng, self.heights, self.resampling.resample)
        self.clouds: dict[int, Cloud] = {}
        self._last_t: float | None = None

    # ------------------------------------------------------------------ the Tracker protocol
    def init_track(self, x: float, y: float, track_id: int | None = None, t: float = 0.0, *,
                   spread: float = 0.1) -> Track:
        """Start a tracking filter at floor position ``(x, y)`` (m), particles spread ``spread`` (m, 1-σ),
        as person ``track_id`` (default: the next id) seen at time ``t`` (s)."""
        if track_id is not None and track_id in self.position_map:
            raise InputError(f"--init: track id {track_id} is taken already")
        n = self.config.tracking.particles
        xyz = np.column_stack([x + spread * self.rng.standard_normal(n), y + spread * self.rng.standard_normal(n),
                               self.rng.random(n) * self.config.column.max_height_m])
        h, w = self.scene.people.size_of(track_id or 0)
        p = self.position_map.add(x, y, h, w, mode="tracking", time=t, track_id=track_id)
        c = Cloud(xyz, self.motion.velocities(n), person=p.id, h=self.heights.draw(n, h))
        self.regions.update([c], [p], t)
        self.clouds[p.id] = c
        return p.track()

    def overlay(self, camera_id: str) -> Overlay:
        """This frame's labels of ``camera_id`` (1 object, 2 no evidence) as the overlay's mask."""
        return Overlay(mask=self.labels.masks.get(camera_id))

    @property
    def last_masks(self) -> dict[str, np.ndarray]:
        """{camera_id: (H, W) uint8} this frame's labels."""
        return self.labels.masks

    @property
    def tracks(self) -> list[Track]:
        """The confirmed people's tracks, in id order."""
        return sorted(self.position_map.tracks(), key=lambda tr: tr.id)

    def step(self, frames: Mapping[str, Frame], t: float) -> list[Track]:
        """Update every filter with one synchronised bundle of frames taken at time ``t``.

        Parameters
        ----------
        frames : {camera_id: Frame or (H, W, 3) uint8 BGR image}
        t : float, seconds — must not decrease from call to call

        Returns
        -------
        list of Track — the confirmed people, ids from 1 (never the detection filters)
        """
        t = float(t)
        if not math.isfinite(t):
            raise InputError(f"particle tracker: time stamp must be a finite number of seconds, got {t}")
        if self._last_t is not None and t < self._last_t:
            raise InputError(f"particle tracker: time went backwards ({t} s after {self._last_t} s)")
        dt = 0.0 if self._last_t is None else t - self._last_t
        self.position_map.advance(t)
        self._follow_map(t)
        self.life.expire(t)
        self.detection.expire(t)
        frame = self.labels.read(frames)
        self._last_t = t
        if not frame.images:
            return self.tracks
        clouds = list(self.clouds.values())
        if clouds:
            persons = self._persons(clouds)
            self.motion.predict(clouds, persons, dt)
            view, centres = self.explainer.tracking(frame, clouds, persons, self.stack)
            self.observer.tracking(clouds, view, centres)
            self._update_tracking(clouds, persons, t)
        if self.colours is not None:
            clouds = list(self.clouds.values())
            self.colours.learn(clouds, self._persons(clouds), frame.images, frame.colour)
        # Splits and merges first, so a filter that just split into two objects hides both of them
        # from the detection filters below (otherwise the second object is also "detected").
        if self.config.split.enabled:
            self._split(t, dt)
        if self.merger is not None:
            self.merger.merge(list(self.clouds.values()), self.position_map, dt, self._end)
        if self.detection.detectors:
            self._detect(frame, t, dt)
        return self.tracks

    # ------------------------------------------------------------------ tracking filters
    def _persons(self, clouds: list[Cloud]) -> list[Person]:
        return [self.position_map[c.person] for c in clouds]

    def _update_tracking(self, clouds: list[Cloud], persons: list[Person], t: float) -> None:
        """Share of likely particles (end at ≤ β), weights (eq. 8), resampling and object region of the
        tracking filters ``clouds`` (equal particle counts), at once."""
        stack = self.stack
        parts = {name: stack.stacked(clouds, name) for name in PARTICLE_FIELDS if getattr(clouds[0], name) is not None}
        # The share of likely particles (a count over N: the mean of the booleans, exactly).
        shares = (parts["likely"].sum(axis=1) / parts["likely"].shape[1]).tolist()
        resampled = self.resampling.parts(parts, self.resampling.weights(parts["logpi"]),
                                          self.config.tracking.particles)
        verdicts = self.life.judge(persons, shares, t, self._mine)
        kept = [v.kept for v in verdicts]
        lost = [p for p, k in zip(persons, kept) if not k]
        for p in lost:
            self._end(p)
        if all(kept):
            for name, a in resampled.items():
                stack.set_rows(clouds, name, a)
        else:
            for name, a in resampled.items():
                for i in np.flatnonzero(kept).tolist():
                    setattr(clouds[i], name, a[i])
        self.detection.watch_lost(lost, t)
        mine = [(c, p) for c, p, v in zip(clouds, persons, verdicts) if v.here]
        if mine:
            self.regions.update([c for c, _ in mine], [p for _, p in mine], t)
        self._mark_seen([p for p, v in zip(persons, verdicts) if v.seen], t)
        for (_, p), leaving in zip(mine, self.life.leaving([p for _, p in mine])):
            if leaving:
                self.life.exit(p, t)
                self._end(p)

    def _mark_seen(self, persons: list[Person], t: float) -> None:
        """``persons`` (whose evidence this frame was good) are seen at ``t`` by this tracker's cameras
        whose image holds their box (by all of them, if none does)."""
        if not persons:
            return
        xy = np.array([[p.x, p.y] for p in persons])
        widths, heights = [p.width for p in persons], [p.height for p in persons]
        shown = {cid: cl.box_array(xy, widths, heights, 0.0)[:, 0] >= 0 for cid, cl in self.cameras.items()}
        for k, p in enumerate(persons):
            p.mark_seen(t, [cid for cid, s in shown.items() if s[k]] or list(self.cameras))

    def _split(self, t: float, dt: float) -> None:
        """Split each tracking filter whose particles have been two lumps long enough into two tracks."""
        clouds = list(self.clouds.values())
        n = self.config.tracking.particles
        for c, side in self.splitter.due(clouds, self._persons(clouds), self.stack, t, dt):
            p = self.position_map[c.person]
            keep, other = (~side, side) if (~side).sum() >= side.sum() else (side, ~side)
            new = c.subset(other, centre=c.centre.copy(), t_update=c.t_update)
            c.take(np.flatnonzero(keep))
            for g in (c, new):
                self.resampling.cloud(g, np.ones(len(g.xyz)), n)
            self.regions.update([c], [p], t)
            self._start(new, t, p.score, velocity=(p.vx, p.vy))

    def _start(self, c: Cloud, t: float, score: float, track_id: int | None = None,
               velocity: tuple[float, float] = (0.0, 0.0)) -> Person:
        """Put a new person on the map for cloud ``c`` (at its particles' mean), with its region."""
        m = c.xyz.mean(axis=0)
        p = self.position_map.add(m[0], m[1], mode="tracking", time=t, track_id=track_id)
        p.height, p.width = self.scene.people.size_of(p.id)
        p.score, (p.vx, p.vy) = score, velocity
        c.person = p.id
        self.regions.update([c], [p], t)
        self.clouds[p.id] = c
        return p

    def _end(self, p: Person) -> None:
        """End person ``p``: their cloud is dropped and they leave the map."""
        self.clouds.pop(p.id, None)
        if p.id in self.position_map and self.position_map[p.id] is p:
            self.position_map.remove(p.id)

    # ------------------------------------------------------------------ detection filters
    def _detect(self, frame, t: float, dt: float) -> None:
        """Move, observe and update the detection filters; those that fire start tracks."""
        # They read past every track's box at the updated positions (stretched along the line of
        # sight), and past the last boxes of objects that just left through an exit.
        clouds = list(self.clouds.values())
        persons = self._persons(clouds) + [e.person for e in self.life.exited]
        xy = [c.centre for c in clouds] + [np.array([e.person.x, e.person.y]) for e in self.life.exited]
        view = self.explainer.detection(frame, xy, persons)
        self.detection.move(dt)
        self.observer.detection(self.detection.detectors, view)
        self.detection.update(t, self._fire)

    def _fire(self, d: Cloud, t: float) -> None:
        """Start tracking filters from a detection filter's likely particles, one per lump."""
        cfg = self.config
        idx = np.flatnonzero(d.likely)
        lumps = self.splitter.lumps(d.xyz, idx, depth=2) if cfg.split.enabled else [idx]
        # A lost track's watch (``lost_same_id``): its biggest lump is that object found again.
        same = (d.lost_id if cfg.detection.lost_same_id and d.lost_id is not None
                and d.lost_id not in self.position_map else None)
        big = max(range(len(lumps)), key=lambda i: len(lumps[i]))
        for i, g in enumerate(lumps):
            c = d.subset(g, v=self.motion.velocities(len(g)))
            self.resampling.cloud(c, self.resampling.weights(c.logpi), cfg.tracking.particles)
            self._start(c, t, float(d.likely.mean()), track_id=same if i == big else None)

    # ------------------------------------------------------------------ sharing the map
    def _follow_map(self, t: float) -> None:
        """Clouds for the map's people: drop those whose person left the map; seed one (from the person's
        place, spread, height and velocity) for each confirmed person that has none, and afresh for
        each that another tracker sees while this one has not updated them since the last time stamp."""
        for pid in [pid for pid in self.clouds if pid not in self.position_map]:
            del self.clouds[pid]
        for p in self.position_map:
            c = self.clouds.get(p.id)
            if not p.confirmed:
                continue
            if c is None or (seen_elsewhere(p, self._mine) and (c.t_update is None or c.t_update < p.prev_t)):
                self.clouds[p.id] = self._seeded(p)

    def _seeded(self, p: Person) -> Cloud:
        """A tracking filter about person ``p`` as the map has them."""
        n = self.config.tracking.particles
        spread = max(p.sigma, 0.05)
        xyz = np.column_stack([p.x + spread * self.rng.standard_normal(n), p.y + spread * self.rng.standard_normal(n),
                               self.rng.random(n) * self.config.column.max_height_m])
        v = self.motion.velocities(n)
        v[:, :2] += (p.vx, p.vy)
        # No region of its own yet (t_update None): seeded afresh each frame until this tracker sees them.
        return Cloud(xyz, v, person=p.id, centre=np.array([p.x, p.y]), h=self.heights.draw(n, p.height))


__all__ = ["ParticleConfig", "ParticleTracker"]
