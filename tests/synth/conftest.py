"""Small synthetic sequences shared by the synth tests (rendered once per session)."""

import pytest

from worldtrack.synth import make_scenario


@pytest.fixture(scope="session")
def crossing():
    """two-crossing at 160×120, 40 frames, both cameras: (scenario, bundles)."""
    sc = make_scenario("two-crossing", size=(160, 120), frames=40, seed=3)
    return sc, sc.render()


@pytest.fixture(scope="session")
def desk():
    """desk-occlusion (feet hidden) at 160×120, the whole route."""
    sc = make_scenario("desk-occlusion", size=(160, 120), seed=0, dwell=1.0, speed=1.0)
    return sc, sc.render()
