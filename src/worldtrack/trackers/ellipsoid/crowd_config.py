"""Settings for crowds one camera sees (:mod:`worldtrack.trackers.ellipsoid.prediction`,
:mod:`~worldtrack.trackers.ellipsoid.coast`); a section of
:class:`~worldtrack.trackers.ellipsoid.config.EllipsoidConfig`, kept apart so the two stay light.

>>> CrowdConfig().predict_along_ray
1.0
"""

from __future__ import annotations

from typing import ClassVar

from pydantic import Field

from worldtrack.config import Section


class CrowdConfig(Section):
    """People one camera alone shows, in a crowd: what the motion between frames may trust."""

    path: ClassVar[str] = "ellipsoid.crowd"

    predict_along_ray: float = Field(
        1.0, ge=0, le=1, description="share of the velocity along the line of sight the prediction uses for a person "
        "one camera alone shows (across it: all). One camera places people worst along its ray, and a slide of the "
        "match, read as velocity, carried tracks on: 1 = the full velocity, as before (default); 0 = across the ray "
        "only: for dense crowds (one-camera crowd of 50, held-out seeds 103-108 started on everyone: 11.7 -> 17.2 "
        "of 50 held), not sparse scenes, where walkers along the ray need it (PETS 2009 MOTA 0.927 -> 0.804)")
    predict_along_ray_measured: bool = Field(
        False, description="the prediction keeps, of the velocity along a lone camera's line of sight, only the share "
        "measured while the person was clear of others (own_share >= clear_own_share: one camera sees their "
        "silhouette's ends, so their depth) - the same running average as the velocity's; a walker clear before a "
        "crossing keeps their velocity, a velocity made of slides in a merged crowd is dropped (times "
        "predict_along_ray; off by default)")
    clear_own_share: float = Field(
        0.5, ge=0, le=1, description="a person counts as clear of others when at least this share of their visible "
        "pixels is theirs alone (as the reported 'occluded' mode)")
    coast_behind_obstacles_s: float = Field(
        0.0, ge=0, description="a track the scene's obstacles wholly hide from a camera that has it in its image is "
        "kept this long unseen, carried by the prediction, instead of ending after end.leave_after_s as one that "
        "left the view (0 = off, the default; PETS 2009 unchanged at 2)")


__all__ = ["CrowdConfig"]
