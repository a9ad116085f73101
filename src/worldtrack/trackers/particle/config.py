"""Configuration of the particle tracker (seed 004): :class:`ParticleConfig`, one section per step.

The paper's text (as we have it) gives the method but none of its numbers — no particle count, σ,
dz, T, γ, α or β survives in it — so every default is ours; :meth:`ParticleConfig.paper` is the
method as published (its choices of method, with our numbers), the default adds worldtrack's
extensions. How each default was chosen, with the measurements, is in
``benchmarks/results/tuning_particle.md`` (one section per setting).

Sections: ``motion`` (eqs. 1–2), ``column`` and ``likelihood`` (eqs. 7, 11–12), ``height`` (the height
state and the top edge), ``explain`` (other objects' pixels), ``appearance``, ``weights`` (eq. 8),
``tracking`` (a tracking filter's life), ``detection`` (§3.2), ``split`` and ``merge``. Durations
are in seconds and turned into frames with the real frame interval.

This module imports only pydantic and the standard library (the command line's ``--help`` and
``--print-config`` read it).

>>> cfg = ParticleConfig()
>>> cfg.motion.model, cfg.likelihood.model, cfg.column.likely_count
('state', 'column-ratio', 8)
>>> ParticleConfig.paper().likelihood.model
'column-count'
"""

from __future__ import annotations

import math
from typing import ClassVar, Literal

from pydantic import Field, StrictInt, model_validator

from worldtrack.config import Section


def _finite(default: float, description: str, **limits) -> float:
    """A field holding a finite number (NaN and ±inf are errors) with ``limits`` (ge, gt, le, lt)."""
    return Field(default, description=description, allow_inf_nan=False, **limits)


class MotionConfig(Section):
    """Prediction, eqs. 1–2 in real time: ``x_t = x_{t−1} + v·dt + w``, ``w ~ N(0, σ²·dt)``."""

    path: ClassVar[str] = "particle.motion"
    model: Literal["state", "object", "particle", "none"] = Field(
        "state", description="the velocity v: each particle's own, walking (state); the object centre's (object); "
        "each particle's last step (particle, the paper's eq. 2); none")
    noise_xy: float = _finite(0.4, "σ of the floor noise w, m/√s: a random walk whose spread per second does not "
                              "depend on the frame rate", ge=0)
    noise_z: float = _finite(0.3, "σ of the vertical noise, m/√s (point likelihood only: the column draws z afresh)",
                             ge=0)
    noise_v: float = _finite(1.0, "model state: σ of the random walk of each particle's velocity, m/s/√s", ge=0)
    velocity_spread_mps: float = _finite(0.7, "model state: σ of a new filter's particle velocities about 0, m/s "
                                         "(the object's velocity is unknown yet)", ge=0)
    coast_hidden: float = _finite(0.3, "model state: a filter whose columns have this share of samples hidden keeps "
                                  "its velocities (coasts) instead of spreading them; 0 = off", ge=0, le=1)
    smoothing: float = _finite(0.5, "model object: weight of the newest measurement in the object velocity",
                               gt=0, le=1)
    max_speed_mps: float = _finite(3.0, "velocities are clipped to this floor speed, m/s", gt=0)


class ColumnConfig(Section):
    """The height column (eqs. 11–12): points ``k·dz``, ``k = 0 … T``, above each particle."""

    path: ClassVar[str] = "particle.column"
    dz_m: float = _finite(0.1, "column step, metres", gt=0)
    max_height_m: float = _finite(1.9, "height limit of objects (§4.2), metres: T = round(max_height / dz)", gt=0)
    min_height_m: float = _finite(0.8, "a particle is likely when its column sees this much object in every camera "
                                  "that sees it, metres (lower for children, bicycles)", gt=0)
    radius_m: float = _finite(0.1, "a sample also reads the pixels this far to its left and right, metres: a thin "
                              "cylinder, so the gap between a walker's legs does not break it; 0 = a line", ge=0)
    foot_samples: StrictInt = Field(4, ge=0, description="column-ratio: samples below the floor that must read "
                                    "background (the column's floor contact)")
    head_samples: StrictInt = Field(3, ge=0, description="column-ratio: samples above the top that must read "
                                    "background (with the foot samples, a ring round the column)")
    surface_offset_m: float = _finite(0.14, "each camera's column stands this much nearer to it than the particle "
                                      "(a body's half-depth: it sees the near side of the feet), metres", ge=0)

    @model_validator(mode="after")
    def _heights(self) -> "ColumnConfig":
        if self.min_height_m > self.max_height_m:
            raise ValueError(f"min_height_m: expected at most max_height_m ({self.max_height_m} m), "
                             f"got {self.min_height_m}")
        if self.dz_m > self.max_height_m:
            raise ValueError(f"dz_m: expected at most max_height_m ({self.max_height_m} m), got {self.dz_m}")
        return self

    @property
    def likely_count(self) -> int:
        """Column samples on the object for a particle to be likely: ``⌈min_height / dz⌉``."""
        return max(1, int(math.ceil(self.min_height_m / self.dz_m - 1e-9)))


class LikelihoodConfig(Section):
    """How a particle's columns (or point) become its likelihood π (eqs. 7, 11)."""

    path: ClassVar[str] = "particle.likelihood"
    model: Literal["column-ratio", "column-count", "point"] = Field(
        "column-ratio", description="column-ratio: the likelihood ratio of an object standing there (sharp along "
        "the line of sight); column-count: π = samples on F > γ (the paper, eq. 11; γ is foreground.threshold); "
        "point: π = F at the particle "
        "(eq. 7, the paper's baseline)")
    hit_rate_object: float = _finite(0.6, "column-ratio: chance that a sample on an object reads F > γ (much of a "
                                     "body below the waist does not)", gt=0, lt=1)
    hit_rate_background: float = _finite(0.05, "column-ratio: chance that a sample on the background reads F > γ",
                                         gt=0, lt=1)
    shadows: Literal["background", "unknown", "object"] = Field(
        "background", description="cast shadows (told by colour and texture) read as background, as no evidence, "
        "or as object (the paper's F)")
    out_of_view: Literal["unknown", "background"] = Field(
        "unknown", description="a column sample out of the image reads no evidence, or background (the paper); "
        "background pushes people whose feet are below the image away from the camera")
    pixel_weights: Literal["none", "depth", "filter", "hidden"] = Field(
        "hidden", description="column-ratio: weigh samples by the image length they stand for — never, relative "
        "to 5 m, per tracking filter, or per tracking filter only where its lower columns were hidden")
    common_view: float = _finite(0.0, "column-ratio: where a tracking filter's lower columns are hidden, compare "
                                 "them on the samples this share of them see; 0 = off", ge=0, le=1)

    @model_validator(mode="after")
    def _rates(self) -> "LikelihoodConfig":
        if not self.hit_rate_object > self.hit_rate_background:
            raise ValueError(f"hit_rate_object: expected above hit_rate_background ({self.hit_rate_background}), "
                             f"got {self.hit_rate_object}")
        return self


class HeightConfig(Section):
    """Each particle's object height (a fourth state variable) and the top edge read at it."""

    path: ClassVar[str] = "particle.height"
    prior_sigma_m: float = _finite(0.05, "column-ratio: σ of the prior of a column's top about the particle's "
                                   "height, metres (it closes one camera's valley of depth–height pairs); 0 = no "
                                   "height state", ge=0)
    spread_m: float = _finite(0.1, "σ of new particles' heights about the scene's person height, metres", ge=0)
    noise: float = _finite(0.02, "random walk of the particles' heights, m/√s", ge=0)
    edge_weight: float = _finite(1.0, "weight of the top-edge terms of tracking filters (the head read to a pixel "
                                 "at the particle's height); 0 = off", ge=0)
    edge_step_m: float = _finite(0.03, "spacing of the top-edge samples, metres", gt=0)
    edge_samples: StrictInt = Field(2, ge=0, description="top-edge samples below (on the object) and as many above "
                                    "(over it) each particle's height")
    edge_explain: bool = Field(False, description="read the top-edge samples past other tracks' boxes as the "
                               "column does (measured worse on real video than the raw labels)")


class ExplainConfig(Section):
    """Explaining away: pixels in another tracked object's image box (not in the paper)."""

    path: ClassVar[str] = "particle.explain"
    filters: Literal["all", "detection", "none"] = Field(
        "all", description="which filters read another track's pixels as background: all (none can take over a "
        "neighbour), detection (the least that stops a detection filter firing again on its object), none")
    box_margin_m: float = _finite(0.05, "margin of the objects' image boxes, metres", ge=0)
    occlusion: bool = Field(True, description="explain all: a sample in the box of an object nearer to the "
                            "camera is occluded (no evidence) instead of background")
    occlusion_margin_m: float = _finite(0.3, "how much nearer (floor distance) that object must stand, metres",
                                        ge=0)
    exclusion_depth_m: float = _finite(0.5, "for detection filters a track's box also covers its object this "
                                       "much nearer and farther (one camera places depth poorly), metres", ge=0)


class AppearanceConfig(Section):
    """Each tracking filter's colours per camera (not in the paper): a penalty for foreign colours."""

    path: ClassVar[str] = "particle.appearance"
    weight: float = _finite(1.0, "weight of the colour penalty of column samples in colours the object rarely "
                            "shows (keeps a filter on its own person when two cross); 0 = off", ge=0)
    rate: float = _finite(0.1, "weight of a frame in the running colour histogram", gt=0, le=1)


class WeightsConfig(Section):
    """Weights and resampling, eq. 8."""

    path: ClassVar[str] = "particle.weights"
    power: float = _finite(0.2, "weights ∝ π^power (the paper: 1); below 1 tempers the ratio, whose samples are "
                           "not independent", ge=0)
    resampler: Literal["systematic", "stratified"] = Field(
        "systematic", description="systematic: one uniform number places all pointers, the least resampling noise; "
        "stratified: one per stratum")


class TrackingConfig(Section):
    """A tracking filter's particles and its end."""

    path: ClassVar[str] = "particle.tracking"
    particles: StrictInt = Field(500, ge=1, description="particles per tracking filter, N")
    beta: float = _finite(0.1, "β: a tracking filter ends when its share of likely particles stays at or below β",
                          ge=0, lt=1)
    end_after_s: float = _finite(0.3, "how long the share must stay ≤ β, seconds (the paper: at once, 0)", ge=0)
    exit_lookahead_s: float = _finite(0.3, "a filter in an entry region walking off the floor this far ahead, "
                                      "seconds, ends at once (it is leaving); 0 = off", ge=0)
    exit_speed_mps: float = _finite(0.3, "least speed of a filter leaving through an exit, m/s", ge=0)
    exit_hold_s: float = _finite(0.5, "an exited object's last box stays explained to the detection filters this "
                                 "long, seconds", ge=0)


class DetectionConfig(Section):
    """Detection filters (§3.2): particles scattered over where objects appear."""

    path: ClassVar[str] = "particle.detection"
    births: Literal["auto", "entry", "entry+lost", "anywhere", "none"] = Field(
        "auto", description="where detection filters scatter: entry regions (and, +lost, where a track was lost), "
        "the walkable floor in view, or nowhere; auto: entry+lost with entry regions, else anywhere")
    particles: StrictInt = Field(1000, ge=1, description="particles per detection filter")
    alpha: float = _finite(0.5, "α: a detection filter fires when its share of likely particles exceeds α",
                           gt=0, lt=1)
    reseed: float = _finite(0.2, "share of a detection filter's particles scattered afresh every frame (1: the "
                            "literal reading of §3.2)", ge=0, le=1)
    noise: float = _finite(0.15, "σ of the jitter of detection particles, m/√s", ge=0)
    entry_margin_m: float = _finite(1.0, "an entry region's filter covers the walkable floor this close to it, "
                                    "metres (people show fully near a door, not in it)", ge=0)
    entry_reach_m: float = _finite(2.0, "a door out of view is watched where its floor within this distance comes "
                                   "into view, metres; 0 = off", ge=0)
    lost_radius_m: float = _finite(1.0, "entry+lost: radius of the floor watched round a lost track, metres", ge=0)
    lost_hold_s: float = _finite(5.0, "entry+lost: how long that floor is watched, seconds; 0 = off", ge=0)
    lost_same_id: bool = Field(True, description="entry+lost: the object found again takes the lost track's id")


class SplitConfig(Section):
    """Splitting a filter whose particles became two lumps (objects that entered together and parted)."""

    path: ClassVar[str] = "particle.split"
    enabled: bool = Field(True, description="split filters on two objects, and start two tracks from a detection "
                          "filter that fires on two lumps")
    distance_m: float = _finite(0.35, "least distance between the two lumps' peaks, metres", gt=0)
    dip: float = _finite(0.5, "deepest valley between them, as a share of the lower peak", gt=0, lt=1)
    min_mass: float = _finite(0.2, "least share of the particles on each side", gt=0, lt=0.5)
    after_s: float = _finite(0.2, "how long the cloud must stay two lumps, seconds (two frames at 7–10 frames/s: "
                             "one frame of two lumps is the resampling's noise)", gt=0)


class MergeConfig(Section):
    """Merging two filters on one object: the younger ends."""

    path: ClassVar[str] = "particle.merge"
    enabled: bool = Field(True, description="end the younger of two filters that stay on one object")
    overlap: float = _finite(0.6, "their image boxes overlap by this much (of the smaller) in every camera that "
                             "sees both", gt=0, le=1)
    after_s: float = _finite(0.3, "for this long, seconds", gt=0)
    distance_m: float = Field(0.6, gt=0, description="or, while their centres stand farther apart than this on "
                              "the floor (one behind the other, as two people passing), metres (inf: boxes alone)")
    far_after_s: float = _finite(0.6, "for this long, seconds", gt=0)
    depth_m: float = Field(10.0, gt=0, description="beyond this floor distance from the nearest camera the distance "
                           "grows in proportion (one camera's depth error grows with it), metres")


class ParticleConfig(Section):
    """Parameters of :class:`~worldtrack.trackers.particle.ParticleTracker`, by step of the method."""

    path: ClassVar[str] = "particle"
    #: The foreground threshold γ a run of this method gets when none is given: paper 004's F > γ on the
    #: RGB distance, at the 25 this tracker always used (``benchmarks/results/tuning_foreground.md``).
    foreground_threshold: ClassVar[float | None] = 25.0
    #: The foreground's shadow test a default-preset run of this method gets when none is given
    #: (``foreground.shadow_test``): shadow-like pixels where the floor's pattern is gone are cloth.
    #: Floor-coloured clothes 25.5 -> 57.5 % foreground, entries better, nothing lost
    #: (``benchmarks/results/tuning_foreground.md``). The paper preset keeps "colour".
    foreground_shadow_test: ClassVar[str | None] = "evidence"
    seed: StrictInt = Field(0, description="seed of the tracker's random generator: same seed and input, same "
                            "tracks")
    motion: MotionConfig = Field(MotionConfig(), description="prediction (eqs. 1–2)")
    column: ColumnConfig = Field(ColumnConfig(), description="the height column (eqs. 11–12)")
    likelihood: LikelihoodConfig = Field(LikelihoodConfig(), description="the likelihood (eqs. 7, 11)")
    height: HeightConfig = Field(HeightConfig(), description="the particles' object heights and the top edge")
    explain: ExplainConfig = Field(ExplainConfig(), description="other objects' pixels")
    appearance: AppearanceConfig = Field(AppearanceConfig(), description="colours of each tracked object")
    weights: WeightsConfig = Field(WeightsConfig(), description="weights and resampling (eq. 8)")
    tracking: TrackingConfig = Field(TrackingConfig(), description="tracking filters and their end")
    detection: DetectionConfig = Field(DetectionConfig(), description="detection filters (§3.2)")
    split: SplitConfig = Field(SplitConfig(), description="splitting a filter on two objects")
    merge: MergeConfig = Field(MergeConfig(), description="merging two filters on one object")

    @classmethod
    def paper(cls) -> "ParticleConfig":
        """The method as published: each particle's own velocity (eq. 2), weights ∝ count (eqs. 8, 11) on
        the plain line column, shadows counted as object, samples out of view as background, no split,
        merge, colours or explaining away for tracking filters, tracks end at once, detection filters on
        the entry regions only. Numbers it does not state stay ours."""
        d = cls()
        return cls(seed=d.seed,
                   motion=d.motion.replace(model="particle"),
                   column=d.column.replace(radius_m=0.0, foot_samples=0, head_samples=0, surface_offset_m=0.0),
                   likelihood=d.likelihood.replace(model="column-count", pixel_weights="none", shadows="object",
                                                   out_of_view="background"),
                   height=d.height.replace(prior_sigma_m=0.0, edge_weight=0.0),
                   explain=d.explain.replace(filters="detection", occlusion=False),
                   appearance=d.appearance.replace(weight=0.0),
                   weights=d.weights.replace(power=1.0),
                   tracking=d.tracking.replace(end_after_s=0.0, exit_lookahead_s=0.0),
                   detection=d.detection.replace(entry_reach_m=0.0, lost_hold_s=0.0),
                   split=d.split.replace(enabled=False),
                   merge=d.merge.replace(enabled=False))


__all__ = ["AppearanceConfig", "ColumnConfig", "DetectionConfig", "ExplainConfig", "HeightConfig",
           "LikelihoodConfig", "MergeConfig", "MotionConfig", "ParticleConfig", "SplitConfig", "TrackingConfig",
           "WeightsConfig"]
