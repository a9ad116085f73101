"""The position map, its persons and the shared life-cycle rules."""

import pytest

from worldtrack.registry import Registry
from worldtrack.errors import InputError
from worldtrack.trackers.base import PositionMap
from worldtrack.trackers.lifecycle import NEVER, counts_for, frames_for, merge_duplicates, younger


def test_ids_tentative_promotion_and_removal():
    m = PositionMap()
    a = m.add(0, 0, time=0.0, mode="tracking")
    c = m.add(1, 0, time=0.0, tentative=True)
    assert (a.id, a.confirmed, c.id, c.confirmed) == (1, True, -1, False)
    assert m.promote(c.id) == 2 and 2 in m and -1 not in m
    m.close_pairs[(1, 2)] = 2
    m.remove(1)
    assert m.close_pairs == {} and len(m) == 1
    assert m.add(5, 5).id == 3                      # ids are never reused
    with pytest.raises(ValueError, match="already exists"):
        m.add(0, 0, track_id=2)
    assert m.tracks() == []                         # promoted is not confirmed: the tracker confirms
    m[2].confirmed = True
    assert [t.id for t in m.tracks()] == [2]        # capture-mode 3 is not confirmed: not reported


def test_counters_advance_once_per_time_stamp_and_seen_wins():
    m = PositionMap()
    p = m.add(0, 0, mode="tracking")
    assert p.tick("unseen", 0.1) == 1
    assert p.tick("unseen", 0.1) == 1               # a second tracker at the same time: once
    p.reset("unseen", 0.1)                          # a tracker that sees them: reset wins
    assert p.count("unseen") == 0
    assert p.tick("unseen", 0.1) == 0               # and a later tick at the same time does nothing
    assert p.tick("unseen", 0.2) == 1 and p.tick("low", 0.2, by=2) == 2
    assert counts_for(p, "low", 0.3, True) == 3 and counts_for(p, "low", 0.4, False) == 0
    assert p.once("velocity", 0.4) and not p.once("velocity", 0.4) and p.once("velocity", 0.5)


def test_advance_keeps_the_previous_state_once_per_time():
    m = PositionMap()
    p = m.add(1.0, 2.0, time=0.0, mode="tracking")
    p.x = 1.5
    m.advance(0.1)
    assert (p.prev_x, p.prev_y, p.prev_t, p.t) == (1.5, 2.0, 0.0, 0.1)
    p.x = 1.7
    m.advance(0.1)                                  # a second tracker at the same time
    assert (p.prev_x, p.t) == (1.5, 0.1)


def test_mark_seen_collects_the_cameras_of_one_time_stamp():
    m = PositionMap()
    p = m.add(0, 0)
    p.mark_seen(0.1, ["c2"])
    p.mark_seen(0.1, ["c1"])
    assert p.seen_by == ("c1", "c2") and p.seen_now(0.1) and not p.seen_now(0.2) and p.last_seen == 0.1
    p.mark_seen(0.2, ["c1"])
    assert p.seen_by == ("c1",)


def test_frames_for_converts_seconds_at_the_real_frame_interval():
    # At least the duration: ⌈s / dt⌉, with slack for time stamps that do not divide exactly.
    assert frames_for(0.3, 0.1) == 3 and frames_for(0.3, 1 / 7) == 3 and frames_for(0.3, 1 / 25) == 8
    assert frames_for(0.2, 1 / 7) == 2 and frames_for(0.3, 0.1 * (1 + 1e-15)) == 3
    assert frames_for(0.3, 0.1 * (1 - 1e-15)) == 3 and frames_for(0.01, 0.1) == 1 and frames_for(1.0, 0.0) == NEVER


def test_merge_duplicates_ends_the_younger_after_the_frames_needed():
    m = PositionMap()
    old, new = m.add(0, 0, time=0.0), m.add(0.1, 0, time=1.0)
    ended = []

    def end(p):
        ended.append(p.id)
        m.remove(p.id)

    assert younger(old, new) is new
    merge_duplicates(m, {(1, 2): 3}, end)
    merge_duplicates(m, {(1, 2): 3}, end)
    assert ended == [] and m.close_pairs == {(1, 2): 2}
    merge_duplicates(m, {}, end)                     # apart for a frame: starts again
    assert m.close_pairs == {}
    for _ in range(3):
        merge_duplicates(m, {(1, 2): 3}, end)
    assert ended == [2] and 1 in m


def test_registry_names_the_choices():
    r: Registry = Registry("resampling")
    r.register("systematic")(lambda: 1)
    r.add_lazy("json", "json:dumps")
    assert r["systematic"]() == 1 and r["json"]([1]) == "[1]" and r.names() == ("systematic", "json")
    with pytest.raises(InputError, match=r"^resampling: expected one of systematic, json, got 'x'$"):
        r["x"]


def test_a_pair_whose_elder_was_just_ended_is_left_alone():
    m = PositionMap()
    a, b, c = m.add(0, 0, time=0.0), m.add(0.1, 0, time=1.0), m.add(0.2, 0, time=2.0)
    ended = []

    def end(p):
        ended.append(p.id)
        m.remove(p.id)

    for _ in range(3):
        merge_duplicates(m, {(1, 2): 3, (2, 3): 3}, end)
    assert ended == [2] and 3 in m                  # b duplicated a; c duplicated b, who is gone
