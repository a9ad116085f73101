"""``follow_synth.py --set`` / ``follow_pets.py --set``: the default run beside itself with one setting changed."""

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import follow_holder  # noqa: E402
import follow_pets  # noqa: E402
import follow_synth  # noqa: E402

from worldtrack.errors import InputError  # noqa: E402


def test_a_setting_becomes_one_variant_of_the_default_with_its_value():
    assert follow_synth.set_variant([]) == {}
    (label, (preset, over)), = follow_synth.set_variant(["reid_any_track_after=inf", "reid_rbhat=0.25"]).items()
    assert preset == "default" and over == {"reid_any_track_after": float("inf"), "reid_rbhat": 0.25}
    assert label == "worldtrack default with reid_any_track_after=inf, reid_rbhat=0.25"
    assert label.startswith(follow_synth.SET_LABEL)     # tables() gives it its own acceptance table


def test_an_unknown_setting_or_a_bad_value_is_refused():
    with pytest.raises(InputError):
        follow_synth.set_variant(["no_such_field=1"])
    with pytest.raises(InputError):
        follow_synth.set_variant(["reid_any_track_after=-1"])
    with pytest.raises(ValueError):
        follow_synth.set_variant(["reid_any_track_after=soon"])


@pytest.mark.parametrize("script", [follow_synth, follow_pets, follow_holder])
def test_bad_set_is_one_line_and_exit_2(script, capsys):
    assert script.main(["--set", "no_such_field=1"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "no_such_field" in err
