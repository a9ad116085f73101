"""Short synthetic follow-target sequences shared by the follower's tests (rendered once per session)."""

import pytest

from worldtrack.synth import make_scenario

HARD = dict(others=3, crossers=2, crossings=2, cross_speed=(0.6, 1.0), cross_pause=(0.3, 1.1), lookalike=1,
            wb_jump_steps=400, clear_route=True)


@pytest.fixture(scope="session")
def lookalike_cut_in():
    """160×120, 130 frames, three others: the person in the target's clothes cuts in between robot
    and target and hides it for 1.1 s from frame 33, another person for 1.3 s from frame 84; the
    white balance jumps by up to 400 steps every 1–2 s."""
    sc = make_scenario("follow-target", size=(160, 120), frames=130, seed=4, **HARD)
    return sc, sc.render()
