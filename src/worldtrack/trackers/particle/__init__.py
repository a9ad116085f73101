"""The particle tracker (seed 004): 3-D particle filters with the height-column likelihood."""

from worldtrack.trackers.particle.config import ParticleConfig
from worldtrack.trackers.particle.tracker import (ParticleTracker, _mean_rows, _overlaps, _quantile_rank,  # noqa: F401
                                                  image_box, image_boxes)

__all__ = ["ParticleConfig", "ParticleTracker", "image_box", "image_boxes"]
