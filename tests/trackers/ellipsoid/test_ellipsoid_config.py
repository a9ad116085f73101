"""The ellipsoid tracker's configuration: sections by step, the paper's preset, files, errors."""

import pytest

from worldtrack.config import dump_yaml, from_mapping, load_yaml, to_mapping, with_overrides
from worldtrack.errors import InputError
from worldtrack.trackers import CONFIGS, method_config
from worldtrack.trackers.ellipsoid import EllipsoidConfig
from worldtrack.trackers.ellipsoid.config import MatchConfig


def test_paper_preset_values_are_the_papers():
    cfg = EllipsoidConfig.paper()
    assert (cfg.match.step_m, cfg.match.iterations, cfg.score.ring_px_160, cfg.confirm.capture_threshold) == (0.05, 3, 5.0, 0.7)
    assert cfg.score.target_pixels == 0 and cfg.score.kind == "paper" and not cfg.match.adaptive_step
    assert not cfg.match.predict and not cfg.height.measure and cfg.score.ring_fraction == 0.0
    assert cfg.births.search_m == 0 and cfg.rescue.search_m == 0 and cfg.warm_start.frames == 0
    assert method_config("ellipsoid", "paper") == cfg and CONFIGS["ellipsoid"] is EllipsoidConfig


def test_durations_are_in_seconds_equal_to_the_old_frame_counts_at_10_frames_per_second():
    cfg = EllipsoidConfig()
    assert (cfg.confirm.held_s, cfg.end.leave_after_s, cfg.rescue.every_s, cfg.rescue.retry_s,
            cfg.end.merge_after_s) == (0.3, 0.2, 1.0, 0.3, 0.3)


def test_sections_are_small():
    for name, info in EllipsoidConfig.model_fields.items():
        assert len(info.annotation.model_fields) <= 15, name
        assert all(f.description for f in info.annotation.model_fields.values()), name


@pytest.mark.parametrize("preset", [EllipsoidConfig(), EllipsoidConfig.paper()])
def test_a_config_file_round_trips(tmp_path, preset):
    changed = with_overrides(preset, {"match.step_m": 0.1, "height.range_m": [1.2, 2.0], "births.where": "entry"},
                             root="ellipsoid")
    path = tmp_path / "tracker.yaml"
    path.write_text(dump_yaml(changed))
    back = from_mapping(EllipsoidConfig, load_yaml(path), root="ellipsoid")
    assert back == changed and back.height.range_m == (1.2, 2.0)
    assert from_mapping(EllipsoidConfig, to_mapping(changed)) == changed
    assert "step_m: 0.1  # candidate step s, m (paper: 50 mm)" in dump_yaml(changed)


@pytest.mark.parametrize("overrides, message", [
    ({"match.step_m": -1}, r"^ellipsoid\.match\.step_m: expected a number > 0, got -1$"),
    ({"match.iterations": 0}, r"^ellipsoid\.match\.iterations: expected a number ≥ 1, got 0$"),
    ({"match.min_step_m": 1.0}, r"^ellipsoid\.match\.min_step_m: expected ≤ max_step_m \(0\.4\), got 1\.0$"),
    ({"score.kind": "jaccard"}, r"^ellipsoid\.score\.kind: expected one of 'symmetric' or 'paper', got 'jaccard'$"),
    ({"height.range_m": [2.0, 1.5]}, r"^ellipsoid\.height\.range_m: expected 0 < min < max, got \[2\.0, 1\.5\]$"),
    ({"confirm.held_s": -0.1}, r"^ellipsoid\.confirm\.held_s: expected a number ≥ 0, got -0\.1$"),
    ({"warm_start.frames": 2.5}, r"^ellipsoid\.warm_start\.frames: expected a whole number, got 2\.5$"),
    ({"match.step": 0.1}, r"^ellipsoid\.match\.step: unknown setting \(expected one of: step_m, iterations, "),
    ({"rescue_gain": 0.1}, r"^ellipsoid\.rescue_gain: unknown setting \(expected one of: score, match, births, "),
    ({"rescue": 0.1}, r"^ellipsoid\.rescue: is a section \(set one of its fields: ellipsoid\.rescue\.search_m, "),
])
def test_a_wrong_name_or_value_is_one_line_naming_it(overrides, message):
    with pytest.raises(InputError, match=message):
        method_config("ellipsoid", "default", overrides)


def test_a_section_built_alone_reports_its_full_path():
    with pytest.raises(InputError, match=r"^ellipsoid\.match\.max_speed_mps: expected a number > 0, got 0$"):
        MatchConfig(max_speed_mps=0)
    with pytest.raises(InputError, match=r"^ellipsoid\.support\.min_support: expected a number ≤ 1, got 2$"):
        EllipsoidConfig(support={"min_support": 2})


def test_the_config_module_is_light():
    # The command line reads configs for --help and --print-config: no compiled kernels there.
    import subprocess
    import sys
    code = ("import sys; from worldtrack.trackers.ellipsoid import EllipsoidConfig; EllipsoidConfig(); "
            "print('numba' in sys.modules)")
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip() == "False"
