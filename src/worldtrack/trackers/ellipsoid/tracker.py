"""Ellipsoid analysis-by-synthesis tracking (seed 000: Kato, Nakazawa & Inokuchi, 1999).

Each person is an ellipsoid on the floor. For every person in turn, 9 candidate positions
(−s, 0, +s along the floor-projected viewing direction and its perpendicular) are rendered into
the joint simulated image of everybody, compared with the ternary foreground image by
``E = Σ sim·real / Σ |sim|`` (eq. 5), and the best one is kept; this is repeated K times a frame.

As published (:meth:`EllipsoidConfig.paper`): s = 50 mm, K = 3, ring of 5 px at 160×120, capture
mode without the ring until E > 0.7, every pixel summed, a fixed-threshold grey difference.

Beyond the paper (the default configuration adds these; each can be switched off):

* several cameras on one map — a candidate's score is Σ numerators / Σ denominators over the
  cameras that see it, so a person hidden in one view is held by another; for a tracked person
  each camera's denominator is taken at the person's current place (``camera_weights``), so a
  candidate cannot gain by sliding out of the view of a camera that fits the person badly;
* automatic start of tracks from foreground the simulation does not explain, confirmed in capture
  mode; tracks end when the person leaves every view or the score stays low;
* coarse-to-fine steps and constant-velocity prediction, so fast walkers are followed and the
  final position is finer than the 50 mm grid;
* an ``unmeasurable`` flag (with a wide uncertainty) when head and feet are hidden in every view;
* scoring on a pixel grid sized to the person (``target_pixels``), so cost does not grow with
  image resolution.

Example
-------
>>> from worldtrack.foreground.background import StaticBackground
>>> tracker = EllipsoidTracker(scene, {"cam1": StaticBackground(bg)})        # doctest: +SKIP
>>> for index, t, frames in source:                                         # doctest: +SKIP
...     tracks = tracker.step(frames, t)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import lru_cache
from typing import Mapping, NamedTuple, Sequence

import cv2
import numpy as np

from worldtrack.foreground.background import Foreground
from worldtrack.foreground.components import blob_extent, blobs
from worldtrack.geometry.camera import Camera
from worldtrack.scene.model import Scene
from worldtrack.trackers.base import PositionMap, Track, TrackerBase
from worldtrack.trackers.ellipsoid.config import EllipsoidConfig
from worldtrack.trackers.lifecycle import frames_for
from worldtrack.trackers.ellipsoid.args import (CameraArgs, DrawArgs, Forms, People, ScoreArgs, StepArgs, Walkable,
                                                camera_args)
from worldtrack.trackers.ellipsoid.forms import ellipse_crop, owner_crop, person_forms
from worldtrack.trackers.ellipsoid.match import OFFSETS, STAY, RoundScoring, held_scores, run_rounds
from worldtrack.trackers.ellipsoid.real import ternary_real
from worldtrack.trackers.ellipsoid.score import score_camera
from worldtrack.trackers.ellipsoid.support import track_support
from worldtrack.trackers.ellipsoid.height import head_ray, measure_height, pixel_clear, triangulate_height

#: Pixels a person must show (in all cameras together) to count as seen, or as its own.
_MIN_OWN_PIXELS = 40
#: A person's height is measured in a view where others' ellipses cover at most this share of its region.
_MAX_COVERED_FOR_HEIGHT = 0.3


@dataclass
class _CameraState:
    """Everything about one camera that does not change from frame to frame."""

    camera: Camera
    args: CameraArgs
    ring_px: int
    foreground: Foreground
    draw: DrawArgs
    _down: tuple | None = None
    _smallest: float | None = None

    @property
    def grid(self) -> np.ndarray:
        return self.args.grid

    @property
    def occ(self) -> np.ndarray:
        return self.args.occ

    def down_direction(self, uv: np.ndarray) -> np.ndarray | None:
        """Image direction of world-down at pixel ``uv`` (from a map built once), or None."""
        if self._down is None:
            step = 8  # the direction varies slowly: sample every 8 px, look up the nearest
            v, u = np.mgrid[0:self.camera.height:step, 0:self.camera.width:step]
            d = self.camera.image_down_direction(np.stack([u.ravel(), v.ravel()], axis=1).astype(float))
            self._down = (step, d.reshape(u.shape + (2,)))
        step, grid = self._down
        j = min(int(round(uv[1] / step)), grid.shape[0] - 1)
        i = min(int(round(uv[0] / step)), grid.shape[1] - 1)
        d = grid[max(j, 0), max(i, 0)]
        return d if np.isfinite(d).all() else None

    def forms(self, xy: np.ndarray, heights: np.ndarray, widths: np.ndarray) -> Forms:
        """Ellipse forms of people at ``xy`` plus their floor distances from this camera."""
        return person_forms(self.args, xy, heights, widths, self.draw)


class EllipsoidTracker(TrackerBase):
    """Multi-person, multi-camera ellipsoid tracker on a shared :class:`PositionMap`.

    Parameters
    ----------
    scene : Scene
    foregrounds : {camera_id: Foreground}
        One foreground model per camera used (e.g. ``StaticBackground(background_image)``).
    config : EllipsoidConfig, optional
    position_map : PositionMap, optional — share one between trackers/processes
    """

    def __init__(self, scene: Scene, foregrounds: Mapping[str, Foreground], config: EllipsoidConfig | None = None,
                 position_map: PositionMap | None = None):
        self.scene = scene
        self.config = config if config is not None else EllipsoidConfig()
        self.position_map = position_map if position_map is not None else PositionMap()
        self.cams: dict[str, _CameraState] = {}
        self._draw = DrawArgs(float(self.config.score.min_depth_m), float(self.config.score.ring_fraction))
        for cid, fg in foregrounds.items():
            cam = scene.camera(cid)
            ring = max(1, int(round(self.config.score.ring_px_160 * math.sqrt(cam.width * cam.height / (160 * 120)))))
            args = camera_args(cam, float(ring), scene.occlusion(cid).floor_distance)
            self.cams[cid] = _CameraState(cam, args, ring, fg, self._draw)
        self._walk_raster = scene.walkable.raster(0.01)
        self._walkable = self._walk_raster.contains
        self._walk_args = Walkable(self._walk_raster.inside, np.asarray(self._walk_raster.origin, float),
                                   float(self._walk_raster.resolution))
        self._python_rounds = self.config.match.rounds == "python"
        self._last_t: float | None = None
        self._frame = 0
        #: The frame interval (s) last seen, for durations on a first frame (learned in a warm start).
        self._interval = 0.0
        self._close_frames: dict[tuple[int, int], int] = {}
        self._unseen: dict[int, int] = {}
        self._confirmed: set[int] = set()
        self._heights: dict[int, list[float]] = {}
        self._height_tries: dict[int, int] = {}
        #: Per camera, the last frame's foreground mask (for overlays) and foreground labels.
        self.last_masks: dict[str, np.ndarray] = {}
        self.last_labels: dict[str, np.ndarray] = {}

    # ------------------------------------------------------------------ public
    def init_track(self, x: float, y: float, track_id: int | None = None, mode: str = "tracking",
                   t: float = 0.0) -> Track:
        """Put a person on the map by hand (``worldtrack track --init ID,X,Y``)."""
        h, w = self.scene.people.size_of(track_id or 0)
        tr = self.position_map.add(x, y, h, w, mode=mode, time=t, track_id=track_id)
        if mode == "tracking":
            self._confirmed.add(tr.id)
        return tr

    @property
    def warm_start_frames(self) -> int:
        """Frames :meth:`warm_start` wants before the first :meth:`step` (0 = none: see the config)."""
        n = self.config.warm_start.frames
        if n < 2 or self._frame > 0 or len(self.position_map) > 0:
            return 0
        if any(getattr(cs.foreground, "learns", True) for cs in self.cams.values()):
            return 0  # the model would learn the first frames three times, once backwards
        return n

    def warm_start(self, frames: Sequence[tuple[float, Mapping[str, object]]]) -> None:
        """Start on the first frame with the people the first frames show (``warm_start_frames``).

        The frames are tracked forwards by a fresh tracker, then backwards (time mirrored) by
        another that starts from the people the first confirmed, with their sizes and height
        measurements; this tracker then starts from the people the backward pass holds on the
        first frame, velocities reversed. The frames must then be given to :meth:`step` as usual,
        from the first. Does nothing when :attr:`warm_start_frames` is 0.

        Parameters
        ----------
        frames : sequence of ``(t, {camera_id: Frame or image})`` — the first frames, in order
            (times in seconds)
        """
        if not self.warm_start_frames or len(frames) < 2:
            return
        ahead = self._fresh()
        for t, views in frames:
            ahead.step(views, t)
        back = self._fresh()
        t_end = frames[-1][0]
        back._adopt(ahead, t_end)
        back._interval = ahead._interval
        for t, views in reversed(frames):
            back.step(views, 2 * t_end - t)
        self._adopt(back, frames[0][0])
        self._interval = back._interval

    def _fresh(self) -> "EllipsoidTracker":
        """An empty tracker on the same scene, foregrounds and settings (for :meth:`warm_start`)."""
        return EllipsoidTracker(self.scene, {cid: cs.foreground for cid, cs in self.cams.items()}, self.config)

    def _adopt(self, other: "EllipsoidTracker", t: float) -> None:
        """Put ``other``'s confirmed people on this map as tracked, at time ``t``, walking the other
        way (a pass in mirrored time hands over): same ids, sizes and height measurements."""
        for tr in other.position_map:
            if tr.id not in other._confirmed:
                continue
            new = self.position_map.add(tr.x, tr.y, tr.height, tr.width, mode="tracking", time=t, track_id=tr.id)
            new.vx, new.vy = -tr.vx, -tr.vy
            self._confirmed.add(new.id)
            if tr.id in other._heights:
                self._heights[new.id] = list(other._heights[tr.id])
            if tr.id in other._height_tries:
                self._height_tries[new.id] = other._height_tries[tr.id]

    def step(self, frames: Mapping[str, object], t: float) -> list[Track]:
        """Update the map with one synchronised bundle of frames; return the confirmed tracks."""
        cfg = self.config
        dt = 0.0 if self._last_t is None else max(t - self._last_t, 1e-6)
        if dt > 0:
            self._interval = dt
        real: dict[str, np.ndarray] = {}
        for cid, frame in frames.items():
            if cid not in self.cams:
                continue
            image = frame.image if hasattr(frame, "image") else frame
            fg = self.cams[cid].foreground
            labels = fg.labels(image) if hasattr(fg, "labels") else fg.mask(image)
            self.last_labels[cid] = labels
            self.last_masks[cid] = (labels == 1).astype(np.uint8)
            real[cid] = ternary_real(labels, self.cams[cid].ring_px)

        tracks = list(self.position_map)
        prev = {tr.id: (tr.x, tr.y) for tr in tracks}
        if cfg.match.predict and dt > 0:
            moving = [tr for tr in tracks if tr.mode == "tracking"]
            ahead = np.array([[tr.x + tr.vx * dt, tr.y + tr.vy * dt] for tr in moving]).reshape(-1, 2)
            for tr, (x, y), ok in zip(moving, ahead, self._walkable(ahead)):
                if ok:  # a prediction into a wall or a desk stays where it was
                    tr.x, tr.y = float(x), float(y)

        scores = self._match(tracks, real, t)
        births = self._births(real, t) if cfg.births.where != "none" else []
        if births:
            scores.update(self._match(births, real, t, others=tracks))
            tracks = tracks + births

        self._update_states(tracks, scores, prev, dt, t)
        self._last_t = t
        self._frame += 1
        return [tr.copy() for tr in self.position_map if tr.id in self._confirmed]

    # ------------------------------------------------------------------ matching
    def _match(self, tracks: list[Track], real: dict[str, np.ndarray], t: float,
               others: list[Track] | None = None) -> dict[int, tuple[float, float]]:
        """Move each of ``tracks`` in turn to its best candidate; returns {id: (E, denominator)}.

        ``others`` are people held fixed (drawn into the joint image but not moved).
        """
        cfg = self.config
        everyone = list(tracks) + list(others or [])
        n = len(tracks)
        result: dict[int, tuple[float, float]] = {}
        if n == 0 or not real:
            return {tr.id: (0.0, 0.0) for tr in tracks}
        xy, hs, ws = _arrays(everyone)
        cids = list(real)
        stacked = Forms(*(np.stack(a) for a in zip(*(self.cams[cid].forms(xy, hs, ws) for cid in cids))))
        # Per camera, views into the stacked arrays: updates through either are shared.
        state = {cid: Forms(*(a[c] for a in stacked)) for c, cid in enumerate(cids)}
        for k, tr in enumerate(tracks):
            seen_by = tr.extra.pop("seen_by", None)  # births' note for this search only
            if cfg.births.search_m > 0 and tr.mode == "capture" and tr.age_frames == 0:
                self._search_new(k, xy, hs, ws, state, real, seen_by)
        use_ring = np.array([tr.mode != "capture" for tr in tracks])
        if self._python_rounds:
            best_e, best_den = self._rounds_python(use_ring, xy, hs, ws, state, real)
        else:
            steps = StepArgs(float(cfg.match.step_m), float(cfg.match.min_step_m), float(cfg.match.max_step_m), int(cfg.match.iterations),
                             int(cfg.match.max_iterations), bool(cfg.match.adaptive_step), float(cfg.match.min_gain))
            scoring = RoundScoring(self._draw, int(cfg.score.target_pixels), cfg.score.kind == "symmetric",
                                   cfg.score.camera_weights == "current")
            best_e, best_den = run_rounds(
                People(xy, hs, ws), n, use_ring, tuple(self.cams[cid].args for cid in cids),
                tuple(real[cid] for cid in cids), stacked, self._walk_args, steps, scoring)
        if cfg.rescue.search_m > 0:
            every = frames_for(cfg.rescue.every_s, self._interval) if cfg.rescue.every_s > 0 else 0
            for k, tr in enumerate(tracks):
                # Periodically too, for everyone (``_rescue`` never moves onto somebody else).
                periodic = every > 0 and (self._frame + tr.id) % every == 0
                # A failing track whose search found nothing better waits a while before searching
                # again: the same line of sight a frame later rarely holds a new answer. (Half a
                # frame of slack: time stamps are rounded.)
                failing = tr.frames_low > 0 and t + 0.5 * self._interval >= tr.extra.get("rescue_after", -np.inf)
                if tr.mode == "tracking" and (failing or periodic):
                    found = self._rescue(k, xy, hs, ws, state, real)
                    if found is not None:
                        best_e[k], best_den[k] = found
                    elif failing:
                        tr.extra["rescue_after"] = t + cfg.rescue.retry_s
        for k, tr in enumerate(tracks):
            tr.x, tr.y = float(xy[k, 0]), float(xy[k, 1])
            result[tr.id] = (float(best_e[k]), float(best_den[k]))
        return result

    def _rounds_python(self, use_ring: np.ndarray, xy: np.ndarray, hs: np.ndarray, ws: np.ndarray, state: dict,
                       real: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        """The matching rounds in plain Python: the reference for :func:`ellipsoid_match.run_rounds`."""
        cfg = self.config
        n = len(use_ring)
        step = np.full(n, cfg.match.step_m)
        done = np.zeros(n, dtype=bool)
        best_e = np.zeros(n)
        best_den = np.zeros(n)
        rounds = cfg.match.max_iterations if cfg.match.adaptive_step else cfg.match.iterations
        for it in range(rounds):
            for k in range(n):
                if done[k]:
                    continue
                e, den, cand, forms, ok = self._score_person(k, xy, hs, ws, step[k], state, real, bool(use_ring[k]))
                if not ok:
                    done[k] = True
                    best_e[k], best_den[k] = e[STAY], den[STAY]
                    continue
                b = int(np.argmax(e))
                if cfg.match.adaptive_step and e[b] - e[STAY] < cfg.match.min_gain:
                    b = STAY
                best_e[k], best_den[k] = e[b], den[b]
                if b != STAY:
                    xy[k] = cand[b]
                    _keep(state, forms, k, b)
                if cfg.match.adaptive_step:
                    if b == STAY:
                        if step[k] <= cfg.match.min_step_m * 1.001:
                            done[k] = True
                        else:
                            step[k] = max(step[k] / 2, cfg.match.min_step_m)
                    elif it >= cfg.match.iterations - 1:
                        step[k] = min(step[k] * 2, cfg.match.max_step_m)
            if done.all():
                break
        return best_e, best_den

    def _score_person(self, k: int, xy: np.ndarray, hs: np.ndarray, ws: np.ndarray, step: float,
                      state: dict, real: dict[str, np.ndarray], use_ring: bool):
        """E of the 9 candidates of person ``k`` over all cameras: Σ num / Σ den, with the cameras
        weighed as at the current place for a tracked person (``camera_weights``)."""
        d, e_perp = self._axes(k, state)
        cand = xy[k] + step * (OFFSETS[:, :1] * d + OFFSETS[:, 1:] * e_perp)
        e, den, forms = self._score_candidates(k, cand, np.full(9, hs[k]), np.full(9, ws[k]), state, real, use_ring,
                                               current=STAY if use_ring else None)
        walk = self._walkable(cand)
        walk[STAY] = True
        e[~walk] = -np.inf
        ok = bool(den[STAY] > 0)
        if not ok:
            e[:] = 0.0
        return e, den, cand, forms, ok

    def _search_new(self, k: int, xy: np.ndarray, hs: np.ndarray, ws: np.ndarray, state: dict,
                    real: dict[str, np.ndarray], seen_by: str | None = None) -> None:
        """Place a just-proposed person by a coarse grid search before the 9-candidate steps.

        A blob's foot point is uncertain mostly along the line of sight of the camera the blob
        was found in (``seen_by``: feet lost in a hole of the mask, two people merged, a head
        back-projected at the default height), so candidates spread ±``birth_search_m`` along that
        camera's ray through the guess and ±0.2 m across it, 0.1 m apart — and likewise along the
        ray of the camera that sees the guess largest (the only one without ``seen_by``) — all
        scored over every camera.
        """
        cfg = self.config
        axes = [self._axes(k, state, xy, along_ray=True)]
        if seen_by in self.cams:
            ray = _ray_direction(self.cams[seen_by].camera, xy[k])
            if not np.allclose(ray, axes[0][0]):  # the same camera: nothing new to search
                axes.append((ray, np.array([-ray[1], ray[0]])))
        along = np.arange(-cfg.births.search_m, cfg.births.search_m + 1e-9, 0.1)
        across = np.array([-0.2, -0.1, 0.0, 0.1, 0.2])
        grid = np.array([(a, c) for a in along for c in across])
        cand = np.concatenate([xy[k] + grid[:, :1] * d[0] + grid[:, 1:] * d[1] for d in axes])
        cand = cand[self._walkable(cand)]
        if len(cand) == 0:
            return
        # Scored with the ring (and, by default, the unexplained foreground): without them the
        # smallest, farthest ellipse that fits inside the blob would win (the paper's Fig. 2).
        e, den, forms = self._score_candidates(k, cand, np.full(len(cand), hs[k]), np.full(len(cand), ws[k]),
                                               state, real, use_ring=True)
        b = int(np.argmax(e))
        if not np.isfinite(e[b]):
            return
        xy[k] = cand[b]
        _keep(state, forms, k, b)

    def _rescue(self, k: int, xy: np.ndarray, hs: np.ndarray, ws: np.ndarray, state: dict,
                real: dict[str, np.ndarray]) -> tuple[float, float] | None:
        """Search the viewing line ±``rescue_search_m`` for a clearly better place (by ``rescue_gain``).

        The 9-candidate steps climb E locally and cannot cross what is not walkable: a track that
        settled behind the wrong row of desks — E has a second peak along the viewing direction
        there — stays. Run on a track whose support is failing, and on each track every
        ``rescue_every`` frames; never onto somebody else (``min_separation_m``).

        The current place is scored in the same call as the candidates: E depends on the pixels
        visited (the union of the candidates' boxes, on a stride that keeps ``target_pixels``), so
        only scores from one call compare. Returns (E, denominator) of the new place, or None.
        """
        cfg = self.config
        along = np.arange(-cfg.rescue.search_m, cfg.rescue.search_m + 1e-9, 0.15)
        along = along[np.abs(along) > 0.2]
        # Along every seeing camera's line of sight: with two cameras the error lies along the one
        # that fixes depth worse, not necessarily the one that sees the person largest.
        cand = np.concatenate([xy[k] + along[:, None] * d for d in self._ray_directions(k, state, xy)])
        others = np.delete(xy, k, axis=0)
        ok = self._walkable(cand)
        if len(others):
            dist = np.min(np.linalg.norm(cand[:, None, :] - others[None, :, :], axis=2), axis=1)
            ok &= dist >= cfg.births.min_separation_m
        if not ok.any():
            return None
        cand = np.vstack([xy[k], cand[ok]])                   # row 0: where the person is now
        e, den, forms = self._score_candidates(k, cand, np.full(len(cand), hs[k]), np.full(len(cand), ws[k]),
                                               state, real, use_ring=True)
        num = np.where(np.isfinite(e), e, 0.0) * den          # Σ sim·real (0 where not in view)
        e_here = float(e[0]) if np.isfinite(e[0]) else 0.0
        # E is a ratio: a place where less of the person is in view (past the image border) can
        # score higher on less evidence. A move must also raise the net matched evidence.
        e[num < num[0]] = -np.inf
        e[0] = -np.inf
        b = int(np.argmax(e))
        if not np.isfinite(e[b]) or e[b] < e_here + cfg.rescue.gain:
            return None
        xy[k] = cand[b]
        _keep(state, forms, k, b)
        return float(e[b]), float(den[b])

    def _ray_directions(self, k: int, state: dict, xy: np.ndarray) -> list[np.ndarray]:
        """Unit floor directions of the rays from each camera that sees person ``k`` through its
        position (the camera's optical axis for a person right below it); one direction at least."""
        out = [_ray_direction(self.cams[cid].camera, xy[k]) for cid, st in state.items() if st.valid[k]]
        return out or [self._axes(k, state, xy, along_ray=True)[0]]

    def _axes(self, k: int, state: dict, xy: np.ndarray | None = None,
              along_ray: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Floor axes for person ``k``: the viewing direction of the camera that sees the person
        largest (the paper's), and its normal.

        With ``along_ray`` the direction is that of the camera's ray through the person's
        position ``xy[k]`` projected on the floor — the direction along which one camera cannot
        tell depth — falling back to the optical axis for a person right below the camera.
        """
        best_cam, best_area = next(iter(state)), -1
        for cid, st in state.items():
            box = st.box[k]
            area = max(0, box[1] - box[0]) * max(0, box[3] - box[2]) if st.valid[k] else 0
            if area > best_area:
                best_cam, best_area = cid, area
        cam = self.cams[best_cam].camera
        d = _ray_direction(cam, xy[k]) if along_ray and xy is not None else cam.floor_direction
        return d, np.array([-d[1], d[0]])

    def _score_candidates(self, k: int, cand: np.ndarray, heights: np.ndarray, widths: np.ndarray,
                          state: dict, real: dict[str, np.ndarray], use_ring: bool, current: int | None = None):
        """E (J,), denominators (J,) and per-camera forms of J candidate ellipsoids for person
        ``k``, everybody else fixed in the joint image.

        E is Σ num / Σ den over the cameras; with ``current`` (the index of the candidate that is the
        person's place now) and ``camera_weights="current"``, each camera is weighed as it is there
        (:func:`ellipsoid_match.held_scores`).
        """
        cfg = self.config
        num = np.zeros((len(state), len(cand)))
        den = np.zeros((len(state), len(cand)))
        forms = {}
        unexplained = use_ring and cfg.score.kind == "symmetric"
        for i, (cid, st) in enumerate(state.items()):
            num[i], den[i], ci, cr, cb, cv, cd = score_camera(
                self.cams[cid].args, real[cid], cand, heights, widths, self._draw, st, k,
                ScoreArgs(use_ring, int(cfg.score.target_pixels), unexplained))
            forms[cid] = Forms(ci, cr, cb, cv, cd)
        if current is not None and cfg.score.camera_weights == "current" and len(state) > 1:
            return held_scores(num, den, current), den.sum(axis=0), forms  # (one camera: the same)
        num, den = num.sum(axis=0), den.sum(axis=0)
        with np.errstate(invalid="ignore", divide="ignore"):
            e = np.where(den > 0, num / np.maximum(den, 1e-12), -np.inf)
        return e, den, forms

    def _smallest_person_px(self, cs: _CameraState) -> float:
        """Image area (px) of a default-size person at the far end of what the camera sees (the
        5th percentile over the walkable floor in view), computed once: smaller blobs cannot be
        a person and are not looked at."""
        if cs._smallest is None:
            x0, x1, y0, y1 = self.scene.walkable.bounds
            gx, gy = np.meshgrid(np.arange(x0, x1, 0.25), np.arange(y0, y1, 0.25))
            xy = np.column_stack([gx.ravel(), gy.ravel()])
            xy = xy[self._walkable(xy)]
            h0, w0 = self.scene.people.height, self.scene.people.width
            inner, _, box, valid, _ = cs.forms(xy, np.full(len(xy), h0), np.full(len(xy), w0))
            seen = valid & (box[:, 0] < box[:, 1]) & (box[:, 2] < box[:, 3])
            det = inner[seen, 2] * inner[seen, 4] - inner[seen, 3] ** 2
            areas = np.pi / np.sqrt(np.maximum(det, 1e-12))
            cs._smallest = float(np.percentile(areas, 5)) if len(areas) else 0.0
        return cs._smallest

    def _nearest_walkable(self, xy: np.ndarray, radius: float) -> np.ndarray | None:
        """``xy`` if walkable, else the nearest walkable point within ``radius`` (5 cm grid), else None.

        A proposal from a head seen above a desk can land on the desk's footprint.
        """
        if self._walkable([xy])[0]:
            return np.asarray(xy, float)
        offsets = _disc_offsets(radius)
        cand = xy + offsets
        ok = self._walkable(cand)
        if not ok.any():
            return None
        d = np.hypot(offsets[ok, 0], offsets[ok, 1])
        return cand[ok][int(np.argmin(d))]

    # ------------------------------------------------------------------ births
    def _births(self, real: dict[str, np.ndarray], t: float) -> list[Track]:
        """Propose new people from foreground that the current simulation does not explain."""
        cfg = self.config
        tracks = list(self.position_map)
        xy, hs, ws = _arrays(tracks)
        h0, w0 = self.scene.people.height, self.scene.people.width
        proposals: list[np.ndarray] = []
        for cid, r in real.items():
            cs = self.cams[cid]
            cam = cs.camera
            mask = self.last_masks[cid]
            explained = np.zeros_like(mask)
            if len(tracks):
                inner, _, box, valid, _ = cs.forms(xy, hs, ws)
                _render_union(explained, inner, box, valid, cs.grid, cam.has_distortion)
                explained = cv2.dilate(explained, _disc(2))
            un = mask & (1 - explained)
            # Remove speckle, then join the pieces of one body that holes in the mask split.
            r_open, r_close = 1, max(1, cs.ring_px // 2)
            un = cv2.morphologyEx(un, cv2.MORPH_OPEN, _disc(r_open))
            un = cv2.morphologyEx(un, cv2.MORPH_CLOSE, np.ones((2 * r_close + 1, 2 * r_close + 1), np.uint8))
            if not cv2.countNonZero(un):
                continue
            min_area = max(10 * cam.width * cam.height / (160 * 120),
                           0.1 * self._smallest_person_px(cs))
            # Components found at ~320 px wide (each blob then read back at full resolution):
            # labelling the whole 640x480 frame was a third of the births' time.
            for area, (x0, y0, bw, bh), centroid, blob in blobs(un, min_area, max(1, cam.width // 320)):
                p = _blob_position(cs, blob, (x0, y0), centroid, h0)
                if p is None:
                    continue
                pxy = self._nearest_walkable(p[:2], 0.6)
                if pxy is None or (len(xy) and np.min(np.hypot(*(xy - pxy).T)) < cfg.births.min_separation_m):
                    continue  # off the floor, or somebody already there
                # Is the blob big enough to be (the visible part of) a person standing there?
                expected = _visible_pixels(cs, pxy, h0, w0)
                if expected <= 0 or area < cfg.births.min_blob_fraction * expected:
                    continue
                proposals.append((pxy, cid))
        if not proposals:
            return []
        if cfg.births.where == "entry" and self._frame > 0 and self.scene.entry_regions:
            proposals = [(p, cid) for p, cid in proposals if self.scene.entry_region_index([p])[0] >= 0]
        # Each proposal is already clear of the existing people; keep the proposals apart too.
        new: list[Track] = []
        for p, cid in proposals:
            if any(np.hypot(*(np.array([b.x, b.y]) - p)) < cfg.births.min_separation_m for b in new):
                continue
            tr = self.position_map.add(p[0], p[1], h0, w0, mode="capture", time=t, tentative=True)
            tr.extra["seen_by"] = cid
            new.append(tr)
        return new

    # ------------------------------------------------------------------ bookkeeping
    def _support(self, tracks: list[Track]) -> dict[int, tuple[float, float, float, float, float, int]]:
        """Per person: (visible pixels over all cameras, support, own share, seen share, evidence,
        views).

        Support is the share of the person's own pixels (visible, covered by nobody else) that
        are foreground, in the camera where it is lowest among those that show at least
        ``_MIN_OWN_PIXELS`` of them — a real person is foreground in every view; a ghost that
        explains the legs of a tall neighbour in one view stands on floor in another. NaN when no
        camera shows enough of the person's own pixels to tell. Own share: the fraction of the
        visible pixels that nobody else covers. Seen share: the largest fraction of the whole
        ellipse that some camera shows (image border and obstacles cut it). Evidence: the
        largest fraction of the whole ellipse that is foreground of its own or explained by
        others — low for a track that drifted past the image border or onto the floor. Views: the
        number of cameras that show at least ``_MIN_OWN_PIXELS`` of the person's own pixels.
        """
        cfg = self.config
        if not tracks:
            return {}
        xy, hs, ws = _arrays(tracks)
        covers = np.array([tr.mode == "tracking" for tr in tracks])
        visible = np.zeros(len(tracks))
        own_total = np.zeros(len(tracks))
        seen_share = np.zeros(len(tracks))
        evidence = np.zeros(len(tracks))
        support = np.full(len(tracks), np.nan)
        views = np.zeros(len(tracks), dtype=int)
        for cid, labels in self.last_labels.items():
            cs = self.cams[cid]
            vis, own, own_fg, area = track_support(cs.args, labels, cs.forms(xy, hs, ws), int(cfg.score.target_pixels), covers)
            visible += vis
            own_total += own
            seen_share = np.maximum(seen_share, np.where(area > 0, vis / np.maximum(area, 1), 0.0))
            # Evidence: foreground of its own plus what others explain, over the whole ellipse.
            evidence = np.maximum(evidence, np.where(area > 0, (own_fg + vis - own) / np.maximum(area, 1), 0.0))
            with np.errstate(invalid="ignore", divide="ignore"):
                here = np.where(own >= _MIN_OWN_PIXELS, own_fg / np.maximum(own, 1), np.nan)
            support = np.fmin(support, here)
            views += own >= _MIN_OWN_PIXELS
        own_share = np.where(visible > 0, own_total / np.maximum(visible, 1), np.nan)
        return {tr.id: (visible[k], support[k], own_share[k], seen_share[k], evidence[k], views[k])
                for k, tr in enumerate(tracks)}

    def _update_states(self, tracks: list[Track], scores: dict[int, tuple[float, float]],
                       prev: dict[int, tuple[float, float]], dt: float, t: float) -> None:
        cfg = self.config
        interval = dt if dt > 0 else self._interval
        lost_after = frames_for(cfg.end.lost_after_s, interval)
        leave_after = frames_for(cfg.end.leave_after_s, interval)
        held_frames = frames_for(cfg.confirm.held_s, interval)
        symmetric = cfg.score.kind == "symmetric"
        support = self._support(tracks)
        for tr in tracks:
            e, den = scores.get(tr.id, (0.0, 0.0))
            visible, sup, own_share, seen, evidence, views = support.get(
                tr.id, (0.0, float("nan"), float("nan"), 0.0, 0.0, 0))
            tr.extra["support"] = sup
            tr.extra["own_share"] = own_share
            tr.score = e
            tr.age_frames += 1
            if visible >= _MIN_OWN_PIXELS:
                self._unseen[tr.id] = 0
                tr.last_seen = t
            else:
                self._unseen[tr.id] = self._unseen.get(tr.id, 0) + 1
            if tr.mode == "tracking" and tr.id in prev and dt > 0:
                px, py = prev[tr.id]
                a = cfg.match.velocity_smoothing
                vx = (1 - a) * tr.vx + a * (tr.x - px) / dt
                vy = (1 - a) * tr.vy + a * (tr.y - py) / dt
                speed = math.hypot(vx, vy)
                scale = min(1.0, cfg.match.max_speed_mps / speed) if speed > 0 else 1.0
                tr.vx, tr.vy = vx * scale, vy * scale
            if tr.mode == "capture":
                if self._near_confirmed(tr, cfg.births.min_separation_m):
                    self._end(tr)  # slid onto somebody already tracked
                    continue
                if symmetric:
                    # Held on foreground for several frames: a person, not a flicker.
                    ok = (e > cfg.confirm.symmetric_threshold and sup >= cfg.support.min_support
                          and not own_share < cfg.support.min_own_share and seen >= cfg.support.min_seen_share)
                    tr.extra["held"] = tr.extra.get("held", 0) + 1 if ok else 0
                    # Strong evidence (the paper's own threshold) confirms at once.
                    # So does a person several cameras agree on (a ghost is rarely one in two views).
                    confirmed = (tr.extra["held"] >= held_frames or (ok and e > cfg.confirm.capture_threshold)
                                 or (ok and cfg.confirm.views > 0 and views >= cfg.confirm.views))
                else:
                    confirmed = e > cfg.confirm.capture_threshold
                if confirmed:
                    tr.extra.pop("held", None)
                    self._promote(tr)
                    tr.mode = "tracking"
                    tr.vx = tr.vy = 0.0  # capture moves are sliding into the blob, not walking
                    self._confirmed.add(tr.id)
                    tr.frames_low = 0
                elif t - tr.born > cfg.confirm.within_s:
                    self._end(tr)
                    continue
            else:
                low = (sup < cfg.support.min_support or evidence < cfg.support.min_evidence) if symmetric else e < cfg.end.keep_score
                # A young track living inside someone else's silhouette duplicates them. So does one of
                # any age that at most one of several cameras shows: a person who walks behind
                # somebody in one view is still seen in another.
                if symmetric and own_share < cfg.support.min_own_share and (
                        t - tr.born < cfg.end.young_s or (len(self.cams) >= 2 and views <= 1)):
                    low = True
                # Own pixels that are nearly all floor: a ghost, or a track that lost its person.
                empty = symmetric and sup < cfg.support.empty_support
                tr.frames_low = tr.frames_low + (2 if empty else 1) if low else 0
                if tr.frames_low >= lost_after:
                    self._end(tr)
                    continue
            if self._unseen.get(tr.id, 0) >= leave_after:
                self._end(tr)
                continue
        self._flag_measurability(tracks)
        if cfg.height.measure:
            self._update_heights(tracks)
        self._merge_duplicates()

    def _near_confirmed(self, tr: Track, distance: float) -> bool:
        return any(o.id != tr.id and o.id in self._confirmed and math.hypot(o.x - tr.x, o.y - tr.y) < distance
                   for o in self.position_map)

    def _update_heights(self, tracks: list[Track]) -> None:
        """Measure the height of people a camera sees whole and alone; use the running median.

        See :mod:`worldtrack.trackers.ellipsoid.height`. In one camera, a tracked person is measured when
        others' ellipses cover at most ``_MAX_COVERED_FOR_HEIGHT`` of its region (the tallest
        plausible person's ellipse with its ring), on the pixels nobody else covers; the feet found
        may be up to ``height_depth_offset_m`` from the track along the line of sight (a wrong model
        height puts it there). Measuring stops once ``height_samples`` are in. A person keeps its
        height when never measured (the scene default, the paper's 1.65 m).
        """
        cfg = self.config
        tracks = [tr for tr in tracks if tr.id in self.position_map]
        if not tracks:
            return
        xy, hs, ws = _arrays(tracks)
        lo, hi = cfg.height.range_m
        samples_now: dict[int, list[float]] = {}
        rays: dict[int, list] = {}
        # Every frame until a person has 10 measurements (or 20 frames were tried: someone always
        # in a group rarely gives one), then one frame in five until ``height_samples`` are in:
        # a person's height does not change, and the median of that many is final.
        due = [k for k, tr in enumerate(tracks) if tr.mode == "tracking"
               and len(self._heights.get(tr.id, ())) < cfg.height.samples
               and ((len(self._heights.get(tr.id, ())) < 10 and self._height_tries.get(tr.id, 0) < 20)
                    or (self._frame + tr.id) % 5 == 0)]
        if not due:
            return
        for k in due:
            self._height_tries[tracks[k].id] = self._height_tries.get(tracks[k].id, 0) + 1
        triangulate = len(self.last_labels) >= 2  # head rays from two cameras or more
        for cid, labels in self.last_labels.items():
            cs = self.cams[cid]
            # Where a person's pixels may be: the ellipse of the tallest plausible person (a
            # 1.9 m person sticks out of a 1.65 m ellipse), with its ring.
            _, ring, box, valid, _ = cs.forms(xy, np.full(len(xy), hi), 1.25 * ws)
            cam = cs.camera
            current = cs.forms(xy, hs, ws)
            for k in due:
                tr = tracks[k]
                if not valid[k]:
                    continue
                b = box[k]
                u0, u1, v0, v1 = b
                if u0 >= u1 or v0 >= v1:
                    continue
                region = _form_mask(ring[k], b, cs.grid, cam.has_distortion)
                down = cs.down_direction(np.array([(u0 + u1) / 2, (v0 + v1) / 2]))
                if down is None:
                    continue
                # Who each pixel of the box belongs to (current ellipses): −1 nobody, −2 several people.
                mine = owner_crop(b, current, cs.grid, cam.has_distortion)
                free = (mine == k) | (mine == -1)
                if triangulate:
                    ray = head_ray(cam, labels, cs.occ, region & free, tuple(b), down)
                    if ray is not None:
                        rays.setdefault(tr.id, []).append(ray)
                # Clear enough in this view: others' ellipses cover little of the region; their
                # pixels are left out of it.
                if np.count_nonzero(region & ~free) > _MAX_COVERED_FOR_HEIGHT * np.count_nonzero(region):
                    continue
                region = region & free
                # One camera alone: only oblique views that show the person large — from above,
                # height is neither measurable nor needed; small, it is noise.
                flat = np.hypot(*(xy[k] - cam.centre[:2]))
                if flat < cam.centre[2] - 0.5 * hs[k] or (b[3] - b[2]) < cfg.height.min_px:
                    continue
                h = measure_height(cam, labels, cs.occ, xy[k], region, tuple(b), height_range_m=(lo, hi), down=down,
                                   max_depth_offset_m=cfg.height.depth_offset_m)
                if h is not None:
                    samples_now.setdefault(tr.id, []).append(h)
        for k, tr in enumerate(tracks):
            # Two views of the head from different sides beat any single view.
            head_rays = rays.get(tr.id, [])
            h3 = triangulate_height(head_rays, xy[k], height_range_m=(lo, hi), max_ray_gap_m=cfg.height.ray_gap_m)
            if h3 is not None:
                new = [h3]
            elif len(head_rays) >= 2:
                # Head rays from two views or more that give no height (they miss each other, or
                # meet off the person or outside the plausible range): some view's "head" is most
                # likely somebody else's, and that view's single-camera measurement would be no
                # better. Nothing this frame.
                new = []
            else:
                new = samples_now.get(tr.id, [])
            if not new:
                continue
            samples = self._heights.setdefault(tr.id, [])
            samples.extend(new)
            del samples[:-cfg.height.samples]
            if len(samples) >= 3:
                default = self.scene.people.size_of(tr.id)[0]
                median = float(np.median(samples))
                tr.height = median if abs(median - default) > cfg.height.deadband_m else default

    def _promote(self, tr: Track) -> None:
        """A confirmed candidate gets its public id (and per-id bookkeeping follows it)."""
        if tr.id > 0:
            return
        old = tr.id
        new = self.position_map.promote(old)
        tr.height, tr.width = self.scene.people.size_of(new)
        if old in self._unseen:
            self._unseen[new] = self._unseen.pop(old)
        if old in self._heights:
            self._heights[new] = self._heights.pop(old)
        if old in self._height_tries:
            self._height_tries[new] = self._height_tries.pop(old)

    def _end(self, tr: Track) -> None:
        self._heights.pop(tr.id, None)
        self._height_tries.pop(tr.id, None)
        if tr.id in self.position_map:
            self.position_map.remove(tr.id)
        self._confirmed.discard(tr.id)
        self._unseen.pop(tr.id, None)

    def _merge_duplicates(self) -> None:
        tracks = [tr for tr in self.position_map]
        seen_pairs = set()
        for i in range(len(tracks)):
            for j in range(i + 1, len(tracks)):
                a, b = tracks[i], tracks[j]
                key = (min(a.id, b.id), max(a.id, b.id))
                if math.hypot(a.x - b.x, a.y - b.y) < self.config.end.merge_distance_m:
                    self._close_frames[key] = self._close_frames.get(key, 0) + 1
                    seen_pairs.add(key)
                    if self._close_frames[key] >= frames_for(self.config.end.merge_after_s, self._interval):
                        younger = b if (b.born, b.id) > (a.born, a.id) else a
                        self._end(younger)
        for key in list(self._close_frames):
            if key not in seen_pairs:
                del self._close_frames[key]

    def _flag_measurability(self, tracks: list[Track]) -> None:
        """Flag people whose head and feet are both hidden in every camera (paper Table 2 (b)).

        Such a person's place along the line of sight is unknown: ``unmeasurable`` with σ = 1 m
        instead of a confident wrong place. Vectorised over people.
        """
        tracks = [tr for tr in tracks if tr.id in self.position_map]
        if not tracks:
            return
        n = len(tracks)
        pts = np.array([[[tr.x, tr.y, 0.0], [tr.x, tr.y, tr.height]] for tr in tracks]).reshape(-1, 3)
        seen = np.zeros(n, dtype=bool)
        head_or_feet = np.zeros(n, dtype=bool)
        for cs in self.cams.values():
            cam = cs.camera
            uv = cam.project(pts)
            inside = cam.in_image(uv)
            visible = inside & ~self.scene.occlusion(cam.id).hidden(uv, cam.floor_distance(pts) - 0.05)
            seen |= inside.reshape(n, 2).any(axis=1)
            head_or_feet |= visible.reshape(n, 2).any(axis=1)
        for k, tr in enumerate(tracks):
            if seen[k] and not head_or_feet[k]:
                tr.flags.add("unmeasurable")
                tr.sigma = 1.0
            else:
                tr.flags.discard("unmeasurable")
                tr.sigma = 0.1


def _blob_position(cs: _CameraState, blob: np.ndarray, origin: tuple[int, int], centroid: np.ndarray,
                   height: float) -> np.ndarray | None:
    """Floor position of a person seen as ``blob``, or None.

    ``blob`` is a boolean crop of the image whose top-left pixel is ``origin`` (u, v);
    ``centroid`` is in full-image pixels.

    The feet are the end of the blob in the direction in which world verticals point down in
    the image — the bottom for an oblique camera, the end nearest the image centre for one that
    looks straight down. They are back-projected to the floor, unless the blob ends there at the
    image border or on an obstacle (a desk hides the feet): then its other end, the top of the
    head, is back-projected to the default ``height``.
    """
    cam = cs.camera
    down = cs.down_direction(centroid)
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
    feet_hidden = not pixel_clear(cam, None, beyond).all() or (~pixel_clear(cam, cs.occ, beyond)).mean() > 0.5
    if not feet_hidden:
        p = cam.backproject(foot[None], 0.0)[0]
    elif pixel_clear(cam, None, head - 2 * down):  # the head inside the image
        p = cam.backproject(head[None], height)[0]
    else:
        return None
    return p if np.isfinite(p).all() else None


def _arrays(tracks: list[Track]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Floor positions (N, 2), heights (N,) and widths (N,) of ``tracks``."""
    xy = np.array([[tr.x, tr.y] for tr in tracks], dtype=float).reshape(-1, 2)
    hs = np.array([tr.height for tr in tracks], dtype=float)
    ws = np.array([tr.width for tr in tracks], dtype=float)
    return xy, hs, ws


def _keep(state: dict[str, Forms], forms: dict[str, Forms], k: int, b: int) -> None:
    """Person ``k`` moves to candidate ``b``: copy the candidate's forms into everybody's, per camera."""
    for cid, f in forms.items():
        for dst, src in zip(state[cid], f):
            dst[k] = src[b]


def _ray_direction(cam: Camera, xy: np.ndarray) -> np.ndarray:
    """Unit floor direction of the camera's ray through floor point ``xy`` — the direction along
    which one camera cannot tell depth — or the optical axis's for a point right below the camera."""
    return cam.floor_rays(xy, min_distance=0.3)[0]


@lru_cache(maxsize=8)
def _disc_offsets(radius: float) -> np.ndarray:
    """(K, 2) floor offsets (m) on a 5 cm grid within ``radius`` of the origin, row by row."""
    g = np.arange(-radius, radius + 1e-9, 0.05)
    offsets = np.array([(a, b) for a in g for b in g])
    offsets = offsets[np.hypot(offsets[:, 0], offsets[:, 1]) <= radius]
    offsets.setflags(write=False)
    return offsets


def _disc(radius: int) -> np.ndarray:
    """Elliptical structuring element of the given radius (pixels)."""
    return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * radius + 1, 2 * radius + 1))


def _visible_pixels(cs: _CameraState, xy: np.ndarray, height: float, width: float) -> int:
    """Pixels of a person's ellipse at ``xy`` inside the image and not hidden by obstacles."""
    inner, _, box, valid, dist = cs.forms(np.asarray(xy, float)[None], np.array([height]), np.array([width]))
    u0, u1, v0, v1 = box[0]
    if not valid[0] or u0 >= u1 or v0 >= v1:
        return 0
    inside = _form_mask(inner[0], box[0], cs.grid, cs.camera.has_distortion)
    return int((inside & (cs.occ[v0:v1, u0:u1] >= dist[0])).sum())


def _form_mask(form: np.ndarray, box: np.ndarray, grid: np.ndarray, has_dist: bool) -> np.ndarray:
    """(v1 − v0, u1 − u0) bool: pixels of ``box`` inside the ellipse of normal form ``form``."""
    return ellipse_crop(form, np.asarray(box, dtype=np.int64), grid, has_dist)


def _render_union(out: np.ndarray, forms: np.ndarray, boxes: np.ndarray, valid: np.ndarray,
                  grid: np.ndarray, has_dist: bool) -> None:
    """Set ``out`` to 1 inside the given ellipses (normal forms), within their boxes (in place)."""
    for k in range(len(forms)):
        if not valid[k]:
            continue
        u0, u1, v0, v1 = boxes[k]
        if u0 >= u1 or v0 >= v1:
            continue
        out[v0:v1, u0:u1] |= _form_mask(forms[k], boxes[k], grid, has_dist).astype(np.uint8)
