"""Fuzzing the three kinds of file users hand over: scene files, track CSVs, calibration points.

Every generated input ends in exit 0 (valid: read as meant) or one ``error:`` line with exit 2
(refused); never a traceback, never more than 2 s or 500 MB, never an invalid input accepted
(see ``fuzz_runner``). Each mutation of the catalogues runs once on a fixed room, then hypothesis
explores mutations × rooms × inserted bytes (seeded, so CI sees the same inputs every run).
``benchmarks/fuzz.py`` runs the same generators on many more inputs and counts the outcomes.
"""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, seed, settings
from hypothesis import strategies as st

import fuzz_calibration
import fuzz_scene
import fuzz_tracks
from fuzz_runner import run_case

FAMILIES = {"scene": (fuzz_scene.scene_case, fuzz_scene.MUTATIONS),
            "tracks": (fuzz_tracks.tracks_case, fuzz_tracks.MUTATIONS),
            "calibration": (fuzz_calibration.calibration_case, fuzz_calibration.MUTATIONS)}
EXAMPLES = 40      # hypothesis examples per family, on top of the sweep over every mutation


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """A folder for the inputs, after one untimed run per family (imports are not the input's cost)."""
    path = tmp_path_factory.mktemp("fuzz")
    for make, _ in FAMILIES.values():
        run_case(make("as-is", 0), path)
    return path


@pytest.mark.parametrize("family, mutation", [(f, m) for f, (_, ms) in FAMILIES.items() for m in ms])
def test_every_mutation_is_read_or_refused_cleanly(folder, family, mutation):
    make, _ = FAMILIES[family]
    outcome = run_case(make(mutation, 1, b"\x00\xff,: [x\r"), folder)
    assert outcome.ok, outcome.describe()


@pytest.mark.parametrize("family", list(FAMILIES))
def test_generated_inputs_are_read_or_refused_cleanly(folder, family):
    make, mutations = FAMILIES[family]

    @seed(38)
    @settings(max_examples=EXAMPLES, deadline=None, database=None,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
    @given(st.sampled_from(mutations), st.integers(0, 2 ** 31 - 1), st.binary(max_size=12))
    def check(mutation, room, inserted):
        outcome = run_case(make(mutation, room, inserted), folder)
        assert outcome.ok, outcome.describe()

    check()


def test_the_runner_catches_what_it_should(folder, monkeypatch):
    """The judge itself can fail: a valid input refused, an invalid one accepted, a traceback."""
    import worldtrack.scene
    from fuzz_runner import Case

    good = fuzz_scene.scene_case("as-is", 2)
    refused = run_case(Case("scene", "x", "valid", b"cameras: [", good.argv), folder)
    accepted = run_case(Case("scene", "x", "invalid", good.data, good.argv), folder)

    def broken(path):
        raise ZeroDivisionError("a bug")
    monkeypatch.setattr(worldtrack.scene, "load_scene", broken)
    crash = run_case(Case("scene", "x", "either", good.data, good.argv), folder)
    assert refused.problems == ["valid input refused"]
    assert accepted.problems == ["wrongly accepted"]
    assert crash.problems == ["traceback (ZeroDivisionError: a bug)"]
