"""The tracking-by-detection baseline: MOG2 blobs, foot points on the floor, Stone Soup (issue 5).

What a practitioner would build without worldtrack, so the other trackers have something to be
compared against (and a fast fallback):

1. per camera, OpenCV MOG2 foreground with shadow detection (shadows count as background);
2. morphological opening (speckle) then closing (holes, legs joined), connected components;
3. every blob above an area threshold gives one detection, its foot point: the bottom centre of
   the blob (the mean column of its pixels in its lowest rows, at the bottom edge of its lowest
   row), back-projected to the floor (Z = 0). Points off the walkable area are dropped, and so is
   a blob whose bottom touches the image's bottom border (its feet are cut off, so the bottom of
   the blob is not the feet). The centre of the bounding box's bottom edge (``foot_point="box"``)
   is the other common choice; it is off by the lean of people off the image centre (a camera
   looking down sees verticals converge), about 0.1–0.2 m at the side of a 70° view;
4. detections of all cameras at one time stamp are fused the only way the baseline can: points
   from different cameras closer than ``merge_distance_m`` are averaged;
5. Stone Soup tracks the fused points on the floor: a nearly-constant-velocity Kalman filter in
   (x, vx, y, vy), global-nearest-neighbour assignment on the Mahalanobis distance, tracks started
   by a multi-measurement initiator and ended when not updated for ``delete_after_s`` seconds.
   Time stamps are the frames' real times (a fixed epoch + ``t`` seconds), so velocities are in
   m/s whatever the frame rate.

It has no model of a person's extent: two people in one blob are one detection, a person split
into two blobs gives a second detection (usually far off, from the upper part's bottom edge),
and a person standing still for long enough fades into the MOG2 background.

Stone Soup is the optional extra ``worldtrack[baseline]``; it is imported when a
:class:`BlobTracker` is built.

Example
-------
>>> from worldtrack.foreground.background import StaticBackground
>>> tracker = BlobTracker(scene, {"cam1": StaticBackground(bg)})      # doctest: +SKIP
>>> for index, t, frames in source:                                  # doctest: +SKIP
...     tracks = tracker.step(frames, t)
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import datetime, timedelta
from typing import Any, Mapping

import cv2
import numpy as np
from numpy.typing import ArrayLike
from scipy.cluster.hierarchy import fcluster, linkage
from scipy.spatial.distance import pdist

from worldtrack.errors import InputError
from worldtrack.foreground.background import AdaptiveBackground
from worldtrack.foreground.components import blobs
from worldtrack.geometry.camera import Camera
from worldtrack.geometry.quadric import ellipse_parameters, ellipsoid_conics, person_ellipsoid
from worldtrack.scene.model import Scene
from worldtrack.trackers.base import PositionMap, Track, TrackerBase

#: Stone Soup wants datetimes; a frame at ``t`` seconds is at ``_EPOCH + t``. Any fixed epoch works:
#: only differences of time stamps enter the filter.
_EPOCH = datetime(2000, 1, 1)

_MISSING_STONESOUP = "the blobs baseline needs Stone Soup: pip install 'worldtrack[baseline]'"


@dataclass(frozen=True)
class BlobConfig:
    """Parameters of the blob baseline; the defaults are what a practitioner would pick.

    Attributes
    ----------
    mog2_history : int — frames of MOG2 history (OpenCV's default 500)
    mog2_var_threshold : float — squared Mahalanobis distance (colour) for a pixel to match the
        background model (OpenCV's default 16)
    detect_shadows : bool — MOG2 shadow detection; shadow pixels count as background
    learning_rate : float — MOG2 learning rate per frame; −1 = OpenCV's automatic
        ``1 / min(2·frames, history)``. Default (None): ``1 / mog2_history``, the rate the automatic
        one settles at. The automatic one starts fast (1/12 after the 5 priming frames of an
        empty-scene image) and absorbs slow or standing people within the first second. Even at
        1/500 a person standing still fades into the background after about 50 frames (5 s at
        10 fps): MOG2 forgets in frames, not seconds. Only used for the MOG2 models the tracker
        creates itself.
    foot_point : {"bottom", "box"} — where a blob's foot is: the mean column of the blob's pixels in
        its lowest ``foot_band`` of rows, or the centre of its bounding box; both at the bottom edge
    foot_band : float — fraction of the blob's height that counts as its bottom (at least one row)
    open_px : int — radius of the morphological opening (speckle removal), pixels; 0 = none
    close_px : int — radius of the morphological closing after it (fills holes, joins legs), pixels
    min_area_px : int — blobs smaller than this (pixels) are noise
    min_area_fraction : float — blobs smaller than this fraction of the area a standing person
        (the scene's default height × width ellipsoid) would cover at the blob's foot point are
        dropped; 0 = only ``min_area_px``
    merge_distance_m : float — floor points from different cameras closer than this (m) are one
        person and are averaged
    process_noise : float — q of each axis's constant-velocity model (m²/s³): the spectral density
        of the white-noise acceleration; 0.5 lets a walker change speed by about
        ``sqrt(q·Δt)`` = 0.7 m/s in a second
    measurement_noise_m : float — 1-σ error of a foot point on each floor axis (m)
    initial_speed_sigma : float — 1-σ of a new track's velocity on each axis (m/s); its mean is 0
    gate : float — Mahalanobis distance (not squared) beyond which a detection cannot update a
        track; 3 ≈ the 99 % gate of a 2-D Gaussian (χ²₂ = 9.21)
    init_min_points : int — detections (the first included) a tentative track needs before it is
        confirmed (Stone Soup counts updates, not time: 3 points = 0.1 s at 20 fps, 0.4 s at 5 fps)
    init_delete_after_s : float — a tentative track without a detection for this long is dropped (s)
    delete_after_s : float — a confirmed track without a detection for this long ends (s)
    report_coasting : bool — also output confirmed tracks that were not updated in this frame (at
        their predicted position, flagged ``coasting``)
    """

    mog2_history: int = 500
    mog2_var_threshold: float = 16.0
    detect_shadows: bool = True
    learning_rate: float | None = None
    foot_point: str = "bottom"
    foot_band: float = 0.05
    open_px: int = 2
    close_px: int = 5
    min_area_px: int = 150
    min_area_fraction: float = 0.25
    merge_distance_m: float = 0.5
    process_noise: float = 0.5
    measurement_noise_m: float = 0.1
    initial_speed_sigma: float = 1.5
    gate: float = 3.0
    init_min_points: int = 3
    init_delete_after_s: float = 0.5
    delete_after_s: float = 1.0
    report_coasting: bool = True

    def __post_init__(self) -> None:
        positive = ("mog2_var_threshold", "measurement_noise_m", "gate", "init_delete_after_s",
                    "delete_after_s", "merge_distance_m", "process_noise", "initial_speed_sigma")
        for name in positive:
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise InputError(f"blobs tracker: {name}: expected a positive number, got {value!r}")
        for name, low in (("mog2_history", 1), ("open_px", 0), ("close_px", 0), ("min_area_px", 1),
                          ("init_min_points", 1)):
            value = getattr(self, name)
            if not (isinstance(value, int) and value >= low):
                raise InputError(f"blobs tracker: {name}: expected an integer ≥ {low}, got {value!r}")
        if self.foot_point not in ("bottom", "box"):
            raise InputError(f"blobs tracker: foot_point: expected 'bottom' or 'box', got {self.foot_point!r}")
        if not 0 <= self.foot_band <= 1:
            raise InputError(f"blobs tracker: foot_band: expected a fraction in [0, 1], got {self.foot_band!r}")
        if not 0 <= self.min_area_fraction < 10:
            raise InputError(f"blobs tracker: min_area_fraction: expected a fraction in [0, 10), "
                             f"got {self.min_area_fraction!r}")
        if self.learning_rate is not None and not (self.learning_rate == -1 or 0 <= self.learning_rate <= 1):
            raise InputError(f"blobs tracker: learning_rate: expected −1 (automatic) or a rate in [0, 1], "
                             f"got {self.learning_rate!r}")


def merge_points(xy: ArrayLike, groups: ArrayLike, distance: float) -> np.ndarray:
    """Fuse floor points of different cameras that are closer than ``distance``.

    Complete-linkage clustering: in each cluster every two points are at most ``distance`` apart
    and come from different groups (cameras); each cluster becomes its mean.

    Parameters
    ----------
    xy : (N, 2) array_like, metres
    groups : (N,) int — camera index of each point; points of one group are never merged
    distance : float, metres

    Returns
    -------
    (M, 2) ndarray, metres, M ≤ N — clusters in order of their first point

    Examples
    --------
    >>> merge_points([[0, 0], [0.2, 0], [3, 0]], [0, 1, 1], 0.5)
    array([[0.1, 0. ],
           [3. , 0. ]])
    """
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    groups = np.asarray(groups).reshape(-1)
    if len(xy) < 2 or len(np.unique(groups)) < 2:
        return xy.copy()
    d = pdist(xy)
    i, j = np.triu_indices(len(xy), k=1)  # pdist's order
    d[groups[i] == groups[j]] = 1e6 * (distance + 1.0)
    labels = fcluster(linkage(d, method="complete"), t=distance, criterion="distance")
    _, first, inverse = np.unique(labels, return_index=True, return_inverse=True)
    sums = np.zeros((len(first), 2))
    np.add.at(sums, inverse, xy)
    means = sums / np.bincount(inverse)[:, None]
    return means[np.argsort(first)]


class _CameraDetector:
    """One camera's foreground, morphology and blob → floor point step."""

    def __init__(self, camera: Camera, foreground: Any, scene: Scene, config: BlobConfig):
        self.camera = camera
        self.scene = scene
        self.config = config
        if isinstance(foreground, AdaptiveBackground):
            self.foreground = foreground
        else:
            rate = config.learning_rate if config.learning_rate is not None else 1.0 / config.mog2_history
            self.foreground = AdaptiveBackground("mog2", history=config.mog2_history, shadows=config.detect_shadows,
                                                 background=getattr(foreground, "background", None),
                                                 learning_rate=rate, open_px=0,
                                                 var_threshold=config.mog2_var_threshold)
        self.open_kernel = _disc(config.open_px)
        self.close_kernel = _disc(config.close_px)

    def mask(self, image: np.ndarray) -> np.ndarray:
        """(H, W) uint8 foreground after opening then closing, 1 = foreground."""
        if image.shape[:2] != (self.camera.height, self.camera.width):
            raise InputError(f"{self.camera.id}: frame is {image.shape[1]}x{image.shape[0]} but the camera is "
                             f"{self.camera.width}x{self.camera.height}")
        m = self.foreground.mask(image)
        if self.open_kernel is not None:
            m = cv2.morphologyEx(m, cv2.MORPH_OPEN, self.open_kernel)
        if self.close_kernel is not None:
            m = cv2.morphologyEx(m, cv2.MORPH_CLOSE, self.close_kernel)
        return m

    def foot_points(self, mask: np.ndarray) -> np.ndarray:
        """(N, 2) floor points (m) of the blobs in ``mask`` that pass every test."""
        cfg, cam = self.config, self.camera
        feet, areas = [], []
        for area, (x0, y0, w, h), _, blob in blobs(mask, cfg.min_area_px):
            if y0 + h >= cam.height:
                continue  # bottom on the border: feet cut off
            if cfg.foot_point == "bottom":
                # Mean column of the blob's own pixels in its lowest rows.
                u = x0 + np.nonzero(blob[h - max(1, int(round(cfg.foot_band * h))):])[1].mean()
            else:
                u = x0 + (w - 1) / 2
            # Pixel centres are at integers, so the bottom edge of the lowest row is at y0 + h − 0.5.
            feet.append((u, y0 + h - 0.5))
            areas.append(area)
        if not feet:
            return np.zeros((0, 2))
        uv, area = np.array(feet, dtype=float), np.array(areas, dtype=float)
        xy = cam.backproject(uv, 0.0)[:, :2]
        ok = np.isfinite(xy).all(axis=1)
        xy, area = xy[ok], area[ok]
        ok = self.scene.walkable.contains(xy)
        xy, area = xy[ok], area[ok]
        if len(xy) and cfg.min_area_fraction > 0:
            ok = area >= cfg.min_area_fraction * self.expected_area(xy)
            xy = xy[ok]
        return xy

    def expected_area(self, xy: np.ndarray) -> np.ndarray:
        """(N,) pixels a default-size person standing at ``xy`` (m) covers (capped at the image)."""
        people = self.scene.people
        centres, radii = person_ellipsoid(xy, people.height, people.width)
        _, axes, _ = ellipse_parameters(ellipsoid_conics(self.camera.P, centres, radii))
        area = math.pi * axes[:, 0] * axes[:, 1]
        # Behind or around the camera the outline is no ellipse: do not hold the blob to an area.
        return np.where(np.isfinite(area), np.minimum(area, self.camera.width * self.camera.height), 0.0)


def _disc(radius: int) -> np.ndarray | None:
    if radius <= 0:
        return None
    return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * radius + 1, 2 * radius + 1))


class BlobTracker(TrackerBase):
    """Tracking by detection: MOG2 blobs → foot points on the floor → Stone Soup GNN tracker.

    Parameters
    ----------
    scene : Scene
    foregrounds : {camera_id: foreground model}
        An :class:`AdaptiveBackground` is used as it is; for anything else (e.g. a
        :class:`StaticBackground`) the tracker builds its own MOG2 model, primed with the model's
        ``background`` (empty-scene) image when it has one.
    config : BlobConfig, optional
    position_map : PositionMap, optional — share one between trackers/processes

    Attributes
    ----------
    position_map : PositionMap — the confirmed tracks, ids from 1 in order of confirmation
    detectors : {camera_id: per-camera foreground, morphology and foot-point step} (``.foreground``
        is the MOG2 model in use)
    last_masks : {camera_id: (H, W) uint8} — the last foreground masks after morphology
    last_detections : (M, 2) ndarray — the last fused floor points (m) given to Stone Soup
    extra_columns : tuple of str — extra output columns (``sigma``)
    """

    extra_columns = ("sigma",)

    def __init__(self, scene: Scene, foregrounds: Mapping[str, Any], config: BlobConfig | None = None,
                 position_map: PositionMap | None = None):
        try:
            from stonesoup.dataassociator.neighbour import GNNWith2DAssignment
            from stonesoup.deleter.time import UpdateTimeDeleter
            from stonesoup.hypothesiser.distance import DistanceHypothesiser
            from stonesoup.initiator.simple import MultiMeasurementInitiator
            from stonesoup.measures import Mahalanobis
            from stonesoup.models.measurement.linear import LinearGaussian
            from stonesoup.models.transition.linear import (CombinedLinearGaussianTransitionModel,
                                                            ConstantVelocity)
            from stonesoup.predictor.kalman import KalmanPredictor
            from stonesoup.types.detection import Detection
            from stonesoup.types.state import GaussianState
            from stonesoup.types.update import Update
            from stonesoup.updater.kalman import KalmanUpdater
        except ImportError:
            raise InputError(_MISSING_STONESOUP) from None
        if not foregrounds:
            raise InputError(f"blobs tracker: no camera given (scene cameras: {', '.join(scene.cameras)})")
        self.scene = scene
        self.config = cfg = config or BlobConfig()
        self.position_map = position_map if position_map is not None else PositionMap()
        self.detectors = {cid: _CameraDetector(scene.camera(cid), fg, scene, cfg) for cid, fg in foregrounds.items()}
        self.last_masks: dict[str, np.ndarray] = {}
        self.last_detections = np.zeros((0, 2))

        # State (x, vx, y, vy): metres and m/s. F and Q of each axis are Stone Soup's
        # constant velocity: F = [[1, Δt], [0, 1]], Q = q·[[Δt³/3, Δt²/2], [Δt²/2, Δt]].
        q = float(cfg.process_noise)
        self._transition = CombinedLinearGaussianTransitionModel([ConstantVelocity(q), ConstantVelocity(q)])
        # z = H·x + v, H picks (x, y), R = r²·I.
        r2 = float(cfg.measurement_noise_m) ** 2
        self._measurement = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.diag([r2, r2]))
        self._predictor = KalmanPredictor(self._transition)
        self._updater = KalmanUpdater(self._measurement)
        hypothesiser = DistanceHypothesiser(self._predictor, self._updater, measure=Mahalanobis(),
                                            missed_distance=float(cfg.gate))
        self._associator = GNNWith2DAssignment(hypothesiser)
        self._deleter = UpdateTimeDeleter(time_since_update=timedelta(seconds=cfg.delete_after_s))
        # The prior's position parts are replaced by the first detection (and R); velocity ~ N(0, σv²).
        sv2 = float(cfg.initial_speed_sigma) ** 2
        prior = GaussianState(np.zeros((4, 1)), np.diag([0.0, sv2, 0.0, sv2]))
        self._initiator = MultiMeasurementInitiator(
            prior_state=prior, measurement_model=self._measurement,
            deleter=UpdateTimeDeleter(time_since_update=timedelta(seconds=cfg.init_delete_after_s)),
            data_associator=self._associator, updater=self._updater, min_points=int(cfg.init_min_points))
        self._Detection = Detection
        self._Update = Update
        self._tracks: set = set()          # confirmed Stone Soup tracks
        self._ids: dict[str, int] = {}     # Stone Soup track id → our integer id
        self._last_t: float | None = None

    # ------------------------------------------------------------------ public
    def detect(self, camera_id: str, image: np.ndarray) -> np.ndarray:
        """Floor points (N, 2) in metres of the blobs in one camera's image (updates its MOG2 model)."""
        if camera_id not in self.detectors:
            raise InputError(f"blobs tracker: no foreground model for camera {camera_id!r} "
                             f"(cameras: {', '.join(self.detectors)})")
        det = self.detectors[camera_id]
        mask = det.mask(image)
        self.last_masks[camera_id] = mask
        return det.foot_points(mask)

    def step(self, frames: Mapping[str, Any], t: float) -> list[Track]:
        """Update with one synchronised bundle ``{camera_id: Frame}`` taken at ``t`` seconds.

        Returns
        -------
        list of Track
            Copies of the confirmed tracks (those coasting only with ``report_coasting``), by id.
        """
        t = float(t)
        if not math.isfinite(t):
            raise InputError(f"blobs tracker: time stamp {t!r} is not a finite number of seconds")
        if self._last_t is not None and t <= self._last_t:
            raise InputError(f"blobs tracker: time stamps must increase, got {t:.6f} s after {self._last_t:.6f} s")
        timestamp = _EPOCH + timedelta(seconds=t)

        points, groups = [], []
        for k, (cid, frame) in enumerate(frames.items()):
            if cid not in self.detectors:
                continue
            xy = self.detect(cid, frame.image if hasattr(frame, "image") else frame)
            points.append(xy)
            groups.append(np.full(len(xy), k))
        xy = np.concatenate(points) if points else np.zeros((0, 2))
        xy = merge_points(xy, np.concatenate(groups) if groups else np.zeros(0, int), self.config.merge_distance_m)
        self.last_detections = xy
        detections = {self._Detection(p.reshape(2, 1), timestamp=timestamp, measurement_model=self._measurement)
                      for p in xy}

        # Stone Soup's MultiTargetTracker loop: associate, update or coast, delete, initiate.
        associations = self._associator.associate(self._tracks, detections, timestamp)
        used = set()
        for track, hypothesis in associations.items():
            if hypothesis:
                track.append(self._updater.update(hypothesis))
                used.add(hypothesis.measurement)
            else:
                track.append(hypothesis.prediction)
        self._tracks -= self._deleter.delete_tracks(self._tracks)
        self._tracks |= self._initiator.initiate(detections - used, timestamp)

        self._sync()
        self._last_t = t
        ours = set(self._ids.values())
        out = [tr.copy() for tr in self.position_map
               if tr.id in ours and (self.config.report_coasting or "coasting" not in tr.flags)]
        return sorted(out, key=lambda tr: tr.id)

    # ------------------------------------------------------------------ bookkeeping
    def _sync(self) -> None:
        """Mirror the confirmed Stone Soup tracks into :attr:`position_map`."""
        live = {track.id for track in self._tracks}
        for sid in [s for s in self._ids if s not in live]:
            tid = self._ids.pop(sid)
            if tid in self.position_map:
                self.position_map.remove(tid)
        # New tracks get ids in a deterministic order (Stone Soup keeps them in sets).
        new = sorted((track for track in self._tracks if track.id not in self._ids),
                     key=lambda tr: (tr.states[0].timestamp, float(tr.state_vector[0, 0]),
                                     float(tr.state_vector[2, 0])))
        for track in new:
            born = (track.states[0].timestamp - _EPOCH).total_seconds()
            tr = self.position_map.add(float(track.state_vector[0, 0]), float(track.state_vector[2, 0]),
                                       mode="tracking", time=born)
            tr.height, tr.width = self.scene.people.size_of(tr.id)
            self._ids[track.id] = tr.id
        for track in self._tracks:
            tr = self.position_map[self._ids[track.id]]
            x = np.asarray(track.state_vector, dtype=float).ravel()
            P = np.asarray(track.covar, dtype=float)
            tr.x, tr.vx, tr.y, tr.vy = (float(v) for v in x)
            # RMS of the two position standard deviations.
            tr.sigma = float(math.sqrt(max(0.5 * (P[0, 0] + P[2, 2]), 0.0)))
            tr.age_frames = len(track.states)
            updated = isinstance(track.state, self._Update)
            missed = 0
            for state in reversed(track.states):
                if isinstance(state, self._Update):
                    tr.last_seen = (state.timestamp - _EPOCH).total_seconds()
                    break
                missed += 1
            tr.frames_low = missed
            tr.score = 1.0 if updated else 0.0
            tr.mode = "tracking"
            if updated:
                tr.flags.discard("coasting")
            else:
                tr.flags.add("coasting")
