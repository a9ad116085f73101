"""The particle tracker (seed 004): 3-D particle filters with the height-column likelihood."""

from worldtrack.trackers.particle.config import ParticleConfig
from worldtrack.trackers.particle.likelihood.boxes import image_box, image_boxes
from worldtrack.trackers.particle.tracker import ParticleTracker

__all__ = ["ParticleConfig", "ParticleTracker", "image_box", "image_boxes"]
