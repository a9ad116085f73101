"""Ellipsoid analysis-by-synthesis tracking (seed 000: Kato, Nakazawa & Inokuchi, 1999).

Each person is an ellipsoid on the floor. For every person in turn, 9 candidate positions
(−s, 0, +s along the floor-projected viewing direction and its perpendicular) are rendered into
the joint simulated image of everybody, compared with the ternary foreground image by
``E = Σ sim·real / Σ |sim|`` (eq. 5), and the best one is kept; this is repeated K times a frame.

As published (:meth:`EllipsoidConfig.paper`): s = 50 mm, K = 3, ring of 5 px at 160×120, capture
mode without the ring until E > 0.7, every pixel summed, a fixed-threshold grey difference.

Beyond the paper (the default configuration adds these; each can be switched off):

* several cameras on one map — a candidate's score is Σ numerators / Σ denominators over the
  cameras that see it, so a person hidden in one view is held by another;
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
from typing import Mapping

import cv2
import numpy as np

from worldtrack.foreground.background import Foreground
from worldtrack.geometry.camera import Camera
from worldtrack.scene.model import Scene
from worldtrack.trackers.base import PositionMap, Track
from worldtrack.trackers.ellipsoid_score import ellipse_forms, score_candidates, ternary_real

#: The 9 candidate offsets in units of the step, along (viewing direction, perpendicular).
#: Index 4 is "stay".
_OFFSETS = np.array([(i, j) for i in (-1, 0, 1) for j in (-1, 0, 1)], dtype=float)
_STAY = 4
_DUMMY_GRID = np.zeros((1, 1, 2), dtype=np.float32)


@dataclass(frozen=True)
class EllipsoidConfig:
    """Parameters of the ellipsoid tracker; defaults are the paper's where the paper gives one.

    Attributes
    ----------
    step_m : float — candidate step s (paper: 50 mm)
    iterations : int — rounds over all people per frame (paper: K = 3)
    ring_px_160 : float — ring width at 160×120 (paper: 5 px); scaled by ``sqrt(W·H / (160·120))``,
        i.e. with the image's linear size, so the ring covers the same part of a person at any
        resolution
    capture_threshold : float — E above which a captured person switches to tracking (paper: 0.7)
    target_pixels : int — pixels visited per candidate set (0 = all, as published)
    adaptive_step : bool — halve the step when "stay" wins, double it (up to ``max_step_m``) when
        the best candidate is on the edge after the K rounds, up to ``max_iterations`` rounds
    min_step_m, max_step_m : float — limits of the adaptive step
    max_iterations : int — cap on rounds with the adaptive step
    predict : bool — constant-velocity prediction before matching
    velocity_smoothing : float — weight of the new velocity measurement (0..1)
    births : {"anywhere", "entry", "none"} — where new people may appear: anywhere in view, only in
        the scene's entry regions (and on the first frame), or never (tracks only from ``init``)
    min_blob_fraction : float — unexplained blob area / expected person area to propose a person
    confirm_within_s : float — a captured person not confirmed within this time is dropped
    keep_score : float — a tracked person whose E stays below this for ``lost_after_s`` ends
    lost_after_s : float
    leave_after_frames : int — frames unseen by every camera before a track ends
    merge_distance_m : float — two tracks closer than this for 3 frames: the younger ends
    min_depth_m : float — ellipsoids nearer than this to a camera's image plane are not drawn
    """

    step_m: float = 0.05
    iterations: int = 3
    ring_px_160: float = 5.0
    capture_threshold: float = 0.7
    target_pixels: int = 1500
    adaptive_step: bool = True
    min_step_m: float = 0.0125
    max_step_m: float = 0.4
    max_iterations: int = 8
    predict: bool = True
    velocity_smoothing: float = 0.5
    births: str = "anywhere"
    min_blob_fraction: float = 0.3
    confirm_within_s: float = 1.0
    keep_score: float = 0.2
    lost_after_s: float = 1.5
    leave_after_frames: int = 2
    merge_distance_m: float = 0.3
    min_depth_m: float = 0.1

    @classmethod
    def paper(cls, **overrides) -> "EllipsoidConfig":
        """The method exactly as published: fixed 50 mm steps, K = 3, every pixel, no prediction."""
        base = cls(adaptive_step=False, predict=False, target_pixels=0)
        return replace(base, **overrides)

    def __post_init__(self) -> None:
        if self.births not in ("anywhere", "entry", "none"):
            raise ValueError(f"births: expected 'anywhere', 'entry' or 'none', got {self.births!r}")
        if self.step_m <= 0 or self.iterations < 1:
            raise ValueError("step_m must be positive and iterations at least 1")


@dataclass
class _CameraState:
    """Everything about one camera that does not change from frame to frame."""

    camera: Camera
    P: np.ndarray
    grid: np.ndarray
    occ: np.ndarray
    ring_px: int
    foreground: Foreground

    def forms(self, xy: np.ndarray, heights: np.ndarray, widths: np.ndarray, min_depth: float):
        """Ellipse forms of people at ``xy`` plus their floor distances from this camera."""
        c = self.camera
        inner, ring, box, valid = ellipse_forms(self.P, c.K, c.dist, c.has_distortion, c.width, c.height,
                                                xy, heights, widths, float(self.ring_px), min_depth)
        dist = np.hypot(xy[:, 0] - c.centre[0], xy[:, 1] - c.centre[1])
        return inner, ring, box, valid, dist


class EllipsoidTracker:
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
        self.config = config or EllipsoidConfig()
        self.position_map = position_map if position_map is not None else PositionMap()
        self.cams: dict[str, _CameraState] = {}
        for cid, fg in foregrounds.items():
            cam = scene.camera(cid)
            ring = max(1, int(round(self.config.ring_px_160 * math.sqrt(cam.width * cam.height / (160 * 120)))))
            occ = scene.occlusion(cid).floor_distance
            self.cams[cid] = _CameraState(cam, np.ascontiguousarray(cam.P), cam.ideal_pixel_grid
                                          if cam.has_distortion else _DUMMY_GRID, occ, ring, fg)
        self._walkable = scene.walkable.raster(0.01).contains
        self._last_t: float | None = None
        self._frame = 0
        self._close_frames: dict[tuple[int, int], int] = {}
        self._unseen: dict[int, int] = {}
        self._confirmed: set[int] = set()
        #: Per camera, the last frame's foreground mask and ternary image (for overlays).
        self.last_masks: dict[str, np.ndarray] = {}
        self.last_real: dict[str, np.ndarray] = {}

    # ------------------------------------------------------------------ public
    def init_track(self, x: float, y: float, track_id: int | None = None, mode: str = "tracking",
                   t: float = 0.0) -> Track:
        """Put a person on the map by hand (``worldtrack track --init ID,X,Y``)."""
        h, w = self.scene.people.size_of(track_id or 0)
        tr = self.position_map.add(x, y, h, w, mode=mode, time=t, track_id=track_id)
        if mode == "tracking":
            self._confirmed.add(tr.id)
        return tr

    def step(self, frames: Mapping[str, object], t: float) -> list[Track]:
        """Update the map with one synchronised bundle of frames; return the confirmed tracks."""
        cfg = self.config
        dt = 0.0 if self._last_t is None else max(t - self._last_t, 1e-6)
        real: dict[str, np.ndarray] = {}
        for cid, frame in frames.items():
            if cid not in self.cams:
                continue
            image = frame.image if hasattr(frame, "image") else frame
            mask = self.cams[cid].foreground.mask(image)
            self.last_masks[cid] = mask
            real[cid] = ternary_real(mask, self.cams[cid].ring_px)
        self.last_real = real

        tracks = list(self.position_map)
        prev = {tr.id: (tr.x, tr.y) for tr in tracks}
        if cfg.predict and dt > 0:
            for tr in tracks:
                if tr.mode == "tracking":
                    self._move_if_walkable(tr, tr.x + tr.vx * dt, tr.y + tr.vy * dt)

        scores = self._match(tracks, real)
        births = self._births(real, t) if cfg.births != "none" else []
        if births:
            scores.update(self._match(births, real, others=tracks))
            tracks = tracks + births

        self._update_states(tracks, scores, prev, dt, t)
        self._last_t = t
        self._frame += 1
        return [tr.copy() for tr in self.position_map if tr.id in self._confirmed]

    # ------------------------------------------------------------------ matching
    def _match(self, tracks: list[Track], real: dict[str, np.ndarray],
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
        xy = np.array([[tr.x, tr.y] for tr in everyone], dtype=float)
        hs = np.array([tr.height for tr in everyone], dtype=float)
        ws = np.array([tr.width for tr in everyone], dtype=float)
        state = {cid: list(self.cams[cid].forms(xy, hs, ws, cfg.min_depth_m)) for cid in real}
        step = np.full(n, cfg.step_m)
        done = np.zeros(n, dtype=bool)
        best_e = np.zeros(n)
        best_den = np.zeros(n)
        rounds = cfg.max_iterations if cfg.adaptive_step else cfg.iterations
        for it in range(rounds):
            for k in range(n):
                if done[k]:
                    continue
                tr = tracks[k]
                e, den, cand, forms, ok = self._score_person(k, xy, hs, ws, step[k], state, real,
                                                             use_ring=tr.mode != "capture")
                if not ok:
                    done[k] = True
                    best_e[k], best_den[k] = e[_STAY], den[_STAY]
                    continue
                b = int(np.argmax(e))
                best_e[k], best_den[k] = e[b], den[b]
                if b != _STAY:
                    xy[k] = cand[b]
                    for cid, f in forms.items():
                        st = state[cid]
                        for a in range(5):
                            st[a][k] = f[a][b]
                if cfg.adaptive_step:
                    if b == _STAY:
                        if step[k] <= cfg.min_step_m * 1.001:
                            done[k] = True
                        else:
                            step[k] = max(step[k] / 2, cfg.min_step_m)
                    elif it >= cfg.iterations - 1:
                        step[k] = min(step[k] * 2, cfg.max_step_m)
            if done.all():
                break
        for k, tr in enumerate(tracks):
            tr.x, tr.y = float(xy[k, 0]), float(xy[k, 1])
            result[tr.id] = (float(best_e[k]), float(best_den[k]))
        return result

    def _score_person(self, k: int, xy: np.ndarray, hs: np.ndarray, ws: np.ndarray, step: float,
                      state: dict, real: dict[str, np.ndarray], use_ring: bool):
        """E of the 9 candidates of person ``k`` over all cameras (Σ num / Σ den)."""
        cfg = self.config
        # Candidate axes: the viewing direction of the camera that sees the person largest.
        best_cam, best_den = None, -1.0
        for cid, st in state.items():
            box = st[2][k]
            area = (box[1] - box[0]) * (box[3] - box[2]) if st[3][k] else 0
            if area > best_den:
                best_cam, best_den = cid, area
        d = self.cams[best_cam].camera.floor_direction
        e_perp = np.array([-d[1], d[0]])
        cand = xy[k] + step * (_OFFSETS[:, :1] * d + _OFFSETS[:, 1:] * e_perp)
        walk = self._walkable(cand)
        walk[_STAY] = True
        h9 = np.full(9, hs[k])
        w9 = np.full(9, ws[k])
        num = np.zeros(9)
        den = np.zeros(9)
        forms = {}
        for cid, st in state.items():
            cs = self.cams[cid]
            f = cs.forms(cand, h9, w9, cfg.min_depth_m)
            forms[cid] = f
            o_valid = st[3].copy()
            o_valid[k] = False
            nu, de, _ = score_candidates(cs.grid, cs.camera.has_distortion, cs.occ, real[cid], use_ring,
                                         f[0], f[1], f[2], f[4], f[3],
                                         st[0], st[1], st[2], st[4], o_valid, cfg.target_pixels)
            num += nu
            den += de
        with np.errstate(invalid="ignore", divide="ignore"):
            e = np.where(den > 0, num / np.maximum(den, 1e-12), -np.inf)
        e[~walk] = -np.inf
        ok = bool(den[_STAY] > 0)
        if not ok:
            e[:] = 0.0
        return e, den, cand, forms, ok

    def _move_if_walkable(self, tr: Track, x: float, y: float) -> None:
        if self._walkable([[x, y]])[0]:
            tr.x, tr.y = float(x), float(y)

    # ------------------------------------------------------------------ births
    def _births(self, real: dict[str, np.ndarray], t: float) -> list[Track]:
        """Propose new people from foreground that the current simulation does not explain."""
        cfg = self.config
        tracks = list(self.position_map)
        xy = np.array([[tr.x, tr.y] for tr in tracks], dtype=float).reshape(-1, 2)
        hs = np.array([tr.height for tr in tracks], dtype=float)
        ws = np.array([tr.width for tr in tracks], dtype=float)
        h0, w0 = self.scene.people.height, self.scene.people.width
        proposals: list[np.ndarray] = []
        for cid, r in real.items():
            cs = self.cams[cid]
            cam = cs.camera
            mask = self.last_masks[cid]
            explained = np.zeros_like(mask)
            if len(tracks):
                _, ring, box, valid, _ = cs.forms(xy, hs, ws, cfg.min_depth_m)
                _render_union(explained, ring, box, valid, cs.grid, cam.has_distortion)
            un = mask & (1 - explained)
            k = max(1, cs.ring_px // 2)
            un = cv2.morphologyEx(un, cv2.MORPH_OPEN, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * k + 1, 2 * k + 1)))
            n, labels, stats, cent = cv2.connectedComponentsWithStats(un, connectivity=8)
            for j in range(1, n):
                x0, y0, bw, bh, area = stats[j]
                if area < 10:
                    continue
                touches_bottom = y0 + bh >= cam.height - 1
                touches_top = y0 <= 0
                u = float(cent[j][0])
                if not touches_bottom:
                    p = cam.backproject([[u, y0 + bh - 0.5]], 0.0)[0]
                elif not touches_top:
                    p = cam.backproject([[u, y0 - 0.5]], h0)[0]
                else:
                    continue
                if not np.isfinite(p).all():
                    continue
                pxy = p[:2]
                if not self._walkable([pxy])[0]:
                    continue
                # Is the blob big enough to be a person standing there?
                _, _, pbox, pvalid, _ = cs.forms(pxy[None], np.array([h0]), np.array([w0]), cfg.min_depth_m)
                if not pvalid[0]:
                    continue
                inner, _, _, _, _ = cs.forms(pxy[None], np.array([h0]), np.array([w0]), cfg.min_depth_m)
                a11, a12, a22 = inner[0, 2:]
                expected = math.pi / math.sqrt(max(a11 * a22 - a12 * a12, 1e-12))
                if area < cfg.min_blob_fraction * min(expected, cam.width * cam.height):
                    continue
                proposals.append(pxy)
        if not proposals:
            return []
        if cfg.births == "entry" and self._frame > 0 and self.scene.entry_regions:
            proposals = [p for p in proposals if self.scene.entry_region_index([p])[0] >= 0]
        new: list[Track] = []
        existing = xy
        for p in proposals:
            if len(existing) and np.min(np.hypot(*(existing - p).T)) < 0.6:
                continue
            if any(np.hypot(*(np.array([b.x, b.y]) - p)) < 0.6 for b in new):
                continue
            tr = self.position_map.add(p[0], p[1], h0, w0, mode="capture", time=t)
            tr.height, tr.width = self.scene.people.size_of(tr.id)
            new.append(tr)
        return new

    # ------------------------------------------------------------------ bookkeeping
    def _update_states(self, tracks: list[Track], scores: dict[int, tuple[float, float]],
                       prev: dict[int, tuple[float, float]], dt: float, t: float) -> None:
        cfg = self.config
        fps_frames = (lambda s: max(1, int(round(s / dt)))) if dt > 0 else (lambda s: max(1, int(round(s * 10))))
        for tr in tracks:
            e, den = scores.get(tr.id, (0.0, 0.0))
            tr.score = e
            tr.age_frames += 1
            if den > 0:
                self._unseen[tr.id] = 0
                tr.last_seen = t
            else:
                self._unseen[tr.id] = self._unseen.get(tr.id, 0) + 1
            if tr.id in prev and dt > 0:
                px, py = prev[tr.id]
                a = cfg.velocity_smoothing
                tr.vx = (1 - a) * tr.vx + a * (tr.x - px) / dt
                tr.vy = (1 - a) * tr.vy + a * (tr.y - py) / dt
            if tr.mode == "capture":
                if e > cfg.capture_threshold:
                    tr.mode = "tracking"
                    self._confirmed.add(tr.id)
                    tr.frames_low = 0
                elif t - tr.born > cfg.confirm_within_s:
                    self._end(tr)
                    continue
            else:
                tr.frames_low = tr.frames_low + 1 if e < cfg.keep_score else 0
                if tr.frames_low >= fps_frames(cfg.lost_after_s):
                    self._end(tr)
                    continue
            if self._unseen.get(tr.id, 0) >= cfg.leave_after_frames:
                self._end(tr)
                continue
            self._flag_measurability(tr)
        self._merge_duplicates()

    def _end(self, tr: Track) -> None:
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
                if math.hypot(a.x - b.x, a.y - b.y) < self.config.merge_distance_m:
                    self._close_frames[key] = self._close_frames.get(key, 0) + 1
                    seen_pairs.add(key)
                    if self._close_frames[key] >= 3:
                        younger = b if (b.born, b.id) > (a.born, a.id) else a
                        self._end(younger)
        for key in list(self._close_frames):
            if key not in seen_pairs:
                del self._close_frames[key]

    def _flag_measurability(self, tr: Track) -> None:
        """Flag a person whose head and feet are both hidden in every camera (paper Table 2 (b))."""
        head_or_feet = False
        seen = False
        pts = np.array([[tr.x, tr.y, 0.0], [tr.x, tr.y, tr.height]])
        for cs in self.cams.values():
            cam = cs.camera
            uv = cam.project(pts)
            inside = cam.in_image(uv)
            if not inside.any():
                continue
            seen = True
            dist = math.hypot(tr.x - cam.centre[0], tr.y - cam.centre[1])
            hidden = self.scene.occlusion(cam.id).hidden(uv, dist - 0.05)
            if (inside & ~hidden).any():
                head_or_feet = True
                break
        if seen and not head_or_feet:
            tr.flags.add("unmeasurable")
            tr.sigma = 1.0
        else:
            tr.flags.discard("unmeasurable")
            tr.sigma = 0.1


def _render_union(out: np.ndarray, forms: np.ndarray, boxes: np.ndarray, valid: np.ndarray,
                  grid: np.ndarray, has_dist: bool) -> None:
    """Set ``out`` to 1 inside the given ellipses (normal forms), within their boxes (in place)."""
    for k in range(len(forms)):
        if not valid[k]:
            continue
        u0, u1, v0, v1 = boxes[k]
        if u0 >= u1 or v0 >= v1:
            continue
        if has_dist:
            g = grid[v0:v1, u0:u1]
            du = g[..., 0] - forms[k, 0]
            dv = g[..., 1] - forms[k, 1]
        else:
            du = np.arange(u0, u1)[None, :] - forms[k, 0]
            dv = np.arange(v0, v1)[:, None] - forms[k, 1]
        inside = forms[k, 2] * du * du + 2 * forms[k, 3] * du * dv + forms[k, 4] * dv * dv < 1
        out[v0:v1, u0:u1] |= inside.astype(np.uint8)
