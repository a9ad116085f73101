"""Fixtures of the trajectory tests (built once per session); helpers live in ``_trajectory_cases``."""

import pytest


@pytest.fixture(scope="session")
def office():
    """The seed-002 office with detours, one person, 2 px noise: (scenario, head tracks, head pixels)."""
    from worldtrack.synth import make_scenario
    from worldtrack.synth.observations import head_pixels, head_tracks
    sc = make_scenario("non-overlapping", frames=420, seed=13, people=1, layout="detours", size=(640, 480),
                       legs=12)
    tracks = head_tracks(sc)
    return sc, tracks, head_pixels(sc, noise_px=2.0, rng=5, tracks=tracks)
