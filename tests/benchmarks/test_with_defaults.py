"""``benchmarks/with_defaults.py``: a benchmark run as if the ellipsoid's defaults were different."""

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import with_defaults  # noqa: E402

import worldtrack.trackers as trackers  # noqa: E402
from worldtrack.trackers.ellipsoid.config import EllipsoidConfig  # noqa: E402


@pytest.fixture
def restored(monkeypatch):
    """Whatever the script changes is put back after the test."""
    monkeypatch.setattr(trackers, "method_config", trackers.method_config)
    monkeypatch.setattr(EllipsoidConfig, "foreground_shadow_test", None, raising=False)


def test_only_the_ellipsoid_default_preset_changes(restored):
    with_defaults.changed_defaults({"feet.anchor": True, "height.prior_sigma_m": 0.1}, "evidence")
    cfg = trackers.method_config("ellipsoid")
    assert cfg.feet.anchor and cfg.height.prior_sigma_m == 0.1
    # A setting given by the run itself still wins over the changed default.
    assert not trackers.method_config("ellipsoid", "default", {"feet.anchor": False}).feet.anchor
    # make_tracker's path (method_config looked up in the module) sees the change too.
    assert trackers.make_tracker.__globals__["method_config"] is trackers.method_config
    assert not trackers.method_config("ellipsoid", "paper").feet.anchor
    assert trackers.method_shadow_test("ellipsoid") == "evidence"
    assert trackers.method_shadow_test("ellipsoid", "paper") is None
    assert trackers.method_shadow_test("particle") == "evidence"


def test_defaults_are_untouched_without_the_script(restored):
    assert not trackers.method_config("ellipsoid").feet.anchor
    assert trackers.method_shadow_test("ellipsoid") is None


def test_a_missing_benchmark_is_a_one_line_error(restored, capsys):
    assert with_defaults.main(["--set", "feet.anchor=true"]) == 2
    assert with_defaults.main(["--", "no_such_benchmark.py"]) == 2
    assert "no benchmark script 'no_such_benchmark.py'" in capsys.readouterr().err
