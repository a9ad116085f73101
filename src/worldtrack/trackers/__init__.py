"""Trackers: each has ``step(frames, t) -> list[Track]`` over a shared :class:`PositionMap`.

``make_tracker(method, scene, foregrounds, **options)`` builds one by name, as the command line
and the YAML select them:

* ``ellipsoid`` — analysis by synthesis with ellipsoid people (seed 000), the default;
* ``particle`` — 3-D particle filters with the height-column likelihood (seed 004), one or more
  cameras (the likelihood multiplies over the cameras that see a particle);
* ``blobs`` — the tracking-by-detection baseline (MOG2 blobs + Stone Soup), for comparison.
"""

from __future__ import annotations

from typing import Mapping

from worldtrack.errors import InputError
from worldtrack.trackers.base import PositionMap, Track, Tracker

METHODS = ("ellipsoid", "particle", "blobs")


def make_tracker(method: str, scene, foregrounds: Mapping, preset: str = "default", **options) -> Tracker:
    """Build a tracker by name.

    Parameters
    ----------
    method : one of :data:`METHODS`
    scene : Scene
    foregrounds : {camera_id: foreground model}
    preset : "default" (with worldtrack's extensions) or "paper" (the method as published)
    options : fields of the method's config dataclass, overriding the preset
    """
    if method == "ellipsoid":
        from worldtrack.trackers.ellipsoid import EllipsoidConfig, EllipsoidTracker
        cfg_cls, tracker_cls = EllipsoidConfig, EllipsoidTracker
    elif method == "particle":
        from worldtrack.trackers.particle import ParticleConfig, ParticleTracker
        cfg_cls, tracker_cls = ParticleConfig, ParticleTracker
    elif method == "blobs":
        from worldtrack.trackers.blobs import BlobConfig, BlobTracker
        cfg_cls, tracker_cls = BlobConfig, BlobTracker
    else:
        raise InputError(f"--method: expected one of {', '.join(METHODS)}, got {method!r}")
    if preset == "paper":
        if not hasattr(cfg_cls, "paper"):
            raise InputError(f"--preset paper: the {method} tracker has no published configuration")
        config = cfg_cls.paper(**options)
    elif preset == "default":
        try:
            config = cfg_cls(**options)
        except TypeError as e:
            raise InputError(f"{method} tracker: {e}") from None
    else:
        raise InputError(f"--preset: expected 'default' or 'paper', got {preset!r}")
    return tracker_cls(scene, foregrounds, config)


__all__ = ["METHODS", "PositionMap", "Track", "Tracker", "make_tracker"]
