"""The particle tracker's configuration: sections by step, one validation path with field paths in
every error, a YAML round trip, the published preset, and the components each name chooses."""

from __future__ import annotations

import typing

import numpy as np
import pytest

from worldtrack.config import dump_yaml, from_mapping, to_mapping, with_overrides
from worldtrack.errors import InputError
from worldtrack.trackers import make_tracker, method_config
from worldtrack.trackers.particle import ParticleConfig
from worldtrack.trackers.particle.config import (DetectionConfig, LikelihoodConfig, MotionConfig, SplitConfig,
                                                 WeightsConfig)
from worldtrack.trackers.particle.likelihood.models import LIKELIHOODS, ColumnCount, ColumnRatio, Point
from worldtrack.trackers.particle.likelihood.pixel_weights import PIXEL_WEIGHTS, FilterScales, HiddenScales
from worldtrack.trackers.particle.motion import MOTIONS, ObjectVelocity, StateVelocity
from worldtrack.trackers.particle.resample import RESAMPLERS, stratified_resample

from particle_scenes import config, foregrounds, make_scene


@pytest.mark.parametrize("setting, value, message", [
    ("detection.alpha", 1.5, "particle.detection.alpha: expected a number < 1, got 1.5"),
    ("tracking.beta", -0.1, "particle.tracking.beta: expected a number ≥ 0, got -0.1"),
    ("tracking.particles", 0, "particle.tracking.particles: expected a number ≥ 1, got 0"),
    ("tracking.particles", 2.5, "particle.tracking.particles: expected a whole number, got 2.5"),
    ("column.dz_m", 0, "particle.column.dz_m: expected a number > 0, got 0"),
    ("likelihood.model", "blob", "particle.likelihood.model: expected one of 'column-ratio', 'column-count' or "
                                 "'point', got 'blob'"),
    ("column.min_height_m", 2.5, "particle.column.min_height_m: expected at most max_height_m (1.9 m), got 2.5"),
    ("weights.resampler", "multinomial", "particle.weights.resampler: expected one of 'systematic' or 'stratified'"),
    ("likelihood.hit_rate_object", 0.01, "particle.likelihood.hit_rate_object: expected above hit_rate_background"),
    ("detection.births", "lost", "particle.detection.births: expected one of"),
    ("detection.lost_radius_m", -1.0, "particle.detection.lost_radius_m: expected a number ≥ 0"),
    ("detection.lost_hold_s", float("nan"), "particle.detection.lost_hold_s: expected a finite number, got nan"),
    ("motion.noise_xy", float("inf"), "particle.motion.noise_xy: expected a finite number, got inf"),
    ("merge.distance_m", 0.0, "particle.merge.distance_m: expected a number > 0"),
    ("merge.distance_m", float("nan"), "particle.merge.distance_m: expected a number > 0, got nan"),
    ("merge.far_after_s", 0, "particle.merge.far_after_s: expected a number > 0"),
    ("merge.depth_m", 0.0, "particle.merge.depth_m: expected a number > 0"),
    ("height.edge_weight", -1.0, "particle.height.edge_weight: expected a number ≥ 0"),
    ("height.edge_samples", -1, "particle.height.edge_samples: expected a number ≥ 0"),
    ("likelihood.out_of_view", "object", "particle.likelihood.out_of_view: expected one of 'unknown' or "
                                         "'background', got 'object'"),
    ("motion.velocity", "state", "particle.motion.velocity: unknown setting (expected one of: model, noise_xy"),
    ("gamma", 30, "particle.gamma: unknown setting"),
    ("likelihood.gamma", 30, "particle.likelihood.gamma: unknown setting"),      # γ is foreground.threshold
])
def test_bad_settings_are_input_errors_naming_the_field(setting, value, message):
    with pytest.raises(InputError) as e:
        with_overrides(ParticleConfig(), {setting: value}, root="particle")
    assert message in str(e.value)
    assert "\n" not in str(e.value)


def test_a_section_built_alone_reports_its_path():
    with pytest.raises(InputError, match="^particle.split.dip: expected a number < 1, got 1.5$"):
        SplitConfig(dip=1.5)
    with pytest.raises(InputError, match="^particle.motion.max_speed_mps: expected a number > 0, got -3"):
        MotionConfig(max_speed_mps=-3)


def test_the_configuration_round_trips_through_yaml():
    import yaml

    for cfg in (ParticleConfig(), ParticleConfig.paper(), config(merge__distance_m=float("inf"), seed=7,
                                                                 likelihood__model="point")):
        text = dump_yaml(cfg)
        assert from_mapping(ParticleConfig, yaml.safe_load(text)) == cfg
        assert from_mapping(ParticleConfig, to_mapping(cfg)) == cfg
    text = dump_yaml(ParticleConfig())
    assert "likelihood:  # the likelihood (eqs. 7, 11)" in text and "  shadows: background  # cast shadows" in text
    # Every section stays small and every field says what it is.
    for name, field in ParticleConfig.model_fields.items():
        assert field.description, name
        section = type(getattr(ParticleConfig(), name))
        if hasattr(section, "model_fields"):
            assert len(section.model_fields) <= 15, name
            assert all(f.description for f in section.model_fields.values()), name


def test_the_paper_preset_is_the_method_as_published():
    paper, default = ParticleConfig.paper(), ParticleConfig()
    assert paper.motion.model == "particle" and paper.likelihood.model == "column-count"
    assert paper.weights.power == 1.0 and paper.column.radius_m == 0.0 and paper.column.foot_samples == 0
    assert paper.likelihood.shadows == "object" and paper.likelihood.out_of_view == "background"
    assert paper.explain.filters == "detection" and not paper.split.enabled and not paper.merge.enabled
    assert paper.tracking.end_after_s == 0.0 and paper.detection.lost_hold_s == 0.0
    # Numbers the paper does not state stay ours.
    assert paper.tracking.particles == default.tracking.particles and paper.column.dz_m == default.column.dz_m
    assert method_config("particle", "paper") == paper
    assert method_config("particle", "paper", {"likelihood.model": "point"}).likelihood.model == "point"
    assert default.likelihood.out_of_view == "unknown"                  # the documented default


@pytest.mark.parametrize("section, field, registry", [
    (MotionConfig, "model", MOTIONS), (LikelihoodConfig, "model", LIKELIHOODS),
    (LikelihoodConfig, "pixel_weights", PIXEL_WEIGHTS), (WeightsConfig, "resampler", RESAMPLERS)])
def test_every_name_a_setting_allows_has_a_component(section, field, registry):
    allowed = typing.get_args(section.model_fields[field].annotation)
    assert set(allowed) == set(registry.names())


def test_components_are_chosen_by_name_at_construction():
    scene = make_scene()
    fgs, _ = foregrounds(scene)
    from worldtrack.trackers.particle import ParticleTracker

    t = ParticleTracker(scene, fgs)
    assert type(t.motion) is StateVelocity and type(t.likelihood) is ColumnRatio
    assert type(t.observer.pixel_weights) is HiddenScales and t.resampling.resample is RESAMPLERS["systematic"]
    t = make_tracker("particle", scene, fgs, overrides={"motion.model": "object", "likelihood.model": "column-count",
                                                       "weights.resampler": "stratified",
                                                       "likelihood.pixel_weights": "filter"})
    assert type(t.motion) is ObjectVelocity and type(t.likelihood) is ColumnCount
    assert t.resampling.resample is stratified_resample
    # Pixel weights act on the column ratio only: another likelihood reads every sample as 1.
    assert not isinstance(t.observer.pixel_weights, FilterScales)
    t = make_tracker("particle", scene, fgs, overrides={"likelihood.model": "point"})
    assert type(t.likelihood) is Point and t.likelihood.reads_difference and not t.likelihood.column
    with pytest.raises(InputError, match="particle.motion.model: expected one of none, particle, object, state, "
                                         "got 'teleport'"):
        MOTIONS["teleport"]


def test_detection_durations_are_seconds():
    d = DetectionConfig()
    assert d.lost_hold_s == 5.0 and "seconds" in DetectionConfig.model_fields["lost_hold_s"].description
    assert np.isclose(config(split__after_s=0.5).split.after_s, 0.5)
