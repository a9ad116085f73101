"""A short two-camera sequence on disk (PNG frames, backgrounds, gt.csv, scene.yaml), rendered once."""

import pytest

from worldtrack.synth import make_scenario, write_sequence


@pytest.fixture(scope="session")
def sequence(tmp_path_factory):
    out = tmp_path_factory.mktemp("seq")
    write_sequence(make_scenario("two-crossing", size=(160, 120), frames=30, seed=1), out, png=True, progress=False)
    return out
