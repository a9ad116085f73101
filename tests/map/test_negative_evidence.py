"""Negative evidence on the shared map: a worker whose camera shows a map person's place clearly,
with nobody there, says so; the map drops a person that only poor views (less than 60 % of the
body) report while such a clear view shows their place empty, and workers drop their copies.
Pure (no server)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from worldtrack.geometry.camera import Camera
from worldtrack.map.config import MapConfig
from worldtrack.map.connection import MapKeys
from worldtrack.map.evidence import looks_empty, people_boxes
from worldtrack.map.fusion import FusionState, fuse_bucket, provisional_state
from worldtrack.map.messages import (REFUTED, Estimate, MapPerson, MapState, Observation, decode_observation,
                                     encode_observation)
from worldtrack.map.shared_ids import SharedPositionMap
from worldtrack.map.worker import MapLink

CAM = Camera.look_at("east", 320, 240, [0.0, 0.0, 3.0], [4.0, 0.0, 0.0], hfov_deg=60)


def _bucket(state, b, visible, absent=True, cfg=MapConfig()):
    """Worker w1 reports person 7 (showing ``visible`` of them); w2's camera shows their place empty."""
    a = Observation("west", b / 10 + 0.05, "w1", b, 0.0,
                    (Estimate(7, 4.0, 0.0, 1.7, 0.45, 0, 0, 0.8, 0.5, True, visible=visible),))
    n = Observation("east", b / 10 + 0.05, "w2", b, 0.0, (), absent=(7,) if absent else ())
    return fuse_bucket(state, b, [a, n], cfg)


def test_a_person_only_a_poor_view_reports_is_dropped_when_a_clear_view_shows_their_place_empty():
    state = FusionState()
    out = [_bucket(state, b, visible=0.4) for b in range(4)]
    assert [len(s.present()) for s in out] == [1, 1, 0, 0]            # refute_after = 3 buckets
    assert out[2].aliases == {7: REFUTED} and 7 not in state.people
    # The worker that made them up goes on reporting them: not brought back (the live map neither).
    assert 7 not in state.people and not provisional_state(state, {4: [Observation(
        "west", 0.45, "w1", 4, 0.0, (Estimate(7, 4.0, 0.0, 1.7, 0.45, 0, 0, 0.8, 0.5, True, visible=0.4),))]},
        MapConfig()).people


def test_a_person_a_worker_shows_well_or_whose_place_is_not_shown_empty_every_bucket_is_kept():
    well = FusionState()                         # shown well for 1 s before the other view says empty
    assert all(len(_bucket(well, b, visible=0.9, absent=b >= 10).present()) == 1 for b in range(16))
    broken = FusionState()                       # the empty view is interrupted: its count starts again
    assert all(len(_bucket(broken, b, visible=0.4, absent=b % 3 != 2).present()) == 1 for b in range(8))
    off = FusionState()
    cfg = MapConfig(negative_evidence=False)
    assert all(len(_bucket(off, b, visible=0.4, cfg=cfg).present()) == 1 for b in range(6))


def test_a_birth_another_workers_clear_view_shows_empty_is_dropped_even_when_shown_well():
    young = FusionState()
    on = MapConfig(confirm_birth_s=1.0)          # opt-in: held-out seeds 24-33 lose with it (issue-39h)
    out = [_bucket(young, b, visible=0.9, cfg=on) for b in range(4)]
    assert [len(s.present()) for s in out] == [1, 1, 0, 0] and out[2].aliases == {7: REFUTED}
    off = FusionState()                          # confirm_birth_s = 0 (default): a person shown well is kept
    cfg = MapConfig()
    assert all(len(_bucket(off, b, visible=0.9, cfg=cfg).present()) == 1 for b in range(6))


def test_the_absent_ids_travel_in_the_observation_and_older_messages_still_decode():
    o = Observation("east", 1.25, "w2", 12, 1.26, (), ended=(3,), absent=(7, 9))
    assert decode_observation(encode_observation(o)) == o
    old = encode_observation(o)
    nine = dict(old, o=old["o"].rsplit(",[", 1)[0] + "]")    # nine elements: before same (issue 39l)
    assert decode_observation(nine) == o
    old["o"] = old["o"].rsplit(",[", 4)[0] + "]"             # six elements: no absent list (nor candidates)
    assert decode_observation(old).absent == () and decode_observation(old).ended == (3,)


def test_looks_empty_needs_a_clear_view_and_counts_only_foreground_nobody_else_explains():
    xy = np.array([5.0, 0.0])
    box = people_boxes(CAM, np.array([[5.0, 0.0, 1.7, 0.45]]))[0]
    u0, v0, u1, v1 = np.round(box[:4]).astype(int)
    empty = np.zeros((240, 320), np.uint8)
    assert looks_empty(CAM, empty, xy, 1.7, 0.45)
    full = empty.copy()
    full[v0:v1, u0:u1] = 1
    assert not looks_empty(CAM, full, xy, 1.7, 0.45)
    # Somebody this worker holds stands in front at 4 m: the place is hidden, nothing to tell.
    front = people_boxes(CAM, np.array([[4.0, 0.0, 1.7, 0.45]]))
    assert not looks_empty(CAM, empty, xy, 1.7, 0.45, blockers=front)
    # Somebody it holds 1 m further away covers the middle of the box: their foreground is theirs,
    # the rest of the box (feet, sides) is what tells.
    behind = people_boxes(CAM, np.array([[6.0, 0.0, 1.7, 0.45]]))
    bu0, bv0, bu1, bv1 = np.clip(np.round(behind[0, :4]), 0, None).astype(int)
    theirs = empty.copy()
    theirs[bv0:bv1, bu0:bu1] = 1
    assert not looks_empty(CAM, theirs, xy, 1.7, 0.45)           # unexplained: counted
    assert looks_empty(CAM, theirs, xy, 1.7, 0.45, blockers=behind)
    # An obstacle of the scene between the camera and the place: nothing to tell.
    wall = np.full((240, 320), np.inf)
    wall[:, :] = 3.0
    assert not looks_empty(CAM, empty, xy, 1.7, 0.45, occlusion=wall)
    assert not looks_empty(CAM, None, xy, 1.7, 0.45)


class _Stub:
    def register_script(self, _):
        return None


def test_a_worker_reports_a_map_person_its_camera_shows_nobody_at_and_drops_a_refuted_copy():
    link = MapLink(_Stub(), MapKeys(), MapConfig(), "w2", {"east": CAM})
    p = MapPerson(7, 5.0, 0.0, 1.7, 0.45, 0.0, 0.0, 0.8, 0.5, "tracking", 0.0, 0.0, 1)
    link.state = MapState(0.0, (p,))
    mask = np.zeros((240, 320), np.uint8)
    tracker = SimpleNamespace(overlay=lambda c: SimpleNamespace(mask=mask))
    boxes = {"east": np.zeros((0, 5))}
    assert link._absent(tracker, [], 0.05, ["east"], boxes, set()) == {"east": (7,)}
    assert link._absent(tracker, [], 0.05, ["east"], boxes, {7}) == {}          # it sees them itself
    u0, v0, u1, v1 = np.round(people_boxes(CAM, np.array([[5.0, 0.0, 1.7, 0.45]]))[0, :4]).astype(int)
    mask[v0:v1, u0:u1] = 1
    assert link._absent(tracker, [], 0.05, ["east"], boxes, set()) == {}        # somebody is there
    # The map dropped 7: a worker holding a copy removes it.
    local = SharedPositionMap(lambda x, y: 100)
    local.add(5.0, 0.0, track_id=7, mode="tracking")
    link.state, link.mine_seen = MapState(0.1, (), aliases={7: REFUTED}), set()
    link.read_map = lambda: link.state
    link.sync(SimpleNamespace(position_map=local), 0.15)
    assert 7 not in local


def _covered(state, b, own, other_worker=True, cfg=MapConfig()):
    """w1 reports person 7 with ``own`` of their body not covered by its other people; w2 reports 8."""
    a = Observation("west", b / 10 + 0.05, "w1", b, 0.0,
                    (Estimate(7, 4.0, 0.0, 1.7, 0.45, 0, 0, 0.8, 0.5, True, visible=0.9, own=own),))
    n = Observation("east", b / 10 + 0.05, "w2", b, 0.0, (Estimate(8, 9.0, 2.0, 1.7, 0.45, 0, 0, 0.8, 0.5, True),))
    return fuse_bucket(state, b, [a, n] if other_worker else [a], cfg)


def test_a_person_one_worker_reports_inside_somebody_elses_silhouette_leaves_the_map_after_1_s():
    state = FusionState()
    out = [_covered(state, b, own=0.1) for b in range(12)]
    assert [7 in {p.id for p in s.present()} for s in out] == [True] * 9 + [False] * 3       # 10 buckets = 1 s
    assert out[9].aliases == {7: REFUTED} and {p.id for p in out[-1].present()} == {8}
    for kept in (dict(own=0.5), dict(own=0.1, other_worker=False), dict(own=0.1, cfg=MapConfig(hidden_after_s=0))):
        state = FusionState()
        assert all(7 in {p.id for p in _covered(state, b, **kept).present()} for b in range(15)), kept
