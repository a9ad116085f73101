"""What the follower sees in one frame (seed 001 §2.3–2.4): an :class:`Observation` — candidates,
silhouettes, histograms, the white balance α reads and the camera — and two ways to make the inputs
without a depth camera's frames: candidates given as image boxes (ground truth, another detector)
and frames of the synthetic world.

>>> import numpy as np
>>> from worldtrack.follow.config import FollowConfig
>>> img = np.zeros((60, 80, 3), np.uint8); img[10:50, 30:40] = (50, 70, 160)
>>> obs = observation_from_boxes(img, np.array([[28.0, 8.0, 14.0, 44.0]]), np.array([[1.0, 2.0]]), None, FollowConfig())
>>> len(obs.candidates), round(float(obs.hists.sum()), 6)
(1, 1.0)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from worldtrack.follow.colour import histograms, normalise_colour
from worldtrack.follow.config import FollowConfig
from worldtrack.follow.planview import Candidates
from worldtrack.follow.silhouette import box_silhouettes
from worldtrack.geometry.camera import Camera
from worldtrack.trackers.base import Frame


@dataclass
class Observation:
    """What one frame shows: candidates, silhouettes (H, W) int32, histograms (N, B), the white
    balance α reads (r, b) and the camera."""

    candidates: Candidates
    silhouettes: np.ndarray
    hists: np.ndarray
    wb: tuple[float, float]
    camera: Camera


def observation_from_boxes(image: np.ndarray, boxes: np.ndarray, xy: np.ndarray, gains_rb, config: FollowConfig,
                           camera: Camera | None = None) -> Observation:
    """An :class:`Observation` whose candidates are given: floor positions ``xy`` (N, 2) metres and
    image boxes (N, 4) ``(left, top, width, height)`` pixels (e.g. ground truth, or another detector).
    ``gains_rb``: the frame's white balance (r, b) or None."""
    sil = box_silhouettes(image.shape[:2], boxes)
    n = len(xy)
    b = np.asarray(boxes, float).reshape(-1, 4)
    cands = Candidates(np.asarray(xy, float).reshape(-1, 2), np.full(n, np.nan), np.full(n, np.nan), np.zeros(n),
                       -(b[:, 1] + b[:, 3]), sil, 1)
    normalised, wb = normalise_colour(image, gains_rb, config.normalise, sil > 0)
    return Observation(cands, sil, histograms(normalised, sil, n, config), wb, camera)


def frame_from_synth(bundle, camera_id: str = "robot") -> Frame:
    """A :class:`~worldtrack.io.sources.Frame` (image, measured depth, gains) from a synthetic bundle."""
    v = bundle.views[camera_id]
    return Frame(v.image, float(bundle.time), int(bundle.frame), v.sensor_depth,
                 meta={"wb_gains": tuple(v.wb_gains)})
