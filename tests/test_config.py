"""The one config system: sections validate with field paths, round-trip through YAML, take --set."""

from typing import ClassVar, Literal

import pytest
import yaml
from pydantic import Field, model_validator

from worldtrack.config import (Section, dump_yaml, from_mapping, load_yaml, parse_assignment, to_mapping,
                               with_overrides)
from worldtrack.errors import InputError


class Motion(Section):
    path: ClassVar[str] = "demo.motion"
    noise_m: float = Field(0.4, ge=0, description="σ of the position noise, m/√s")
    kind: Literal["state", "object"] = Field("state", description="velocity model")
    samples: int = Field(3, ge=1, description="samples")
    range_m: tuple[float, float] = Field((1.3, 2.1), description="range, m")

    @model_validator(mode="after")
    def _order(self):
        if self.range_m[0] > self.range_m[1]:
            raise ValueError(f"range_m: expected min ≤ max, got {list(self.range_m)}")
        return self


class Demo(Section):
    path: ClassVar[str] = "demo"
    motion: Motion = Field(Motion(), description="motion model")
    flag: bool = Field(True, description="a flag")


def test_overrides_by_dotted_path_validate():
    cfg = with_overrides(Demo(), {"motion.noise_m": 0.05, "flag": False})
    assert cfg.motion.noise_m == 0.05 and cfg.flag is False
    assert Demo().motion.noise_m == 0.4                       # the default is untouched (frozen)
    with pytest.raises(Exception):
        cfg.motion.noise_m = 1.0


@pytest.mark.parametrize("override, message", [
    ({"motion.noise_m": -1}, "demo.motion.noise_m: expected a number ≥ 0, got -1"),
    ({"motion.nois_m": 1}, "demo.motion.nois_m: unknown setting (expected one of: noise_m, kind, samples, range_m)"),
    ({"motion.kind": "x"}, "demo.motion.kind: expected one of 'state' or 'object', got 'x'"),
    ({"motion.samples": 2.5}, "demo.motion.samples: expected a whole number, got 2.5"),
    ({"motion.samples": "many"}, "demo.motion.samples: expected a whole number, got 'many'"),
    ({"motion.range_m": [2.0, 1.0]}, "demo.motion.range_m: expected min ≤ max, got [2.0, 1.0]"),
    ({"motion.range_m": [2.0]}, "demo.motion.range_m.1: required"),
    ({"motion": 3}, "demo.motion: is a section (set one of its fields: demo.motion.noise_m"),
    ({"flag.x": 3}, "demo.flag: is a value, not a section"),
])
def test_each_bad_value_is_one_line_naming_its_path(override, message):
    with pytest.raises(InputError) as e:
        with_overrides(Demo(), override, root="demo")
    assert str(e.value).startswith(message)
    assert "\n" not in str(e.value)


def test_a_section_built_alone_reports_under_its_path():
    with pytest.raises(InputError, match=r"^demo\.motion\.noise_m: expected a number ≥ 0, got -2$"):
        Motion(noise_m=-2)


def test_mapping_and_yaml_round_trip(tmp_path):
    cfg = with_overrides(Demo(), {"motion.noise_m": 0.05, "motion.range_m": [1.2, 2.0]})
    assert from_mapping(Demo, to_mapping(cfg)) == cfg
    text = dump_yaml(cfg)
    assert "noise_m: 0.05  # σ of the position noise, m/√s" in text
    (tmp_path / "c.yaml").write_text(text)
    assert from_mapping(Demo, load_yaml(tmp_path / "c.yaml")) == cfg


def test_unknown_keys_in_a_file_are_errors():
    with pytest.raises(InputError, match=r"^demo\.motion\.speed: unknown setting"):
        from_mapping(Demo, {"motion": {"speed": 1}}, root="demo")
    with pytest.raises(InputError, match=r"^demo: expected a mapping of settings, got \[1, 2\]"):
        from_mapping(Demo, [1, 2], root="demo")


def test_parse_assignment_reads_values_as_yaml():
    assert parse_assignment("a.b=0.05") == ("a.b", 0.05)
    assert parse_assignment("a.b=true") == ("a.b", True)
    assert parse_assignment("a.b=[1, 2]") == ("a.b", [1, 2])
    assert parse_assignment("a.b=null") == ("a.b", None)
    assert parse_assignment("a.kind=state") == ("a.kind", "state")
    for bad in ("a.b", "=3", "a..b=1", "a b=1"):
        with pytest.raises(InputError, match="--set"):
            parse_assignment(bad)


def test_load_yaml_errors_name_the_file(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        load_yaml(tmp_path / "missing.yaml")
    (tmp_path / "bad.yaml").write_text("a: [1, 2\n")
    with pytest.raises(InputError, match=r"bad.yaml: not valid YAML at line"):
        load_yaml(tmp_path / "bad.yaml")
    (tmp_path / "list.yaml").write_text("- 1\n- 2\n")
    with pytest.raises(InputError, match="expected a mapping of settings at the top, got list"):
        load_yaml(tmp_path / "list.yaml")
    (tmp_path / "latin.yaml").write_bytes("a: caf\xe9\n".encode("latin-1"))
    with pytest.raises(InputError, match="not a UTF-8 text file"):
        load_yaml(tmp_path / "latin.yaml")
    (tmp_path / "empty.yaml").write_text("")
    assert load_yaml(tmp_path / "empty.yaml") == {}


def test_long_values_are_quoted_short():
    with pytest.raises(InputError) as e:
        with_overrides(Demo(), {"motion.kind": "x" * 10_000}, root="demo")
    assert len(str(e.value)) < 200 and str(e.value).endswith("...")
