"""The tracking-by-detection baseline (MOG2 blobs, floor points, Stone Soup), for comparison.

* :mod:`~worldtrack.trackers.blobs.config` — :class:`BlobConfig`, by step;
* :mod:`~worldtrack.trackers.blobs.detection` — foreground, morphology, foot points, fusion of cameras;
* :mod:`~worldtrack.trackers.blobs.tracker` — :class:`BlobTracker`, the Stone Soup loop.
"""

from worldtrack.trackers.blobs.config import BlobConfig
from worldtrack.trackers.blobs.detection import merge_points
from worldtrack.trackers.blobs.tracker import BlobTracker

__all__ = ["BlobConfig", "BlobTracker", "merge_points"]
