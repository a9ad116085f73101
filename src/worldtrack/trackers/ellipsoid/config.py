"""Settings of the ellipsoid tracker (paper 000), one section per step of the method.

``EllipsoidConfig()`` is worldtrack's default; :meth:`EllipsoidConfig.paper` the method as published (s = 50 mm,
K = 3, every pixel, eq. 5 as printed, no prediction, no searches, fixed 1.65 m people). Durations are in seconds and
turned into frames with the real frame interval (:func:`worldtrack.trackers.lifecycle.frames_for`). Why each default
is what it is, with the measurements, is in ``benchmarks/results/tuning_ellipsoid.md``.

Light on purpose (pydantic and worldtrack.config only): the command line imports it for ``--help`` and ``--print-config``.

>>> cfg = EllipsoidConfig()
>>> cfg.match.step_m, cfg.end.leave_after_s
(0.05, 0.2)
>>> EllipsoidConfig.paper().score.kind
'paper'
>>> EllipsoidConfig(match={"step_m": -1})
Traceback (most recent call last):
...
worldtrack.errors.InputError: ellipsoid.match.step_m: expected a number > 0, got -1
"""

from __future__ import annotations

from typing import ClassVar, Literal

from pydantic import Field, model_validator

from worldtrack.config import Section, with_overrides
from worldtrack.trackers.ellipsoid.cross_view_config import CrossViewConfig
from worldtrack.trackers.ellipsoid.crowd_config import CrowdConfig
from worldtrack.trackers.ellipsoid.depth_config import AnchorHeightConfig, DepthConfig, FeetConfig
from worldtrack.trackers.ellipsoid.region_config import RegionConfig


class ScoreConfig(Section):
    """Eq. 5 and the simulated image it compares (paper 000 §4)."""

    path: ClassVar[str] = "ellipsoid.score"

    kind: Literal["symmetric", "paper"] = Field(
        "symmetric", description="eq. 5 as published ('paper'), or with the foreground no ellipse explains added to "
        "the denominator for tracked people ('symmetric': drifting off the feet costs)")
    camera_weights: Literal["current", "candidate"] = Field(
        "current", description="several cameras: weigh each camera as at the person's current place ('current'), so "
        "a candidate cannot gain by sliding out of a camera that fits badly, or at the candidate")
    fixed_pixels: bool = Field(
        False, description="with camera_weights 'current': a candidate's denominator in each camera also counts the "
        "pixels its current place counts and it does not, so a camera that sees a sliver of the person past a "
        "nearer one cannot push them away by shrinking the sliver (issue 37; off: as before)")
    target_pixels: int = Field(
        1500, ge=0, description="pixels visited per candidate set, on a stride (0 = every pixel, as published); "
        "keeps the cost independent of the image size")
    ring_px_160: float = Field(
        5.0, gt=0, description="width of the -1 ring at 160x120, px (paper: 5), scaled with the image's linear size")
    ring_fraction: float = Field(
        2.0, ge=0, description="the ring is at most this fraction of the ellipse's semi-minor axis (0 = always the "
        "scaled width, as published): a far, small person gets a ring no wider than itself")
    min_depth_m: float = Field(0.1, ge=0, description="ellipsoids nearer than this to a camera's image plane are not drawn, m")


class MatchConfig(Section):
    """The matching rounds: 9 candidates per person, K rounds, coarse to fine; the motion between frames."""

    path: ClassVar[str] = "ellipsoid.match"

    step_m: float = Field(0.05, gt=0, description="candidate step s, m (paper: 50 mm)")
    iterations: int = Field(3, ge=1, description="rounds over all people per frame (paper: K = 3)")
    adaptive_step: bool = Field(
        True, description="halve the step when 'stay' wins, double it (to max_step_m) when still moving after K "
        "rounds: fast walkers are followed and the final place is finer than the grid")
    min_gain: float = Field(0.002, ge=0, description="with the adaptive step, a move must raise E by this much "
                            "(smaller gains are noise and count as 'stay')")
    min_step_m: float = Field(0.025, gt=0, description="smallest adaptive step, m")
    max_step_m: float = Field(0.4, gt=0, description="largest adaptive step, m")
    max_iterations: int = Field(6, ge=1, description="cap on rounds with the adaptive step")
    predict: bool = Field(True, description="constant-velocity prediction before matching")
    velocity_smoothing: float = Field(0.5, ge=0, le=1, description="weight of each frame's velocity measurement (0..1)")
    max_speed_mps: float = Field(3.0, gt=0, description="velocities are clipped to this speed (a running person), m/s")
    velocity_along_ray: float = Field(1.0, ge=0, le=1, description="velocity_smoothing's share along the line of sight "
        "of the one camera that showed a person (1 = all, the default; PETS 2009 at 0.4: 0.251 -> 0.238 m, MOTA 0.926 -> 0.912)")
    velocity_sure_sigma_m: float = Field(0.0, ge=0, description="velocity_smoothing's share along the line of sight "
        "follows how well E places the person there: (this / the along-ray sigma)^2, at most 1; 0 = off (issue 37)")
    rounds: Literal["compiled", "python"] = Field("compiled", description="the compiled rounds, or their readable Python reference (same tracks, slower)")

    @model_validator(mode="after")
    def _steps_in_order(self) -> "MatchConfig":
        if self.min_step_m > self.max_step_m:
            raise ValueError(f"min_step_m: expected ≤ max_step_m ({self.max_step_m}), got {self.min_step_m}")
        return self


class BirthConfig(Section):
    """Where new people come from: foreground the simulation does not explain."""

    path: ClassVar[str] = "ellipsoid.births"

    where: Literal["anywhere", "entry", "none"] = Field(
        "anywhere", description="new people appear anywhere in view, only in the scene's entry regions (and on the "
        "first frame), or never (tracks only from --init)")
    min_blob_fraction: float = Field(
        0.25, ge=0, description="an unexplained blob proposes a person when its area is this share of the area a "
        "person standing there would have")
    min_separation_m: float = Field(
        0.4, ge=0, description="no person is proposed, kept in capture, or rescued onto a place this close to "
        "another, m (two bodies' centres are rarely nearer)")
    search_m: float = Field(
        1.0, ge=0, description="a new person is placed by a grid search this far along the proposing camera's line "
        "of sight, m (0 = start at the foot point, as the paper's capture does)")
    people_occlude: bool = Field(
        False, description="a blob whose top stops against somebody already known (their ellipse) is a person "
        "whose upper body that ellipse covers: the blob's feet place them, and it need only be min_blob_fraction "
        "of the share of the person it shows (two people on one camera's line of sight; crowd 10 MOTA dev seeds "
        "20-39 0.920 -> 0.924, held-out 140-159 0.932 -> 0.927, never-used 360-399 0.918 -> 0.921: off; false: the "
        "blob's top is the head, as before)")


class RescueConfig(Section):
    """The rescue search along the lines of sight: a track stuck at a second peak of E jumps back."""

    path: ClassVar[str] = "ellipsoid.rescue"

    search_m: float = Field(
        1.5, ge=0, description="search each seeing camera's line of sight this far, m (0 = never, as published)")
    gain: float = Field(0.08, ge=0, description="a place must score E higher by this much to be taken")
    every_s: float = Field(
        1.0, ge=0, description="every person is searched this often, s, besides failing tracks (0 = only failing "
        "tracks)")
    retry_s: float = Field(
        0.3, ge=0, description="after a search that found nothing, a failing track waits this long before the "
        "next, s")


class ConfirmConfig(Section):
    """Capture mode: when a proposed person becomes a tracked one (paper 000 §5.2)."""

    path: ClassVar[str] = "ellipsoid.confirm"

    capture_threshold: float = Field(
        0.7, description="E (capture mode) above which a person is confirmed at once (paper: 0.7)")
    symmetric_threshold: float = Field(
        0.3, description="with the symmetric score: E (capture mode) a person must hold for held_s to be "
        "confirmed; an articulated body covers only 30-80 % of its ellipse")
    held_s: float = Field(0.3, ge=0, description="time the capture tests must hold in a row, s")
    within_s: float = Field(1.0, ge=0, description="a person not confirmed within this time of being proposed is dropped, s")
    views: int = Field(
        2, ge=0, description="a person passing the capture tests while at least this many cameras show their own "
        "foreground is confirmed at once (0 = never)")
    weak_threshold: float = Field(
        0.0, ge=0, description="when > 0, a captured person whose E stays above this (below symmetric_threshold) "
        "for weak_held_s while two cameras show their own pixels with support >= weak_support is confirmed (a body "
        "the foreground labels only in part; 0 = off)")
    weak_support: float = Field(0.35, ge=0, le=1, description="... with at least this support, ...")
    weak_held_s: float = Field(0.8, ge=0, description="... held this long in a row, s (below within_s)")


class SupportConfig(Section):
    """How much foreground a person must explain to be confirmed and kept (see the support module)."""

    path: ClassVar[str] = "ellipsoid.support"

    min_support: float = Field(
        0.25, ge=0, le=1, description="share of a person's own pixels (visible, nobody else's) that must be "
        "foreground; below it a track is failing, and a captured person is not confirmed")
    min_own_share: float = Field(
        0.25, ge=0, le=1, description="a young or captured person whose visible pixels are more than 1 - this "
        "covered by others duplicates them")
    min_evidence: float = Field(
        0.2, ge=0, le=1, description="a tracked person is failing when no camera shows this share of its ellipse as "
        "own foreground or explained by others (past the border, on empty floor)")
    min_seen_share: float = Field(
        0.3, ge=0, le=1, description="a captured person is confirmed only once some camera shows this share of its "
        "ellipse (a sliver at the border fits anything)")
    empty_support: float = Field(
        0.1, ge=0, le=1, description="a failing track with support below this (its own pixels nearly all floor) "
        "counts double toward end.lost_after_s (0 = never)")
    obstacles_explain: bool = Field(
        True, description="pixels a scene obstacle hides count as explained in min_evidence, as those another "
        "person covers do, and min_seen_share is of what the obstacles leave in view (a person behind a sign "
        "shows only head and legs; PETS 2009 MOTA +0.019 over 8 start frames, crowd 10 and paper_kato unchanged; "
        "false: before issue 37)")
    obstacles_confirm: bool = Field(
        True, description="with obstacles_explain, min_seen_share is of what the obstacles leave in view rather "
        "than of the whole ellipse (false: obstacles explain pixels in min_evidence only: crowd 50 MOTA +0.020, "
        "but PETS 2009 -0.002 over 8 start frames, the person behind the sign unconfirmed, and the one-camera "
        "20-person crowd with pillars 0.437 -> 0.363; issue 37)")


class EndConfig(Section):
    """When a person's track ends: evidence gone, left every view, or a duplicate."""

    path: ClassVar[str] = "ellipsoid.end"

    keep_score: float = Field(
        0.2, description="with the paper's score: a tracked person whose E stays below this for lost_after_s ends")
    lost_after_s: float = Field(1.0, ge=0, description="time a track may fail in a row before it ends, s")
    young_s: float = Field(
        3.0, ge=0, description="a track younger than this that lives inside someone else's silhouette is a "
        "duplicate, s")
    leave_after_s: float = Field(
        0.2, ge=0, description="time unseen by every camera on the map before a track ends, s")
    merge_distance_m: float = Field(0.25, ge=0, description="two tracks closer than this are duplicates, m")
    merge_after_s: float = Field(0.3, ge=0, description="time two tracks must stay that close before the younger ends, s")


class HeightConfig(Section):
    """Measuring each person's height where a camera sees them whole and alone (the paper fixes 1.65 m)."""

    path: ClassVar[str] = "ellipsoid.height"

    measure: bool = Field(
        True, description="measure heights: a wrong model height puts an oblique camera's person at the wrong depth")
    range_m: tuple[float, float] = Field((1.3, 2.1), description="plausible heights (min, max), m")
    samples: int = Field(25, ge=1, description="the height is the median of the last this many measurements")
    deadband_m: float = Field(
        0.05, ge=0, description="the measured height replaces the default only when it differs by more than this, m "
        "(the measurement's own scatter would add depth error)")
    min_px: int = Field(
        60, ge=0, description="measure in one view only where the person is at least this tall, px, and seen at "
        "more than 45 degrees from the vertical")
    prior_sigma_m: float = Field(
        0.0, ge=0, description="when > 0, replaces deadband_m: the height is the precision-weighted mean of the default "
        "(people's heights scatter by this much about it, m) and the measurements' median (its own standard error)")
    ray_gap_m: float = Field(
        0.03, ge=0, description="head rays of several cameras give a height only when each passes this close to "
        "their nearest common point, m (else some view took another head for this one's)")
    depth_offset_m: float = Field(
        1.0, ge=0, description="in one view, the feet found may be this far from the track along the line of "
        "sight, m (0.4 m across it)")
    prefer_large: bool = Field(
        False, description="once samples are in, keep measuring and keep the samples from the views that show the "
        "person largest (a pixel of a far view is centimetres of height; false: the first samples are final; "
        "PETS 2009 over 8 start frames: mean error 0.253 -> 0.250 m but MOTA 0.926 -> 0.919, issue 37)")
    keep_with_id: bool = Field(
        False, description="a person given a lost id back keeps the height samples measured under it (the "
        "kept_heights module; false: measured again from scratch; PETS 2009 over 8 start frames MOTA 0.926 -> "
        "0.916, mean error 0.253 -> 0.265 m: ids given back to somebody else carry a wrong height, issue 37)")
    reset_sigmas: float = Field(
        0.0, ge=0, description="when > 0, keep measuring and start a person's height samples over when reset_after "
        "measurements in a row are more than this many sigma (robust spread, >= 1.5 cm) from their median: a track "
        "handed over to somebody else keeps the first person's height otherwise (the height_reset module; dev "
        "400-419, best one-camera recipe: 3 sigma x 3 / x 6: heights within 3 cm 83 -> 82 / 84 of 98, MOTA 0.759 -> "
        "0.742 / 0.743: off)")
    reset_after: int = Field(3, ge=1, description="with reset_sigmas: disagreeing measurements in a row that start "
                                                   "the height over")

    @model_validator(mode="after")
    def _range_in_order(self) -> "HeightConfig":
        lo, hi = self.range_m
        if not 0 < lo < hi:
            raise ValueError(f"range_m: expected 0 < min < max, got {list(self.range_m)}")
        return self


class SplitConfig(Section):
    """One person or two on one line of sight, decided by rendering both (:mod:`.two_hypotheses`)."""

    path: ClassVar[str] = "ellipsoid.split"

    enabled: bool = Field(
        False, description="score each confirmed person alone against them shorter plus a second person behind on "
        "the camera's ray; map the second when two wins (issue 37; off: it lost, line of sight 0.740 -> 0.652 on "
        "seeds 20-39, 0.767 -> 0.649 on 150-169, PETS 0.919 -> 0.765)")
    margin: float = Field(0.05, ge=0, description="E the two must beat the best one by")
    head_ratio: float = Field(0.0, ge=0, description="test only people whose silhouette's top is a head this much "
                              "narrower than theirs would be (the two_on_ray cue; 0 = everybody)")
    held: int = Field(2, ge=1, description="frames in a row two must win, at about the same place")
    same_place_m: float = Field(0.5, gt=0, description="... the second person's places within this distance, m")
    behind_min_m: float = Field(1.2, ge=0, description="the second person (head on top) at least this much farther, m ...")
    behind_max_m: float = Field(4.0, ge=0, description="... and at most this much, m")
    step_m: float = Field(0.03, gt=0, description="... tried at heights on this step along the top's ray, m")
    far_min_m: float = Field(1.45, gt=0, description="the second person is this tall at least, m ...")
    far_max_m: float = Field(1.95, gt=0, description="... and at most, m")
    clear_m: float = Field(1.0, ge=0, description="no second person this close to anybody tracked, m")
    shorter_step_m: float = Field(0.05, gt=0, description="the first person's heights tried below theirs on this step, m")
    band_m: float = Field(
        0.25, ge=0, description="both are scored on the rows above this far below the first person's top, m: the "
        "heads tell one from two, the body's shape does not (0 = the whole silhouette)")


class IdentityConfig(Section):
    """Identity by colour: per-person colour models that undo swaps and re-identify people who come
    back (:mod:`worldtrack.trackers.ellipsoid.identity`)."""

    path: ClassVar[str] = "ellipsoid.identity"

    enabled: bool = Field(True, description="keep colour models, undo swaps and re-identify people")
    min_pixels: int = Field(
        30, ge=1, description="a body part gives colours only with at least this many foreground pixels it owns")
    update_rate: float = Field(
        0.1, gt=0, le=1, description="weight of each new isolated view in a person's colour model")
    min_updates: int = Field(5, ge=1, description="a model decides a swap only after this many isolated views")
    swap_window_s: float = Field(
        3.0, ge=0, description="two people whose ellipses met this recently are checked for a swap, s")
    swap_margin: float = Field(
        0.1, ge=0, description="the exchanged places must fit the two models better by this much (Bhattacharyya "
        "distance summed over the two people)")
    reid_s: float = Field(5.0, ge=0, description="a lost person can be re-identified this long after the track ended, s")
    reid_distance: float = Field(
        0.35, ge=0, le=1, description="largest colour distance (Bhattacharyya, mean of the body parts) of a "
        "re-identification")
    reid_margin: float = Field(
        0.05, ge=0, description="the best lost person must be nearer in colour than the next by this much")
    reid_near_m: float = Field(1.0, ge=0, description="a lost person may be found this far from where they were lost, m, ...")
    walk_speed_mps: float = Field(2.0, ge=0, description="... plus this speed times the time since, m/s")
    min_age_s: float = Field(1.0, ge=0, description="only tracks that lived this long are kept for re-identification, s")
    isolation: Literal["ring", "ellipse"] = Field(
        "ellipse", description="when a view of a person is clear enough to learn their colours from: 'ellipse' — no "
        "other person's ellipse overlaps theirs (the rings may: people walking side by side in a group, who are never "
        "clear by the ring); 'ring' — no other person's ellipse grown by the ring overlaps theirs (stricter)")


class LostConfig(Section):
    """Track management: confirmed tracks that ended, kept to give their ids back (:mod:`.reentry`)."""

    path: ClassVar[str] = "ellipsoid.lost"

    keep_s: float = Field(
        2.0, ge=0, description="a confirmed track that ended this recently gives its id back by place alone: a person "
        "who comes out from behind a pole or another person, s (0 = off)")
    near_m: float = Field(1.0, ge=0, description="... to a new person within this distance, m, ...")
    speed_mps: float = Field(1.0, ge=0, description="... plus this speed × the time since, on the lost one's heading, m/s")
    margin_m: float = Field(1.0, ge=0, description="... when no other lost person is within this much as near, m")
    colour_veto: float = Field(
        0.6, ge=0, le=1, description="... and, when both have colour models, their colour distance is at most this")
    min_age_s: float = Field(1.0, ge=0, description="only tracks that lived this long are kept, s")
    border_share: float = Field(0.9, ge=0, le=1, description="not by place to a track lost with less than this share "
                                "of its ellipse inside any camera's image: it walked out of view (:mod:`.exits`; 0 = off)")


class WarmStartConfig(Section):
    """Starting on the first frame with the people already in view."""

    path: ClassVar[str] = "ellipsoid.warm_start"

    frames: int = Field(
        10, ge=0, description="track this many first frames forwards and back before reporting frame 0 (0 = start "
        "empty, as published); skipped for learning foregrounds and hand-placed people")


class EllipsoidConfig(Section):
    """Parameters of the ellipsoid tracker, by step of the method; defaults are worldtrack's."""

    path: ClassVar[str] = "ellipsoid"
    #: The foreground threshold a run of this method gets when none is given (None: the kind's default).
    foreground_threshold: ClassVar[float | None] = None

    score: ScoreConfig = Field(ScoreConfig(), description="eq. 5 and the simulated image")
    match: MatchConfig = Field(MatchConfig(), description="the matching rounds and the motion between frames")
    births: BirthConfig = Field(BirthConfig(), description="new people from unexplained foreground")
    rescue: RescueConfig = Field(RescueConfig(), description="the search along lines of sight")
    confirm: ConfirmConfig = Field(ConfirmConfig(), description="capture mode: confirming new people")
    support: SupportConfig = Field(SupportConfig(), description="foreground a person must explain")
    end: EndConfig = Field(EndConfig(), description="when tracks end")
    height: HeightConfig = Field(HeightConfig(), description="measuring people's heights")
    warm_start: WarmStartConfig = Field(WarmStartConfig(), description="starting with the people in view")
    feet: FeetConfig = Field(FeetConfig(), description="depth from the feet along the line of sight")
    anchor_height: AnchorHeightConfig = Field(AnchorHeightConfig(), description="how tight feet.height_sigmas's gate is")
    depth: DepthConfig = Field(DepthConfig(), description="depth along one camera's line of sight from every cue")
    identity: IdentityConfig = Field(IdentityConfig(), description="identity by colour")
    lost: LostConfig = Field(LostConfig(), description="tracks that ended, kept a moment to give their ids back")
    split: SplitConfig = Field(SplitConfig(), description="one person or two on one line of sight")
    cross_view: CrossViewConfig = Field(CrossViewConfig(), description="a track one camera cannot see, searched along another's ray")
    crowd: CrowdConfig = Field(CrowdConfig(), description="people one camera alone shows, in a crowd")
    region: RegionConfig = Field(RegionConfig(), description="a region of interest on the floor: one id per visit")

    @classmethod
    def paper(cls) -> "EllipsoidConfig":
        """The method exactly as published: fixed 50 mm steps, K = 3, every pixel, eq. 5 as printed,
        no prediction, no searches, no height measurement, no warm start."""
        return with_overrides(cls(), {
            "score.kind": "paper", "score.target_pixels": 0, "score.ring_fraction": 0.0,
            "match.adaptive_step": False, "match.predict": False,
            "births.search_m": 0.0, "rescue.search_m": 0.0, "height.measure": False, "warm_start.frames": 0,
            "identity.enabled": False, "lost.keep_s": 0.0,
        }, root="ellipsoid")


__all__ = ["AnchorHeightConfig", "BirthConfig", "ConfirmConfig", "DepthConfig", "EllipsoidConfig", "EndConfig", "FeetConfig", "HeightConfig", "IdentityConfig", "LostConfig", "MatchConfig", "RescueConfig", "ScoreConfig", "SplitConfig", "SupportConfig", "WarmStartConfig"]
