"""benchmarks/trajectory_finish.py reads its option sets as SolverOptions fields of the right kinds, refuses
others."""

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from trajectory_finish import main, parse_set  # noqa: E402

from worldtrack.errors import InputError  # noqa: E402


def test_parse_set_gives_each_field_its_kind():
    kw = parse_set("shrink_on_reject=1,outward_curvature=1.0,finish_newton=0,max_iterations=7,look_ahead=None")
    assert kw == {"shrink_on_reject": True, "outward_curvature": 1.0, "finish_newton": False, "max_iterations": 7,
                  "look_ahead": None}
    assert type(kw["max_iterations"]) is int and type(kw["outward_curvature"]) is float
    assert kw["shrink_on_reject"] is True and kw["finish_newton"] is False
    assert parse_set("linear_solver=lapack") == {"linear_solver": "lapack"}


@pytest.mark.parametrize("spec", ["outward=1.0", "shrink_on_reject", "finish_newton="])
def test_parse_set_refuses_what_is_not_a_field_value(spec):
    with pytest.raises(InputError):
        parse_set(spec)


def test_bad_set_exits_2(capsys):
    assert main(["--quick", "--sets", "no_such_field=1"]) == 2
    assert "no_such_field" in capsys.readouterr().err
