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
from worldtrack.foreground.evidence import ABOVE_FEET, SURE, EvidenceSettings, judge_by_evidence
from worldtrack.foreground.kernels import colour_labels, shadow_like
from worldtrack.foreground.texture import relabel_cloth


#: Label of a pixel that changed but may be a shadow: neither foreground nor background evidence.
UNSURE = 2
#: The tests of shadow-like changes (``StaticBackground(shadow_test=)``, ``foreground.shadow_test``).
SHADOW_TESTS = ("colour", "evidence", "evidence-background", "evidence-sure", "evidence-above-feet")
#: The evidence settings of each evidence test.
_SETTINGS = {"evidence": EvidenceSettings(), "evidence-background": EvidenceSettings(), "evidence-sure": SURE,
             "evidence-above-feet": ABOVE_FEET}

#: MOG2/KNN output (0 background, 127 shadow, 255 foreground) → labels.
_MOG = np.zeros(256, np.uint8)
_MOG[255] = 1
_MOG[127] = UNSURE


class Foreground(Protocol):
    """What trackers read of a frame, one model per camera (:data:`worldtrack.foreground.FOREGROUNDS`)."""

    #: True when ``labels``/``mask`` update a model (the answer depends on the frames seen before).
    learns: bool

    def mask(self, image: np.ndarray) -> np.ndarray:
        """(H, W) uint8, 1 = foreground."""
        ...

    def labels(self, image: np.ndarray) -> np.ndarray:
        """(H, W) uint8: 0 background, 1 foreground, 2 unsure (shadow-like)."""
        ...

    def difference(self, image: np.ndarray) -> np.ndarray:
        """(H, W) float32: colour distance to the background (paper 004's F)."""
        ...

    def background_image(self) -> np.ndarray | None:
        """(H, W, 3) uint8: the empty scene the model compares with now, if it has one."""
        ...


def _open_foreground(labels: np.ndarray, kernel: np.ndarray | None) -> np.ndarray:
    """Remove foreground specks smaller than ``kernel`` (a morphological opening of label 1), in place."""
    if kernel is not None:
        fg = labels == 1
        opened = cv2.morphologyEx(fg.astype(np.uint8), cv2.MORPH_OPEN, kernel)
        labels[fg & (opened == 0)] = 0
    return labels


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
    shadows : bool
        Treat cast shadows as background: a pixel whose colour is the background's scaled by a
        brightness ratio ``a`` in ``[shadow_min_ratio, 0.97]`` with little colour distortion
        ``‖I − a·B‖`` (Horprasert et al. 1999; what MOG2's shadow detection tests) is not
        foreground. Not in the paper, which names shadows as its main failure.
    shadow_min_ratio : float
        Darkest shadow, as a fraction of the background brightness.
    shadow_distortion : float
        Largest colour distortion of a shadow, as a fraction of ``‖B‖`` (RGB distance).
    shadow_texture_ncc : float or None
        With ``shadows``: a shadow-like pixel over textured background whose grey levels do not
        correlate with the background's (NCC at most this over a 5-pixel window) is foreground — a
        dark garment of the floor's colour hides the floor's pattern, a shadow keeps it (see
        :mod:`worldtrack.foreground.texture`). None: no texture test.
    shadow_test : {"colour", "evidence", "evidence-background"}
        With ``shadows``: ``"colour"`` leaves every shadow-like change unsure; ``"evidence"`` judges
        them (:func:`~worldtrack.foreground.evidence.judge_by_evidence`): the ones whose
        neighbourhood hides the floor's pattern, or that are darker than the frame's shadows, are
        foreground (cloth of the floor's colour); the rest stay unsure. ``"evidence-background"``:
        the same, and the ones whose neighbourhood shows the floor's pattern through are background
        (0, judged shadows), so that a silhouette that takes in its own shadow is penalised.
        ``"evidence-sure"``: ``"evidence"`` deciding only on stronger pooled evidence
        (:data:`~worldtrack.foreground.evidence.SURE`); ``"evidence-above-feet"``: ``"evidence-sure"``
        calling no cloth in the lowest band of a silhouette or below it, where contact shadows lie
        (:data:`~worldtrack.foreground.evidence.ABOVE_FEET`).
    """

    learns = False  #: a fixed background: the same frame always gives the same labels

    def __init__(self, background: np.ndarray, threshold: float = 30.0, mode: str = "grey", open_px: int = 0,
                 shadows: bool = False, shadow_min_ratio: float = 0.45, shadow_distortion: float = 0.08,
                 shadow_texture_ncc: float | None = None, shadow_test: str = "colour"):
        if background.ndim != 3 or background.shape[2] != 3 or background.dtype != np.uint8:
            raise InputError(f"background: expected an (H, W, 3) uint8 colour image, got {background.shape} "
                             f"{background.dtype}")
        if mode not in ("grey", "colour"):
            raise InputError(f"foreground mode: expected 'grey' or 'colour', got {mode!r}")
        self.background = background
        self.grey = cv2.cvtColor(background, cv2.COLOR_BGR2GRAY)
        self.threshold = float(threshold)
        if shadow_test not in SHADOW_TESTS:
            raise InputError(f"shadow test: expected one of {', '.join(map(repr, SHADOW_TESTS))}, got {shadow_test!r}")
        self.mode = mode
        self.shadow_test = shadow_test
        self.kernel = (cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * open_px + 1, 2 * open_px + 1))
                       if open_px > 0 else None)
        self.shadows = bool(shadows)
        self.shadow_min_ratio = float(shadow_min_ratio)
        self.shadow_distortion = float(shadow_distortion)
        self.shadow_texture_ncc = None if shadow_texture_ncc is None else float(shadow_texture_ncc)
        bg = background.astype(np.float32)
        self._bg = bg
        self._bg_norm2 = np.ascontiguousarray(np.maximum(np.einsum("hwc,hwc->hw", bg, bg), 1.0), np.float32)

    def shadow_mask(self, image: np.ndarray) -> np.ndarray:
        """(H, W) bool: pixels that look like the background in shadow."""
        return shadow_like(image.astype(np.float32), self._bg, self._bg_norm2, self.shadow_min_ratio,
                           self.shadow_distortion)

    def _check(self, image: np.ndarray) -> None:
        if image.shape != self.background.shape:
            raise InputError(f"frame is {image.shape[1]}x{image.shape[0]} but the background is "
                             f"{self.background.shape[1]}x{self.background.shape[0]}")

    def labels(self, image: np.ndarray) -> np.ndarray:
        """(H, W) uint8: 0 background, 1 foreground, :data:`UNSURE` (2) changed but shadow-like.

        A shadow-like change may be a cast shadow or a dark, grey garment over a grey floor;
        trackers that can should treat it as no evidence either way rather than as background.
        With ``shadow_test="evidence"`` or ``shadow_texture_ncc`` the garments that hide a textured
        floor, or are darker than the frame's shadows, are told apart (1); with
        ``"evidence-background"`` the shadows the evidence finds are background (0).
        """
        self._check(image)
        if self.mode == "grey":
            diff = cv2.absdiff(cv2.cvtColor(image, cv2.COLOR_BGR2GRAY), self.grey)
            changed = diff > self.threshold
            out = changed.astype(np.uint8)
            if self.shadows:
                out[changed & self.shadow_mask(image)] = UNSURE
        else:
            out = colour_labels(np.ascontiguousarray(image), self.background, self._bg_norm2, self.threshold,
                                self.shadows, self.shadow_min_ratio, self.shadow_distortion)
        if self.shadows and self.shadow_test != "colour":
            judged = 0 if self.shadow_test == "evidence-background" else UNSURE
            out = judge_by_evidence(out, image, self.background, _SETTINGS[self.shadow_test], candidate=UNSURE,
                                    cloth=1, shadow=judged, grey_background=self.grey)
        if self.shadows and self.shadow_texture_ncc is not None:
            relabel_cloth(out, image, self.grey, self.shadow_texture_ncc, candidate=UNSURE)
        return _open_foreground(out, self.kernel)

    def mask(self, image: np.ndarray) -> np.ndarray:
        """(H, W) uint8, 1 = foreground (shadow-like changes excluded)."""
        return (self.labels(image) == 1).astype(np.uint8)

    def difference(self, image: np.ndarray) -> np.ndarray:
        """(H, W) float32 colour distance to the background."""
        self._check(image)
        return colour_distance(image, self.background)

    def background_image(self) -> np.ndarray:
        """The fixed empty-scene image."""
        return self.background


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

    learns = True  #: every frame updates the model

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

    def labels(self, image: np.ndarray) -> np.ndarray:
        """(H, W) uint8: 0 background, 1 foreground, :data:`UNSURE` (2) shadow (MOG2/KNN's 127).

        Updates the model (one ``apply``); call once per frame.
        """
        raw = self.model.apply(image, learningRate=self.learning_rate)
        out = _MOG[raw]
        return _open_foreground(out, self.kernel)

    def mask(self, image: np.ndarray) -> np.ndarray:
        """(H, W) uint8, 1 = foreground; shadows count as background. Updates the model."""
        return (self.labels(image) == 1).astype(np.uint8)

    def difference(self, image: np.ndarray) -> np.ndarray:
        """Colour distance to the model's current background image."""
        return colour_distance(image, self.model.getBackgroundImage())

    def background_image(self) -> np.ndarray | None:
        """The model's current background image (OpenCV's estimate), or None before any frame."""
        return self.model.getBackgroundImage()
