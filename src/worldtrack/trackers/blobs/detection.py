"""Steps 1–4 of the blobs baseline: foreground and morphology per camera, blobs → foot points on the
floor, and the fusion of the cameras' points."""

from __future__ import annotations

import math
from typing import Any

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
from worldtrack.trackers.blobs.config import BlobConfig


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


class CameraDetector:
    """One camera's foreground, morphology and blob → floor point step."""

    def __init__(self, camera: Camera, foreground: Any, scene: Scene, config: BlobConfig):
        self.camera = camera
        self.scene = scene
        self.config = config
        if isinstance(foreground, AdaptiveBackground):
            self.foreground = foreground
        else:
            rate = config.foreground.learning_rate if config.foreground.learning_rate is not None else 1.0 / config.foreground.mog2_history
            self.foreground = AdaptiveBackground("mog2", history=config.foreground.mog2_history, shadows=config.foreground.detect_shadows,
                                                 background=getattr(foreground, "background", None),
                                                 learning_rate=rate, open_px=0,
                                                 var_threshold=config.foreground.mog2_var_threshold)
        self.open_kernel = _disc(config.foreground.open_px)
        self.close_kernel = _disc(config.foreground.close_px)

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
        for area, (x0, y0, w, h), _, blob in blobs(mask, cfg.detection.min_area_px):
            if y0 + h >= cam.height:
                continue  # bottom on the border: feet cut off
            if cfg.detection.foot_point == "bottom":
                # Mean column of the blob's own pixels in its lowest rows.
                u = x0 + np.nonzero(blob[h - max(1, int(round(cfg.detection.foot_band * h))):])[1].mean()
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
        if len(xy) and cfg.detection.min_area_fraction > 0:
            ok = area >= cfg.detection.min_area_fraction * self.expected_area(xy)
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


__all__ = ["CameraDetector", "merge_points"]
