"""The follow-target scenario's issue-35 options: white-balance wander, cut-ins, look-alikes, a clear route."""

import numpy as np
import pytest

from worldtrack.errors import InputError
from worldtrack.synth import make_scenario
from worldtrack.synth.photometry import WhiteBalance


def test_white_balance_offsets_hold_until_the_next_entry_and_auto_keeps_its_own_state():
    wb = WhiteBalance(mode="fixed", offsets={2: (100, -50), 5: (0, 0)})
    got = [wb.update(k, np.array([100.0, 100.0, 100.0])) for k in range(7)]
    assert got == [(512, 512)] * 2 + [(612, 462)] * 3 + [(512, 512)] * 2


def test_the_wandering_white_balance_jumps_every_one_to_two_seconds_and_is_recorded():
    sc = make_scenario("follow-target", size=(64, 48), frames=120, seed=1, others=0, wb_jump_steps=400,
                       segments=("front",))
    offsets = sc.rigs["robot"].white_balance.offsets
    starts = np.array(sorted(offsets))
    assert 5 <= len(starts) <= 12 and np.all(np.diff(starts) >= 10) and np.all(np.diff(starts) <= 20)
    values = np.array([offsets[k] for k in starts])
    assert np.abs(values).max() <= 300
    jumps = np.abs(np.diff(np.vstack([[0, 0], values]), axis=0)).sum(axis=1)
    assert jumps.max() <= 400 + 1 and jumps.max() > 150
    metas = [b.meta for b in sc.frames()]
    r = np.array([m["wb_r_robot"] for m in metas])
    k = starts[2]
    assert r[k] - r[k - 1] == offsets[k][0] - offsets[starts[1]][0]   # the light did not change: only the jump


def test_look_alike_cut_ins_and_a_route_clear_of_the_kiosk():
    sc = make_scenario("follow-target", size=(64, 48), frames=600, seed=3, others=3, crossers=2, crossings=4,
                       cross_speed=(0.6, 1.0), cross_pause=(0.3, 1.1), lookalike=1, clear_route=True)
    target, twin = sc.people[0].shape, sc.people[1].shape
    assert np.allclose(twin.top, target.top, rtol=0.09) and np.allclose(twin.bottom, target.bottom, rtol=0.09)
    assert not np.allclose(sc.people[2].shape.top, target.top, rtol=0.09)
    df = sc.scene.distance_field(0.05)
    assert df.sample(sc.people[0].track.xy).min() > 0.7                 # the target's loop, 0.8 m from obstacles
    robot = np.array([sc.camera_at("robot", k).centre[:2] for k in range(sc.n_frames)])
    assert df.sample(robot).min() > 0.3                                 # the robot steers round them
    for p in sc.people[1:3]:                                            # two people cut in, twice each
        on = p.track.present
        assert 1 <= len(np.flatnonzero(np.diff(on.astype(int)) == 1)) + int(on[0]) <= 2
        assert np.hypot(*(p.track.xy[on] - sc.people[0].track.xy[on]).T).min() > 0.6


def test_option_errors_name_the_parameter():
    with pytest.raises(InputError, match="cross_speed"):
        make_scenario("follow-target", frames=5, cross_speed=(2.0, 1.0))
    with pytest.raises(InputError, match="wb_jump_steps"):
        make_scenario("follow-target", frames=5, wb_jump_steps=2000)
