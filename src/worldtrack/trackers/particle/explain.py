"""Explaining away (worldtrack's, not in seed 004): the tracked objects' boxes as the filters read them.

A pixel inside another tracked object's image box reads as background, so a tracking filter cannot
take over its neighbour's pixels and a detection filter sees only what no track explains; where that
object stands nearer to the camera the pixel reads as occluded (no evidence), so a person walking
behind another is neither penalised nor pushed off (``particle.explain``). Per frame:

* for the tracking filters (``filters="all"``, two or more of them): each filter's box at its
  particles' mean, the owner images and the occluder layers (:meth:`Explainer.tracking`);
* for the detection filters (``filters`` not ``none``): every track's box at its updated place,
  stretched along the line of sight (``exclusion_depth_m``), and the boxes of objects that just
  left through an exit (:meth:`Explainer.detection`).

The per-camera images are reused frame to frame (a fresh 640×480 image costs more in page faults
than its boxes cost to fill).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Mapping, Sequence

import numpy as np

from worldtrack.trackers.particle.cloud import Cloud, CloudStack
from worldtrack.trackers.particle.likelihood.boxes import Box
from worldtrack.trackers.particle.likelihood.camera import CameraLikelihood
from worldtrack.trackers.particle.likelihood.images import occluder_layers, owner_image
from worldtrack.trackers.particle.likelihood.models import FrameView
from worldtrack.trackers.particle.region import cloud_mean

if TYPE_CHECKING:
    from worldtrack.trackers.base import Person
    from worldtrack.trackers.particle.config import ParticleConfig


class Explainer:
    """The boxes of the tracked objects per camera, as the filters read past them.

    Parameters
    ----------
    cfg : ParticleConfig — its ``explain`` section
    cameras : {camera_id: CameraLikelihood}
    """

    def __init__(self, cfg: "ParticleConfig", cameras: Mapping[str, CameraLikelihood]):
        e = cfg.explain
        self.cameras = cameras
        self.for_tracking, self.for_detection = e.filters == "all", e.filters != "none"
        self.occlusion = e.occlusion
        self.margin, self.depth = e.box_margin_m, e.exclusion_depth_m
        self._layers: dict = {}          # per camera, the occluder layers reused frame to frame
        self._owners: dict = {}          # per camera, the owner image reused frame to frame and its boxes

    def boxes(self, xy: np.ndarray, persons: Sequence["Person"], depth: float = 0.0) -> dict[str, list[Box | None]]:
        """Per camera, the image boxes (``box_margin_m``) of ``persons`` standing at ``xy`` (K, 2),
        stretched by ``depth`` (m) along the line of sight."""
        xy = np.array(xy, dtype=float).reshape(-1, 2)
        widths = np.array([p.width for p in persons], dtype=float)
        heights = np.array([p.height for p in persons], dtype=float)
        return {cid: cl.boxes(xy, widths, heights, self.margin, depth) for cid, cl in self.cameras.items()}

    def owner_images(self, images: Mapping[str, np.ndarray], boxes: Mapping[str, list]) -> dict[str, np.ndarray]:
        """Per camera, :func:`~.likelihood.images.owner_image` of ``boxes[camera_id]``, in one image per
        camera reused frame to frame (valid until the next call)."""
        out = {}
        for cid, img in images.items():
            buf, previous = self._owners.get(cid, (None, ()))
            out[cid] = owner_image(img.shape[:2], boxes[cid], buf, previous)
            self._owners[cid] = (out[cid], list(boxes[cid]))
        return out

    def tracking(self, frame: FrameView, clouds: Sequence[Cloud], persons: Sequence["Person"],
                 stack: CloudStack) -> tuple[FrameView, np.ndarray | None]:
        """The frame as the tracking filters ``clouds`` read it (each filter's box at its particles'
        mean; a lone filter has nothing to explain away), and those means (F, 2) if computed."""
        if not self.for_tracking or len(clouds) < 2:
            return frame, None
        centres = cloud_mean(stack.stacked(clouds, "xyz")[:, :, :2])
        boxes = self.boxes(centres, persons)
        owners = self.owner_images(frame.images, boxes)
        occluders = None
        if self.occlusion:
            occluders = {cid: occluder_layers(img.shape[:2], boxes[cid], self.cameras[cid].distances(centres),
                                              self._layers.get(cid))
                         for cid, img in frame.images.items()}
            self._layers.update(occluders)
        return FrameView(frame.images, owners, boxes, occluders, frame.colour), centres

    def detection(self, frame: FrameView, xy: np.ndarray, persons: Sequence["Person"]) -> FrameView:
        """The frame as the detection filters read it: past the boxes of ``persons`` at ``xy`` (K, 2)
        (tracks at their updated places and objects that just left), stretched along the line of sight."""
        if not self.for_detection:
            return FrameView(frame.images, colour=frame.colour)
        boxes = self.boxes(xy, persons, self.depth)
        return FrameView(frame.images, self.owner_images(frame.images, boxes), colour=frame.colour)


__all__ = ["Explainer"]
