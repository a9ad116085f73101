"""What the likelihood reads of each camera's frame: ``F > γ`` labels, cast shadows set apart.

Per camera and frame, from its foreground model: the labels 0 background, 1 object, 2 no evidence
(:mod:`worldtrack.foreground.shadows`) — ``F > γ`` with the paper's F (``shadows="object"``), or with
cast shadows on the floor read as background or as no evidence — and what the likelihood reads of
them (:meth:`~.models.Likelihood.image`: the labels, or F thresholded at γ for the point).
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from worldtrack.errors import InputError
from worldtrack.foreground.shadows import floor_pixels, hit_image, hit_labels
from worldtrack.scene.model import Scene
from worldtrack.trackers.base import frame_image
from worldtrack.trackers.particle.likelihood.models import FrameView, Likelihood


class FrameLabels:
    """Turns a bundle of frames into the :class:`~.models.FrameView` the likelihood reads.

    Parameters
    ----------
    scene : Scene
    foregrounds : {camera_id: foreground model} — each with ``difference(image)`` (F, the Euclidean RGB
        distance); unless ``shadows == "object"`` also a background image (``.background`` or
        ``.model.getBackgroundImage()``)
    gamma : float — γ; shadows : {"background", "unknown", "object"}
    likelihood : Likelihood — what it reads of the labels
    colour : bool — keep the BGR frames for the colour term

    Attributes
    ----------
    masks : {camera_id: (H, W) uint8} — this frame's labels (for overlays)
    """

    def __init__(self, scene: Scene, foregrounds: Mapping[str, object], gamma: float, shadows: str,
                 likelihood: Likelihood, colour: bool):
        self.foregrounds, self.gamma, self.likelihood, self.colour = dict(foregrounds), gamma, likelihood, colour
        self.cameras = {cid: scene.camera(cid) for cid in self.foregrounds}
        self.shadow = {"background": 0, "unknown": 2, "object": None}[shadows]
        for cid, fg in self.foregrounds.items():
            if not callable(getattr(fg, "difference", None)):
                raise InputError(f"particle tracker: the foreground model of {cid} has no difference(image)")
            if self.shadow is not None and background_image(fg) is None:
                raise InputError(f"particle tracker: shadows={shadows!r} needs the background image of {cid}'s "
                                 "foreground model (use a static background, or set shadows='object')")
        self.floor: dict[str, np.ndarray] = {}
        if self.shadow is not None:
            walk = scene.walkable.raster(0.01)
            for cid in self.foregrounds:
                occ = scene.occlusion(cid).floor_distance if scene.obstacles else None
                self.floor[cid] = floor_pixels(scene.camera(cid), walk, occ)
        self.masks: dict[str, np.ndarray] = {}

    def read(self, frames: Mapping[str, object]) -> FrameView:
        """The frames of the tracker's cameras (``{camera_id: Frame or BGR image}``; others are left
        out) as the likelihood reads them; a frame whose size is not its camera's is an InputError."""
        images, colour = {}, {}
        self.masks = {}
        for cid, frame in frames.items():
            if cid not in self.foregrounds:
                continue
            image = frame_image(frame)
            cam = self.cameras[cid]
            if getattr(image, "shape", (0, 0))[:2] != (cam.height, cam.width):
                raise InputError(f"{cid}: frame is {image.shape[1]}x{image.shape[0]} but the camera is "
                                 f"{cam.width}x{cam.height}")
            fg = self.foregrounds[cid]
            F = fg.difference(image) if (self.likelihood.reads_difference or self.shadow is None) else None
            if self.shadow is None:
                hit = hit_image(F, self.gamma)
            else:
                hit = hit_labels(image, background_image(fg), self.gamma, where=self.floor[cid], shadow=self.shadow)
            self.masks[cid] = hit
            if self.colour:
                colour[cid] = image
            images[cid] = self.likelihood.image(hit, F)
        return FrameView(images, colour=colour)


def background_image(fg: object) -> np.ndarray | None:
    """The background image of a foreground model: ``.model.getBackgroundImage()`` or ``.background``."""
    model = getattr(fg, "model", None)
    if model is not None and hasattr(model, "getBackgroundImage"):
        bg = model.getBackgroundImage()
        if bg is not None:
            return bg
    bg = getattr(fg, "background", None)
    return bg if isinstance(bg, np.ndarray) else None


__all__ = ["FrameLabels", "background_image"]
