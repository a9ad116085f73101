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
>>> from worldtrack.trackers.blobs import BlobTracker
>>> tracker = BlobTracker(scene, {"cam1": StaticBackground(bg)})      # doctest: +SKIP
>>> for index, t, frames in source:                                  # doctest: +SKIP
...     tracks = tracker.step(frames, t)
"""

from __future__ import annotations

import math
from datetime import datetime, timedelta
from typing import Any, Mapping

import numpy as np

from worldtrack.errors import InputError
from worldtrack.scene.model import Scene
from worldtrack.trackers.base import PositionMap, Track, TrackerBase, frame_image
from worldtrack.trackers.blobs.config import BlobConfig
from worldtrack.trackers.blobs.detection import CameraDetector, merge_points

#: Stone Soup wants datetimes; a frame at ``t`` seconds is at ``_EPOCH + t``. Any fixed epoch works:
#: only differences of time stamps enter the filter.
_EPOCH = datetime(2000, 1, 1)

_MISSING_STONESOUP = "the blobs baseline needs Stone Soup: pip install 'worldtrack[baseline]'"


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
        self.detectors = {cid: CameraDetector(scene.camera(cid), fg, scene, cfg) for cid, fg in foregrounds.items()}
        self.last_masks: dict[str, np.ndarray] = {}
        self.last_detections = np.zeros((0, 2))

        # State (x, vx, y, vy): metres and m/s. F and Q of each axis are Stone Soup's
        # constant velocity: F = [[1, Δt], [0, 1]], Q = q·[[Δt³/3, Δt²/2], [Δt²/2, Δt]].
        q = float(cfg.filter.process_noise)
        self._transition = CombinedLinearGaussianTransitionModel([ConstantVelocity(q), ConstantVelocity(q)])
        # z = H·x + v, H picks (x, y), R = r²·I.
        r2 = float(cfg.filter.measurement_noise_m) ** 2
        self._measurement = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.diag([r2, r2]))
        self._predictor = KalmanPredictor(self._transition)
        self._updater = KalmanUpdater(self._measurement)
        hypothesiser = DistanceHypothesiser(self._predictor, self._updater, measure=Mahalanobis(),
                                            missed_distance=float(cfg.filter.gate))
        self._associator = GNNWith2DAssignment(hypothesiser)
        self._deleter = UpdateTimeDeleter(time_since_update=timedelta(seconds=cfg.lifecycle.delete_after_s))
        # The prior's position parts are replaced by the first detection (and R); velocity ~ N(0, σv²).
        sv2 = float(cfg.filter.initial_speed_sigma) ** 2
        prior = GaussianState(np.zeros((4, 1)), np.diag([0.0, sv2, 0.0, sv2]))
        self._initiator = MultiMeasurementInitiator(
            prior_state=prior, measurement_model=self._measurement,
            deleter=UpdateTimeDeleter(time_since_update=timedelta(seconds=cfg.lifecycle.init_delete_after_s)),
            data_associator=self._associator, updater=self._updater, min_points=int(cfg.lifecycle.init_min_points))
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
            xy = self.detect(cid, frame_image(frame))
            points.append(xy)
            groups.append(np.full(len(xy), k))
        xy = np.concatenate(points) if points else np.zeros((0, 2))
        xy = merge_points(xy, np.concatenate(groups) if groups else np.zeros(0, int), self.config.detection.merge_distance_m)
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
        out = [p.track() for p in self.position_map
               if p.id in ours and (self.config.lifecycle.report_coasting or "coasting" not in p.flags)]
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
            updated = isinstance(track.state, self._Update)
            missed = 0
            for state in reversed(track.states):
                if isinstance(state, self._Update):
                    tr.last_seen = (state.timestamp - _EPOCH).total_seconds()
                    break
                missed += 1
            tr.counters["missed"] = missed
            tr.score = 1.0 if updated else 0.0
            tr.mode = "tracking"
            if updated:
                tr.flags.discard("coasting")
            else:
                tr.flags.add("coasting")
