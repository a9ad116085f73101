"""Foreground models: what the trackers read from an image.

* :class:`StaticBackground` — the 1999 paper: ``|frame − background|`` against a fixed threshold,
  on grey levels (as published) or as a colour distance (its suggested fix for missing regions
  where a person matches the background in brightness).
* :class:`AdaptiveBackground` — OpenCV MOG2 or KNN with shadow detection (the paper's future work
  on lighting change and shadows); shadow pixels count as background.

Both give a binary mask (H, W) uint8 with 1 = foreground, and a colour difference (H, W) float32
(Euclidean RGB distance, seed 004's F) for trackers that want the grey-level evidence.
"""

from __future__ import annotations

from typing import Protocol

import cv2
import numpy as np

from worldtrack.errors import InputError


class Foreground(Protocol):
    def mask(self, image: np.ndarray) -> np.ndarray:
        """(H, W) uint8, 1 = foreground."""
        ...


def colour_distance(image: np.ndarray, background: np.ndarray) -> np.ndarray:
    """Euclidean RGB distance per pixel, ``sqrt(ΔR² + ΔG² + ΔB²)`` (seed 004, eq. 13), (H, W) float32."""
    d = image.astype(np.float32) - background.astype(np.float32)
    return np.sqrt(np.einsum("hwc,hwc->hw", d, d))


class StaticBackground:
    """Difference against a fixed background image and a fixed threshold (seed 000 §2).

    Parameters
    ----------
    background : (H, W, 3) uint8 BGR
    threshold : float
        Grey levels (0–255) for ``mode="grey"``; Euclidean RGB distance for ``mode="colour"``.
    mode : {"grey", "colour"}
    open_px : int
        Radius of a morphological opening that removes isolated noise pixels (0 = none, as published).
    """

    def __init__(self, background: np.ndarray, threshold: float = 30.0, mode: str = "grey", open_px: int = 0):
        if background.ndim != 3 or background.shape[2] != 3 or background.dtype != np.uint8:
            raise InputError(f"background: expected an (H, W, 3) uint8 colour image, got {background.shape} "
                             f"{background.dtype}")
        if mode not in ("grey", "colour"):
            raise InputError(f"foreground mode: expected 'grey' or 'colour', got {mode!r}")
        self.background = background
        self.grey = cv2.cvtColor(background, cv2.COLOR_BGR2GRAY)
        self.threshold = float(threshold)
        self.mode = mode
        self.kernel = (cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * open_px + 1, 2 * open_px + 1))
                       if open_px > 0 else None)

    def _check(self, image: np.ndarray) -> None:
        if image.shape != self.background.shape:
            raise InputError(f"frame is {image.shape[1]}x{image.shape[0]} but the background is "
                             f"{self.background.shape[1]}x{self.background.shape[0]}")

    def mask(self, image: np.ndarray) -> np.ndarray:
        self._check(image)
        if self.mode == "grey":
            diff = cv2.absdiff(cv2.cvtColor(image, cv2.COLOR_BGR2GRAY), self.grey)
            m = (diff > self.threshold).astype(np.uint8)
        else:
            m = (colour_distance(image, self.background) > self.threshold).astype(np.uint8)
        if self.kernel is not None:
            m = cv2.morphologyEx(m, cv2.MORPH_OPEN, self.kernel)
        return m

    def difference(self, image: np.ndarray) -> np.ndarray:
        """(H, W) float32 colour distance to the background."""
        self._check(image)
        return colour_distance(image, self.background)


class AdaptiveBackground:
    """OpenCV's adaptive background subtractors with shadow detection.

    Parameters
    ----------
    method : {"mog2", "knn"}
    history : int — frames of history
    shadows : bool — detect shadows (they are then treated as background)
    background : (H, W, 3) uint8, optional — an empty-scene image to start from (learned once, fully)
    learning_rate : float — −1 for OpenCV's automatic rate
    open_px : int — radius of a morphological opening after thresholding
    """

    def __init__(self, method: str = "mog2", history: int = 500, shadows: bool = True,
                 background: np.ndarray | None = None, learning_rate: float = -1.0, open_px: int = 1,
                 var_threshold: float | None = None):
        method = method.lower()
        if method == "mog2":
            self.model = cv2.createBackgroundSubtractorMOG2(history=history, detectShadows=shadows,
                                                            varThreshold=var_threshold or 16.0)
        elif method == "knn":
            self.model = cv2.createBackgroundSubtractorKNN(history=history, detectShadows=shadows,
                                                           dist2Threshold=var_threshold or 400.0)
        else:
            raise InputError(f"adaptive background: expected 'mog2' or 'knn', got {method!r}")
        self.learning_rate = learning_rate
        self.kernel = (cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * open_px + 1, 2 * open_px + 1))
                       if open_px > 0 else None)
        self.background = background
        if background is not None:
            for _ in range(5):
                self.model.apply(background, learningRate=1.0 if _ == 0 else 0.5)

    def mask(self, image: np.ndarray) -> np.ndarray:
        raw = self.model.apply(image, learningRate=self.learning_rate)
        m = (raw == 255).astype(np.uint8)  # 127 = shadow → background
        if self.kernel is not None:
            m = cv2.morphologyEx(m, cv2.MORPH_OPEN, self.kernel)
        return m

    def difference(self, image: np.ndarray) -> np.ndarray:
        """Colour distance to the model's current background image."""
        return colour_distance(image, self.model.getBackgroundImage())


def estimate_background(frames, method: str = "median") -> np.ndarray:
    """Background image from frames that contain people: per-pixel temporal median.

    Parameters
    ----------
    frames : sequence of (H, W, 3) uint8 images (a sample spread over the video)
    method : {"median"}

    Returns
    -------
    (H, W, 3) uint8
    """
    stack = np.stack(list(frames))
    if stack.ndim != 4 or stack.shape[-1] != 3:
        raise InputError(f"background estimate: expected colour frames, got shape {stack.shape[1:]}")
    if method != "median":
        raise InputError(f"background estimate: unknown method {method!r}")
    return np.median(stack, axis=0).astype(np.uint8)
