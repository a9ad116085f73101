"""The ellipsoid tracker: each frame, the paper's steps in order, on the shared position map.

One :meth:`EllipsoidTracker.step`:

1. read each camera's foreground into the ternary real image (:mod:`.real`);
2. predict tracked people at constant velocity (``match.predict``);
3. match: a just-proposed person is placed by the birth search (:mod:`.search`), then everybody
   is moved in turn to the best of 9 candidates, K rounds (:mod:`.match`, eq. 5 in
   :mod:`.score`), and failing tracks are rescued along their lines of sight (:mod:`.search`);
   with ``cross_view.search_m`` > 0, a tracked person some camera does not show is searched along
   the other cameras' lines of sight for where it does (:mod:`.cross_view`);
4. propose new people from unexplained foreground (:mod:`.births`) and match them;
   with ``depth.fuse``, place people one camera alone shows along its line of sight from every
   cue (:mod:`.depth`);
5. measure each person's support (:mod:`.support`), then confirm, follow or end them
   (:mod:`.life`), flag the unmeasurable, measure heights (:mod:`.height`), end duplicates;
6. measure each person's position uncertainty σ, filter their velocity and say their state (:mod:`.uncertainty`).

Everything needed to continue a person is on the :class:`~worldtrack.trackers.base.Person` in the map, so
several trackers, each with its own cameras, can share one map: each moves and judges the people its cameras
show and the people no camera on the map shows, and leaves the others (whom another tracker's cameras show)
to that tracker; per-frame counters and the prediction advance once per time stamp whichever tracker steps first.
"""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from worldtrack.errors import InputError
from worldtrack.foreground.background import Foreground
from worldtrack.scene.model import Scene
from worldtrack.trackers.base import Frame, Overlay, Person, PositionMap, Track, TrackerBase, frame_image
from worldtrack.trackers.ellipsoid.args import DrawArgs, People, Scoring, StepArgs, Walkable
from worldtrack.trackers.ellipsoid.births import Births
from worldtrack.trackers.ellipsoid.cameras import CameraView, camera_view
from worldtrack.trackers.ellipsoid.coast import behind_obstacles
from worldtrack.trackers.ellipsoid.config import EllipsoidConfig
from worldtrack.trackers.ellipsoid.depth import DepthFusion
from worldtrack.trackers.ellipsoid.feet import anchor_to_feet
from worldtrack.trackers.ellipsoid.height import update_heights
from worldtrack.trackers.ellipsoid.height_gate import heights_due_clear
from worldtrack.trackers.ellipsoid.identity import Identities
from worldtrack.trackers.ellipsoid.joint import JointImage
from worldtrack.trackers.ellipsoid.kept_heights import KeptHeights
from worldtrack.trackers.ellipsoid.life import LifeCycle
from worldtrack.trackers.ellipsoid.match import ROUNDS, Rounds
from worldtrack.trackers.ellipsoid.prediction import MeasuredShare, lone_camera, predicted_places
from worldtrack.trackers.ellipsoid.ray_velocity import flat_rays
from worldtrack.trackers.ellipsoid.real import ternary_real
from worldtrack.trackers.ellipsoid.exits import left_the_view
from worldtrack.trackers.ellipsoid.reentry import LostTracks
from worldtrack.trackers.ellipsoid.region import RegionVisits
from worldtrack.trackers.ellipsoid.cross_view import CrossViewArgs, cross_view_people
from worldtrack.trackers.ellipsoid.cross_view_colour import ColourCheck
from worldtrack.trackers.ellipsoid.search import RescueArgs, RescueSchedule, birth_search, rescue_people
from worldtrack.trackers.ellipsoid.support import MIN_OWN_PIXELS, flag_unmeasurable, measure_support
from worldtrack.trackers.ellipsoid.two_hypotheses import RaySplitter
from worldtrack.trackers.ellipsoid.uncertainty import PositionUncertainty
from worldtrack.trackers.ellipsoid.warm_start import frames_wanted, warm_start
from worldtrack.trackers.lifecycle import frames_for


class EllipsoidTracker(TrackerBase):
    """Multi-person, multi-camera ellipsoid tracker (paper 000) on a shared :class:`PositionMap`.

    Parameters
    ----------
    scene : Scene
    foregrounds : {camera_id: Foreground} — one foreground model per camera this tracker reads
        (e.g. ``StaticBackground(background_image)``)
    config : EllipsoidConfig, optional (default: worldtrack's defaults)
    position_map : PositionMap, optional — share one between trackers (each with its own cameras)

    Attributes
    ----------
    views : {camera_id: CameraView} — the cameras, as the tracker reads them
    rounds : Rounds — the matching rounds (``match.rounds``: compiled, or the Python reference)
    frames_stepped : int — frames stepped so far
    frame_interval : float — the last frame interval seen, s (0 before two frames)
    last_masks, last_labels : {camera_id: (H, W) uint8} — the last frame's foreground, per camera
    """

    def __init__(self, scene: Scene, foregrounds: Mapping[str, Foreground], config: EllipsoidConfig | None = None,
                 position_map: PositionMap | None = None):
        self.scene = scene
        self.config = cfg = config if config is not None else EllipsoidConfig()
        self.position_map = position_map if position_map is not None else PositionMap()
        self._draw = DrawArgs(float(cfg.score.min_depth_m), float(cfg.score.ring_fraction))
        self.views: dict[str, CameraView] = {cid: camera_view(scene, cid, fg, cfg.score.ring_px_160, self._draw)
                                             for cid, fg in foregrounds.items()}
        self.position_map.cameras.update(self.views)
        raster = scene.walkable.raster(0.01)
        #: (M, 2) floor points → (M,) bool: where people can stand (1 cm raster).
        self.walkable = raster.contains
        self._walk = Walkable(raster.inside, np.asarray(raster.origin, float), float(raster.resolution))
        self.scoring = Scoring(self._draw, int(cfg.score.target_pixels), cfg.score.kind == "symmetric",
                               cfg.score.camera_weights == "current", bool(cfg.score.fixed_pixels))
        m, crowd = cfg.match, cfg.crowd
        self.steps = StepArgs(float(m.step_m), float(m.min_step_m), float(m.max_step_m), int(m.iterations),
                              int(m.max_iterations), bool(m.adaptive_step), float(m.min_gain))
        self.rounds: Rounds = ROUNDS[m.rounds]
        self.births = Births(self.views, scene, self.walkable, cfg.births,
                             cfg.height.range_m if cfg.height.measure and crowd.births_heights else None,
                             cfg.height.min_px, crowd.births_past_people, crowd.births_head_bands, crowd)
        self.life = LifeCycle(cfg, self.position_map, len(self.views) >= 2, self._promote)
        self.frames_stepped = 0
        self.frame_interval = 0.0
        self._last_t: float | None = None
        self._other_views: dict[str, CameraView] = {}
        self.last_masks: dict[str, np.ndarray] = {}
        self.last_labels: dict[str, np.ndarray] = {}
        #: σ, reported velocity and mode of each person (:mod:`.uncertainty`).
        self.uncertainty = PositionUncertainty()
        self.last_images: dict[str, np.ndarray] = {}
        #: The people's colour models (:mod:`.identity`).
        self.identity = Identities(cfg.identity)
        #: Confirmed people lost in the last ``lost.keep_s`` s, to give their ids back (:mod:`.reentry`).
        self.reentry = LostTracks(cfg.lost)
        #: Depth along one camera's line of sight from every cue (:mod:`.depth`; ``depth.fuse``).
        self.depth = DepthFusion(cfg.depth, cfg.feet, cfg.height)
        #: Each confirmed id's height samples, for a person given the id back (:mod:`.kept_heights`).
        self.kept_heights = KeptHeights(cfg.height)
        #: One person or two on one line of sight (:mod:`.two_hypotheses`; ``split.enabled``).
        self.splitter = RaySplitter(cfg.split, cfg.births.min_separation_m, self.walkable, scene.people.width,
                                    tuple(cfg.height.range_m))
        #: One id per visit to the region of interest (:mod:`.region`; ``region.area``, off when empty).
        self.region = RegionVisits(cfg.region)
        #: Each person's share of velocity measured while their depth was observed (:mod:`.prediction`).
        self.measured_share = MeasuredShare.from_config(cfg)
        self._now = 0.0
        if cfg.crowd.coast_behind_obstacles_s > 0:
            self.life.coasting = self._coasting
        if cfg.match.velocity_along_ray != 1.0:
            self.life.velocity_ray = self._lone_ray
        if cfg.match.velocity_sure_sigma_m > 0:
            self.life.velocity_flat = flat_rays(self.uncertainty.components, cfg.match.velocity_sure_sigma_m)

    # ------------------------------------------------------------------ the Tracker protocol
    def init_track(self, x: float, y: float, track_id: int | None = None, t: float = 0.0,
                   mode: str = "tracking") -> Track:
        """Put a person on the map by hand (``worldtrack track --init ID,X,Y``), at floor place
        (x, y) m, time ``t`` s; ``mode="capture"`` to let them slide into their blob first."""
        if track_id is not None and track_id in self.position_map:
            raise InputError(f"--init: track id {track_id} is already on the map")
        h, w = self.scene.people.size_of(track_id or 0)
        return self.position_map.add(x, y, h, w, mode=mode, time=t, track_id=track_id).track()

    @property
    def warm_start_frames(self) -> int:
        """Frames :meth:`warm_start` wants before the first :meth:`step` (0 = none)."""
        return frames_wanted(self)

    def warm_start(self, frames: Sequence[tuple[float, Mapping[str, Frame]]]) -> None:
        """Start on the first frame with the people the first frames show (:mod:`.warm_start`)."""
        warm_start(self, frames)

    def overlay(self, camera_id: str) -> Overlay:
        """The last foreground mask of ``camera_id`` and the width of its −1 ring (px)."""
        view = self.views.get(camera_id)
        return Overlay(mask=self.last_masks.get(camera_id), ring_px=view.ring_px if view is not None else None)

    def fresh(self) -> "EllipsoidTracker":
        """An empty tracker on the same scene, foregrounds and settings, with a map of its own."""
        return EllipsoidTracker(self.scene, {cid: v.foreground for cid, v in self.views.items()}, self.config)

    def step(self, frames: Mapping[str, Frame], t: float) -> list[Track]:
        """Update the map with one synchronised bundle of frames (``{camera_id: Frame}``, cameras
        this tracker does not read are ignored) taken at time ``t`` (s); return the confirmed
        people's tracks (everybody on the map, whoever's cameras see them)."""
        self.position_map.advance(t)
        self._now = t
        dt = 0.0 if self._last_t is None else max(t - self._last_t, 1e-6)
        if dt > 0:
            self.frame_interval = dt
        real = self._read(frames)
        people = list(self.position_map)
        self._predict(people, dt, t)
        self.depth.remember_prediction(people)
        judged = self._judged(people, t)
        bystanders = [p for p in people if not any(p is q for q in judged)]
        scores = self._match(judged, real, t, bystanders)
        born = self._births(real, t)
        if born:
            scores += self._match(born, real, t, judged + bystanders)
        if self.config.split.enabled and real:
            split = self._split(real, judged + bystanders + born, t)
            born, scores = born + split, scores + [(0.0, 0.0)] * len(split)
        anchor_to_feet(judged + born, self.views, self.last_labels, self.walkable, self.config.feet, self.config.height, self.config.anchor_height)
        self.depth.apply(judged + born, self.views, self.last_labels, self.walkable, dt if dt > 0 else self.frame_interval)
        if self.config.identity.enabled:  # before the life cycle: a person confirmed now is re-identified by it
            self.identity.update(judged + born, self.views, self.last_images, self.last_labels, t,
                                 lambda p: self.position_map.get(p.id) is p)
        self._update(judged + born, bystanders, scores, len(judged), t, dt)
        if self.config.crowd.predict_along_ray_measured:   # was each one's depth observed (the feet in view)?
            self.measured_share.observe(judged, list(self.position_map), self.views, list(self.last_labels), t)
        self.uncertainty.measure(self, real, t)
        if self.config.lost.keep_s > 0:
            share = self.config.lost.border_share
            self.reentry.watch(self.position_map, t, lambda p: self.position_map.get(p.id) is p,
                               (lambda p, xy: left_the_view(self.views.values(), xy, p.height, p.width, share))
                               if share > 0 else None)
        if self.config.height.keep_with_id:
            self.kept_heights.remember(self.position_map)
        self._last_t = t
        self.frames_stepped += 1
        return self.region.relabel(self.uncertainty.tracks(self.position_map, t), t)

    # ------------------------------------------------------------------ steps
    def _read(self, frames: Mapping[str, Frame]) -> dict[str, np.ndarray]:
        """The ternary real image of each camera of this tracker in ``frames``. A camera missing
        from the bundle (a skipped frame, a video that ended) has no labels this step, so support
        and heights are not measured on its last, stale image."""
        real: dict[str, np.ndarray] = {}
        for cid in [c for c in self.last_labels if c not in frames]:
            del self.last_labels[cid]
            self.last_masks.pop(cid, None)
            self.last_images.pop(cid, None)
        for cid, frame in frames.items():
            if cid not in self.views:
                continue
            fg = self.views[cid].foreground
            image = frame_image(frame)
            labels = fg.labels(image)
            self.last_labels[cid] = labels
            self.last_images[cid] = image
            self.last_masks[cid] = (labels == 1).astype(np.uint8)
            real[cid] = ternary_real(labels, self.views[cid].ring_px)
        return real

    def _predict(self, people: Sequence[Person], dt: float, t: float) -> None:
        """Constant-velocity prediction of tracked people, once per time stamp; a prediction into a
        wall or a desk stays where it was; ``crowd.predict_along_ray`` < 1 damps the velocity along
        a lone camera's line of sight, ``crowd.predict_along_ray_measured`` by the share of it
        measured while the person's depth was observed (:mod:`.prediction`)."""
        if not (self.config.match.predict and dt > 0):
            return
        moving = [p for p in people if p.mode == "tracking" and p.once("predict", t)]
        share: float | np.ndarray = float(self.config.crowd.predict_along_ray)
        if self.config.crowd.predict_along_ray_measured:   # the share measured with depth observed
            share = share * self.measured_share.shares(moving)
        cids = list(self.views)
        # Which lone camera's ray damps a person's velocity; nobody's at the default share 1.
        damps = bool(np.any(np.asarray(share) != 1.0))
        which = np.array([lone_camera(p.seen_by, cids) if damps else -1 for p in moving], dtype=int)
        ahead = predicted_places(np.array([[p.x, p.y] for p in moving]).reshape(-1, 2),
                                 np.array([[p.vx, p.vy] for p in moving]).reshape(-1, 2), dt,
                                 [self.views[c].camera for c in cids], which, which >= 0, share)
        for p, (x, y), ok in zip(moving, ahead, self.walkable(ahead)):
            if ok:
                p.x, p.y = float(x), float(y)

    def _judged(self, people: Sequence[Person], t: float) -> list[Person]:
        """The people this tracker moves and judges: those its cameras show, and those no camera on
        the map shows. (All of them when no other tracker's cameras are on the map.)"""
        others = self._cameras_of_others()
        if not others:
            return list(people)
        out = []
        for p in people:
            xy = np.array([p.x, p.y])
            if sum(v.visible_pixels(xy, p.height, p.width) for v in self.views.values()) >= MIN_OWN_PIXELS:
                out.append(p)
            elif not p.seen_now(t) and sum(v.visible_pixels(xy, p.height, p.width) for v in others) < MIN_OWN_PIXELS:
                out.append(p)
        return out

    def _cameras_of_others(self) -> list[CameraView]:
        """Views of the cameras on the map that other trackers read (built once, no foreground)."""
        out = []
        for cid in sorted(self.position_map.cameras):
            if cid in self.views or cid not in self.scene.cameras:
                continue
            if cid not in self._other_views:
                self._other_views[cid] = camera_view(self.scene, cid, None, self.config.score.ring_px_160, self._draw)
            out.append(self._other_views[cid])
        return out

    def _match(self, people: list[Person], real: Mapping[str, np.ndarray], t: float,
               fixed: Sequence[Person] = ()) -> list[tuple[float, float]]:
        """Move each of ``people`` in turn to its best place, ``fixed`` drawn but not moved;
        returns each one's (E, denominator)."""
        cfg = self.config
        if not people or not real:
            return [(0.0, 0.0)] * len(people)
        joint = self.joint_image(real, list(people) + list(fixed))
        for k, p in enumerate(people):
            if cfg.births.search_m > 0 and p.mode == "capture" and p.count("age") == 0:
                birth_search(joint, k, cfg.births.search_m, self.views.get(p.birth_camera))
        use_ring = np.array([p.mode != "capture" for p in people])
        best_e, best_den = self.rounds(joint, use_ring, self.steps)
        if cfg.rescue.search_m > 0:
            every = frames_for(cfg.rescue.every_s, self.frame_interval) if cfg.rescue.every_s > 0 else 0
            rescue_people(joint, people, best_e, best_den,
                          RescueArgs(cfg.rescue.search_m, cfg.rescue.gain, cfg.births.min_separation_m),
                          RescueSchedule(self.frames_stepped, every, cfg.rescue.retry_s, 0.5 * self.frame_interval), t)
        cv = cfg.cross_view
        if cv.search_m > 0:
            accept = ColourCheck(list(people) + list(fixed), self.identity.models, self.views, self.last_images,
                                 self.last_labels, cv.colour_min_pixels, cv.colour_distance,
                                 cv.colour_veto_only) \
                if cv.colour_distance > 0 and cfg.identity.enabled else None
            cross_view_people(joint, people, self.views, best_e, best_den, CrossViewArgs(
                cv.search_m, cv.step_m, cv.min_share, cv.min_ratio, cv.gain, max(cv.clear_m, cfg.births.min_separation_m)),
                accept)
        for k, p in enumerate(people):
            p.x, p.y = float(joint.xy[k, 0]), float(joint.xy[k, 1])
        return [(float(best_e[k]), float(best_den[k])) for k in range(len(people))]

    def joint_image(self, real: Mapping[str, np.ndarray], people: Sequence[Person]) -> JointImage:
        """The joint image of ``people`` in this tracker's cameras with real images ``real``."""
        return JointImage(self.views, real, _people(people), self.scoring, self.walkable, self._walk)

    def _births(self, real: Mapping[str, np.ndarray], t: float) -> list[Person]:
        """New people (tentative, in capture mode) from foreground the simulation does not explain."""
        if not self.births.places.proposes:
            return []
        masks, known = {cid: self.last_masks[cid] for cid in real}, list(self.position_map)
        proposals = self.births.propose(masks, _people(known), self.frames_stepped == 0, [p.id > 0 for p in known])
        h0, w0 = self.scene.people.height, self.scene.people.width
        born = []
        for xy, cid, shown in proposals:
            # The height the blob shows (feet and head in view) is the person's first measurement.
            height = shown if shown is not None and abs(shown - h0) > self.config.height.deadband_m else h0
            p = self.position_map.add(xy[0], xy[1], height, w0, mode="capture", time=t, tentative=True)
            p.birth_camera = cid
            if shown is not None:
                p.height_samples.append(shown)
            born.append(p)
        return born

    def _split(self, real: Mapping[str, np.ndarray], people: list[Person], t: float) -> list[Person]:
        """Second people behind confirmed ones, where rendering two explains the image better
        (:mod:`.two_hypotheses`); they are put on the map confirmed."""
        return self.splitter.split(self.joint_image(real, people), self.last_labels, people, self.position_map, t,
                                   lambda q: self.life._confirm(q, t))

    def _update(self, judged: list[Person], bystanders: list[Person], scores: list[tuple[float, float]],
                n_before: int, t: float, dt: float) -> None:
        """Measure the people's support, then confirm, follow or end those judged; flag, measure
        heights, end duplicates."""
        cfg = self.config
        interval = dt if dt > 0 else self.frame_interval
        everyone = judged + bystanders
        if everyone:
            people = _people(everyone)
            cams = {cid: (self.views[cid].args, self.views[cid].forms(*people)) for cid in self.last_labels}
            covers = np.array([p.mode == "tracking" for p in everyone])
            support = measure_support(cams, self.last_labels, int(cfg.score.target_pixels), covers,
                                      cfg.support.obstacles_explain, cfg.support.obstacles_confirm)
            judged = self.life.update(judged, scores, support, n_before, t, dt, interval)
        flag_unmeasurable(judged, [v.camera for v in self.views.values()], self.scene.occlusion, t)
        if cfg.height.measure:
            present = judged + [p for p in bystanders if self.position_map.get(p.id) is p]
            due = heights_due_clear(judged, present, cfg, self.frames_stepped, self.views, self.last_labels)
            update_heights(present, due, self.views, self.last_labels, lambda pid: self.scene.people.size_of(pid)[0], cfg.height)
        self.life.merge_duplicates(t, interval)

    def _coasting(self, p: Person) -> bool:
        """An unseen person behind obstacles, unseen for less than ``crowd.coast_behind_obstacles_s``."""
        if p.count("unseen") >= frames_for(self.config.crowd.coast_behind_obstacles_s, self.frame_interval):
            return False
        return bool(behind_obstacles(np.array([[p.x, p.y]]), np.array([p.height]),
                                     [v.camera for v in self.views.values()], self.scene.occlusion)[0])

    def _lone_ray(self, p: Person) -> np.ndarray | None:
        """The floor ray (2,) through ``p`` of the one camera of this tracker that showed them; None
        when several did (``match.velocity_along_ray``, :mod:`.ray_velocity`)."""
        c = lone_camera(p.seen_by, list(self.views))
        if c < 0:
            return None
        return list(self.views.values())[c].camera.floor_rays(np.array([[p.x, p.y]]), min_distance=0.3)[0][0]

    def _promote(self, p: Person) -> None:
        """A confirmed candidate gets its public id and the scene's size for that id."""
        if p.id > 0:
            return
        back = self.identity.reidentify(p, self._now, lambda pid: pid in self.position_map) \
            if self.config.identity.enabled else None
        if back is None and self.config.lost.keep_s > 0:
            colours = self.identity.colour_distance if self.config.identity.enabled else (lambda q, pid: None)
            back = self.reentry.claim((p.x, p.y), self._now, lambda pid: pid in self.position_map,
                                      lambda pid: colours(p, pid))
        new = self.position_map.promote(p.id, back)
        height, p.width = self.scene.people.size_of(new)
        if back is not None and self.config.height.keep_with_id:
            self.kept_heights.give_back(p, height)
        if not p.height_samples:  # else keep what was measured (at birth, or since)
            p.height = height


def _people(people: Sequence[Person]) -> People:
    """Floor positions (N, 2), heights (N,) and widths (N,) of ``people``."""
    xy = np.array([[p.x, p.y] for p in people], dtype=float).reshape(-1, 2)
    return People(xy, np.array([p.height for p in people], dtype=float), np.array([p.width for p in people], dtype=float))


__all__ = ["EllipsoidTracker"]
