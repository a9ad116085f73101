"""What the likelihood reads of each camera's frame: the foreground's labels, cast shadows judged.

Per camera and frame, from its foreground model (the :class:`~worldtrack.foreground.Foreground`
protocol, whose threshold is the paper's γ): the labels 0 background, 1 object, 2 no evidence —
every change counted as object (``shadows="object"``, the paper's F > γ), or with shadow-like
changes on the floor judged by texture (:func:`~worldtrack.foreground.shadows.read_shadows`) and the
shadows read as background or as no evidence — and what the likelihood reads of them
(:meth:`~.models.Likelihood.image`: the labels, or F where they say object for the point).
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from worldtrack.errors import InputError
from worldtrack.foreground import Foreground
from worldtrack.foreground.shadows import floor_pixels, read_shadows
from worldtrack.foreground.texture import grey
from worldtrack.scene.model import Scene
from worldtrack.trackers.base import frame_image
from worldtrack.trackers.particle.likelihood.models import FrameView, Likelihood


class FrameLabels:
    """Turns a bundle of frames into the :class:`~.models.FrameView` the likelihood reads.

    Parameters
    ----------
    scene : Scene
    foregrounds : {camera_id: Foreground}
    shadows : {"background", "unknown", "object"} — what a judged cast shadow reads as (object: shadows
        are not set apart, every change is object)
    likelihood : Likelihood — what it reads of the labels
    colour : bool — keep the BGR frames for the colour term

    Attributes
    ----------
    masks : {camera_id: (H, W) uint8} — this frame's labels (for overlays)
    """

    def __init__(self, scene: Scene, foregrounds: Mapping[str, Foreground], shadows: str,
                 likelihood: Likelihood, colour: bool):
        self.foregrounds, self.likelihood, self.colour = dict(foregrounds), likelihood, colour
        self.cameras = {cid: scene.camera(cid) for cid in self.foregrounds}
        self.shadow_as = {"background": 0, "unknown": 2, "object": None}[shadows]
        self.floor: dict[str, np.ndarray] = {}
        self._grey: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        if self.shadow_as is not None:
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
            labels = fg.labels(image)
            if self.shadow_as is None:
                hit = (labels != 0).astype(np.uint8)
            else:
                background = fg.background_image()
                if background is None:                      # an adaptive model before its first frame
                    hit = labels.astype(np.uint8)
                else:
                    hit = read_shadows(labels, image, background, self.floor[cid], self.shadow_as,
                                       self._grey_of(cid, background))
            self.masks[cid] = hit
            if self.colour:
                colour[cid] = image
            F = fg.difference(image) if self.likelihood.reads_difference else None
            images[cid] = self.likelihood.image(hit, F)
        return FrameView(images, colour=colour)

    def _grey_of(self, cid: str, background: np.ndarray) -> np.ndarray:
        """The grey levels of a camera's background image, kept while it is the same image."""
        held = self._grey.get(cid)
        if held is None or held[0] is not background:
            held = (background, grey(background))
            self._grey[cid] = held
        return held[1]


__all__ = ["FrameLabels"]
