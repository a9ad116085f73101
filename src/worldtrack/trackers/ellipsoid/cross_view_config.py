"""Settings of the search along the seeing camera's line of sight for a track another camera
cannot see (:mod:`worldtrack.trackers.ellipsoid.cross_view`); a section of
:class:`~worldtrack.trackers.ellipsoid.config.EllipsoidConfig`, kept apart so the two stay light.

>>> CrossViewConfig().search_m
0.0
"""

from __future__ import annotations

from typing import ClassVar

from pydantic import Field

from worldtrack.config import Section


class CrossViewConfig(Section):
    """A track one camera cannot see, looked for along another's line of sight where it can."""

    path: ClassVar[str] = "ellipsoid.cross_view"

    search_m: float = Field(
        0.0, ge=0, description="for a tracked person some camera does not show (out of its image, behind an "
        "obstacle): search each seeing camera's line of sight this far, m, for a place that camera shows and "
        "confirms (0 = off, the default; 3 measured on crowd 10: dev seeds 20-39 0.920 -> 0.936, held-out 140-199 "
        "0.914 -> 0.920 with 21 of 60 seeds worse)")
    step_m: float = Field(0.15, gt=0, description="... in steps of this, m")
    min_share: float = Field(
        0.5, gt=0, le=1, description="a camera shows a place when this share of the person's ellipse is in its "
        "image and not hidden by an obstacle")
    min_ratio: float = Field(0.3, description="the unseeing camera's own E at the new place must be at least this")
    gain: float = Field(0.0, ge=0, description="E with every camera must beat E at the current place by this")
    clear_m: float = Field(
        0.8, ge=0, description="never onto a place this close to somebody else, m: there the other camera's "
        "silhouettes of the two overlap, and what it shows is not this person's (a track pulled onto a neighbour)")

    colour_distance: float = Field(
        0.0, ge=0, le=1, description="when > 0, move a person only where the camera that did not show them shows "
        "their own colours (the identity model's, Bhattacharyya distance at most this, and nearer than anybody "
        "else's model): what that camera shows along the ray may be a neighbour (0 = off; 1.0 measured on crowd 10 "
        "dev seeds 20-39 with search_m 3: 0.936 without it -> 0.9345, veto only 0.930: not better, issue 37)")
    colour_min_pixels: int = Field(
        10, ge=1, description="... measured where each body part has at least this many foreground pixels the person's "
        "ellipse alone covers there (fewer than the identity model's own: the place may be near the image's edge)")
    colour_veto_only: bool = Field(
        False, description="... the colours only refuse a move: a person without a colour model yet, or a place where "
        "too few of their pixels are seen, moves as without the test")


__all__ = ["CrossViewConfig"]
