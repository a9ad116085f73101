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


@pytest.fixture(scope="session")
def office_person(office):
    """Person 1 of the office: (head pixels as Observations, the scene's distance field at 5 cm, head height m)."""
    from worldtrack.trajectory.observation import Observations
    sc, tracks, pixels = office
    person = pixels.of(1)
    obs = Observations.from_rows(person.time, person.camera, person.uv, sc.scene.cameras, 2.0)
    return obs, sc.scene.distance_field(0.05), tracks[1].height
