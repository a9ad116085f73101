"""Settings of depth along one camera's line of sight: the feet anchor (:mod:`.feet`) and the fusion
of every cue (:mod:`.depth`); sections of :class:`~worldtrack.trackers.ellipsoid.config.EllipsoidConfig`,
kept apart so the two stay light (``from worldtrack.trackers.ellipsoid.config import FeetConfig`` still works).
"""

from __future__ import annotations

from typing import ClassVar

from pydantic import Field

from worldtrack.config import Section


class FeetConfig(Section):
    """Depth from the feet: after matching, a person seen whole and alone moves along the line of
    sight towards their feet (:mod:`worldtrack.trackers.ellipsoid.feet`)."""

    path: ClassVar[str] = "ellipsoid.feet"

    anchor: bool = Field(
        False, description="move people one camera alone shows towards their feet (or the top of the head) along its "
        "line of sight; off by default: it costs PETS 2009 MOTA (issue 37); ellipsoid.depth.fuse weighs all the cues")
    sigma_m: float = Field(0.1, gt=0, description="σ of the feet's place along the line of sight, m (a shoe's length)")
    head_fallback: bool = Field(True, description="with anchor: where the feet are not trusted, the top of the head places the person")
    head_clear: bool = Field(False, description="with anchor: the head only when clear of others and of the region's top (head_clear.py)")
    pixel_sigma_px: float = Field(0.0, ge=0, description="with > 0, the feet's σ also holds this many pixels' floor span (feet_pixel.py)")
    centre_offset_m: float = Field(0.0, ge=0, description="with anchor: the person stands this far beyond the lowest "
                                   "point of their silhouette along the line of sight, m (trackers/ellipsoid/toes.py)")
    footprint: bool = Field(False, description="with anchor: the person stands beyond the lowest point of their silhouette by "
                            "where this camera sees a foot model's lowest point (anchor_footprint.py); replaces centre_offset_m")
    ray_band_share: float = Field(
        0.0, ge=0, le=1, description="with anchor, > 0: the feet are not used where another person's ellipse box reaches "
        "their columns from this share of the person's box height above them down to them (someone just behind or "
        "in front on the line of sight, anchor_gates.py); 0 = off (0.1 with footprint and obstacle_clear: PETS 8 starts IDF1 "
        "0.804 -> 0.842, switches 5.1 -> 4.2, with height_sigmas 3 too 0.858, 1.6 (main 0.830, 2.75); one "
        "camera held-out 420-439 0.457 -> 0.438, -0.019 +- 0.017, issue 37)")
    obstacle_clear: bool = Field(
        False, description="with anchor: the feet are not used where an obstacle nearer than them covers a pixel "
        "beside or below them (the window half the person's ellipse wide each side; the silhouette's bottom may be "
        "the obstacle's edge, anchor_gates.py); false: the one pixel below the feet is tested (with footprint, paper_kato "
        "T2 (a) feet hidden, through, 160 / 640: 0.260 / 0.140 -> 0.135 / 0.071 m = the anchor off, issue 37)")
    height_sigmas: float = Field(
        0.0, ge=0, description="with anchor, > 0: once the height is measured, the feet count only where the height "
        "read above them is within this many times one measurement's scatter of the person's height (at most "
        "height_match_m; anchor_gates.py); 0 = height_match_m alone (3 cost one camera held-out 420-439 0.438 -> 0.389 "
        "with the other gates, issue 37: too strict)")
    ellipse_sigma_m: float = Field(0.3, ge=0, description="uncertainty of the matched ellipse's place along the line of sight, m")
    height_match_m: float = Field(0.3, ge=0, description="the feet count only where the head's ray above them is "
                                  "this close to the person's height, m (floor-coloured legs end silhouettes at the waist)")
    height_sigma_m: float = Field(
        0.1, gt=0, description="where the feet are not to be trusted, the top of the head places the person at their "
        "height, uncertain by this much while it is not measured, m (people's heights scatter by 0.1 m)")
    measured_height_sigma_m: float = Field(
        0.03, gt=0, description="the same once 3 height measurements are in, m (their scatter; with depth.fuse, the "
        "least σ of a measured height)")
    min_px: int = Field(40, ge=0, description="only people at least this tall in the image, px")


class AnchorHeightConfig(Section):
    """How tight ``feet.height_sigmas``'s gate is: the height read above the feet against the person's
    height (:func:`worldtrack.trackers.ellipsoid.anchor_gates.height_gate_m`)."""

    path: ClassVar[str] = "ellipsoid.anchor_height"

    scatter_floor_m: float = Field(
        0.02, gt=0, description="the least scatter of one height measurement the gate assumes, m (0.02 m with 3 "
        "sigmas is a 0.06 m gate; 0.04 lost PETS start 1 IDF1 0.884 -> 0.810, issue 37)")
    min_samples: int = Field(
        3, ge=3, description="the gate only once this many height samples are in (a settled height); before, "
        "feet.height_match_m (10 lost PETS start 0 IDF1 0.849 -> 0.815, 1 -> 9 switches, issue 37)")


class DepthConfig(Section):
    """Depth along one camera's line of sight from every cue, each weighed by its σ
    (:mod:`worldtrack.trackers.ellipsoid.depth`); the feet's and the head's σ are ``ellipsoid.feet``'s."""

    path: ClassVar[str] = "ellipsoid.depth"

    fuse: bool = Field(
        False, description="place people one camera alone shows along its line of sight by the inverse-variance mean "
        "of the ellipse, the prediction, the feet (where the legs are foreground) and the top of the head; off by "
        "default (issue 37: helps one oblique camera, not measured to be harmless in crowds and PETS)")
    prior_speed_mps: float = Field(
        1.5, gt=0, description="σ of the constant-velocity prediction along the line of sight is this times the "
        "frame interval, m/s (the velocity prior: no 0.6 m jump in 0.1 s)")
    weak_sigma_m: float = Field(
        0.6, gt=0, description="σ of the matched ellipse's place along the line of sight where its evidence is weak "
        "(legs not foreground, or others cover the person), m")
    legs_min_share: float = Field(
        0.5, ge=0, le=1, description="the feet count only where at least this share of the labelled pixels below the "
        "knees is foreground (not shadow-like)")
    remeasure_after_encounter: bool = Field(
        False, description="drop a person's height samples once others stop covering them: the height is measured "
        "afresh, not carried through a crossing (with or without depth.fuse; with feet.anchor and height.prior_sigma_m "
        "0.1, heights within 3 cm 67 -> 84 of 97 on held-out line-of-sight seeds, issue 37)")
    max_along_speed_mps: float = Field(
        0.0, ge=0, description="when > 0, a tracked person one camera alone shows stays within this speed times the "
        "frame interval of their last place along its line of sight, m/s (depth_step.py: one frame's evidence may be "
        "a near person's feet; 0 = off; 2 m/s did not help on line-of-sight seeds 410/415)")
    head_when_covered: bool = Field(
        False, description="a person one camera alone shows, covered there by others (the feet anchor silent), with a "
        "measured height, moves towards the point under their head where it is clear of the others (depth_hold.py); "
        "off: with the best one-camera opt-in, line of sight dev 0.759 -> 0.779, held-out 0.771 -> 0.796, new seeds "
        "460-479 0.801 -> 0.795 (issue 37)")
