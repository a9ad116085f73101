"""Two people crossing on the axis two facing cameras share (``map.crossing_s``): each camera shows
only the person in front, so each worker holds one of the two ids at one place. Pure (no server)."""

from __future__ import annotations

import json
from types import SimpleNamespace

from worldtrack.geometry.camera import Camera
from worldtrack.map.config import MapConfig
from worldtrack.map.connection import MapKeys
from worldtrack.map.fusion import FusionState, fuse_bucket
from worldtrack.map.merges import held_together
from worldtrack.map.messages import Estimate, MapPerson, MapState, Observation
from worldtrack.map.shared_ids import SharedPositionMap
from worldtrack.map.worker import MapLink

CAM = Camera.look_at("east", 320, 240, [0.0, 0.0, 3.0], [4.0, 0.0, 0.0], hfov_deg=60)


def _est(pid: int, x: float) -> Estimate:
    return Estimate(pid, x, 2.4, 1.7, 0.45, 0.0, 0.0, 0.5, 0.8, True, 1.0, 0.0, 1.0)


def _obs(cam: str, b: int, worker: str, people: list[Estimate]) -> Observation:
    return Observation(cam, b / 10, worker, b, b / 10 + 0.01, tuple(people))


def _cross(cfg: MapConfig) -> tuple[dict[int, int], FusionState]:
    """Both workers see 1 and 3 one metre apart (buckets 0-2), then w1 shows only 1 and w2 only 3,
    0.1 m apart (buckets 3-7). Returns the merges and the state after a JSON hand-over."""
    state, merged = FusionState(), {}
    for b in range(3):
        both = [_est(1, 5.0), _est(3, 6.0)]
        fuse_bucket(state, b, [_obs("west", b, "w1", both), _obs("east", b, "w2", both)], cfg)
    for b in range(3, 8):
        s = fuse_bucket(state, b, [_obs("west", b, "w1", [_est(1, 5.6)]), _obs("east", b, "w2", [_est(3, 5.7)])], cfg)
        merged.update(s.aliases)
    return merged, FusionState.from_json(state.to_json())


def test_the_map_keeps_two_ids_a_worker_saw_apart_moments_ago_only_when_asked():
    merged, handed = _cross(MapConfig())
    assert merged == {3: 1} and "together" not in json.loads(handed.to_json())    # the default: folded
    merged, handed = _cross(MapConfig(crossing_s=2.0))
    assert merged == {} and handed.together == {(1, 3): 0.2}                        # kept, and handed over
    merged, _ = _cross(MapConfig(crossing_s=0.05))
    assert merged == {3: 1}                                   # seen apart too long ago: one person after all


def test_held_together_notes_pairs_and_forgets_old_ones():
    assert held_together({(1, 9): 0.0, (2, 9): 4.0}, [3, 1], 5.0, 2.0) == {(1, 3): 5.0, (2, 9): 4.0}
    assert held_together({}, [4], 5.0, 2.0) == {}


class _Tracker:
    """As much of a tracker as a worker's sync needs: a position map and a way to start a person."""

    def __init__(self):
        self.position_map = SharedPositionMap(lambda x, y: 100)

    def init_track(self, x: float, y: float, track_id: int, t: float) -> None:
        self.position_map.add(x, y, mode="tracking", time=t, track_id=track_id, confirmed=True)


def _sync(crossing_s: float, seen_apart_at: float | None, gap_m: float = 0.0) -> set[int]:
    """Worker w2 (one camera) holds 3 as its own; the map has 1 (w1's) 0.2 m from it. Which ids does
    w2 hold after its sync at t = 1.05 s, having seen 1 and 3 apart at ``seen_apart_at`` (s)?"""
    stub = SimpleNamespace(register_script=lambda _: None)
    cfg = MapConfig(crossing_s=crossing_s, crossing_gap_m=gap_m, affirm_candidates=False)
    link = MapLink(stub, MapKeys(), cfg, "w2", {"east": CAM})
    tracker = _Tracker()
    tracker.position_map.add(5.0, 0.0, mode="tracking", track_id=3, confirmed=True)
    link.mine_seen = link.ever_seen = {3}
    if seen_apart_at is not None:
        link.together = {(1, 3): seen_apart_at}
    p = MapPerson(1, 5.2, 0.0, 1.7, 0.45, 0.0, 0.0, 0.8, 0.5, "tracking", 1.0, 0.0, 1, "w1")
    link.state = MapState(1.0, (p,))
    link.read_map = lambda: link.state
    link.sync(tracker, 1.05)
    return {q.id for q in tracker.position_map}


def test_a_worker_puts_back_the_person_it_saw_beside_its_own_moments_ago_only_when_asked():
    assert _sync(0.0, 0.5) == {3}              # the default: somebody held there already, not placed
    assert _sync(2.0, 0.5) == {1, 3}           # seen apart 0.55 s ago: another person, placed from the map
    assert _sync(2.0, None) == {3}             # never seen apart: the map will merge them
    assert _sync(0.3, 0.5) == {3}              # seen apart too long ago


def test_a_worker_does_not_put_back_the_other_on_top_of_its_own():
    assert _sync(2.0, 0.5, gap_m=0.1) == {1, 3}    # 0.2 m from its own: placed
    assert _sync(2.0, 0.5, gap_m=0.25) == {3}      # within the gap its tracker would end it again: not placed


def test_a_worker_notes_the_pairs_it_sees_at_once_only_when_asked():
    from worldtrack.trackers.base import Frame
    stub = SimpleNamespace(register_script=lambda _: None)
    for crossing_s, noted in ((2.0, {(3, 5): 1.0}), (0.0, {})):
        link = MapLink(stub, MapKeys(), MapConfig(crossing_s=crossing_s, affirm_candidates=False), "w2", {"east": CAM})
        tracker = _Tracker()
        for pid, x in ((3, 5.0), (5, 6.0)):
            tracker.position_map.add(x, 0.0, mode="tracking", track_id=pid, confirmed=True).seen_at = 1.0
        tracks = [p.track() for p in tracker.position_map]
        link.observations(tracker, tracks, 1.0, {"east": Frame(None, t=1.0, index=10)})
        assert link.together == noted


def _twins(cfg: MapConfig) -> dict[int, int]:
    """w1 holds 1 and its tracker's duplicate 3 0.1 m apart (buckets 0-2), then only 1 while w2
    holds 3 there (buckets 3-7). Returns the merges."""
    state, merged = FusionState(), {}
    for b in range(3):
        fuse_bucket(state, b, [_obs("west", b, "w1", [_est(1, 5.6), _est(3, 5.7)]),
                               _obs("east", b, "w2", [_est(3, 5.7)])], cfg)
    for b in range(3, 8):
        s = fuse_bucket(state, b, [_obs("west", b, "w1", [_est(1, 5.6)]), _obs("east", b, "w2", [_est(3, 5.7)])], cfg)
        merged.update(s.aliases)
    return merged


def test_the_map_folds_a_duplicate_born_on_top_of_its_twin_despite_crossing_s():
    assert _twins(MapConfig(crossing_s=2.0)) == {3: 1}                          # never held apart: folded
    assert _twins(MapConfig(crossing_s=2.0, crossing_apart_m=0.0)) == {}        # issue 39o: kept for 2 s
    merged, _ = _cross(MapConfig(crossing_s=2.0, crossing_apart_m=0.9))
    assert merged == {}                                                         # 1 m apart: a crossing, kept
    merged, _ = _cross(MapConfig(crossing_s=2.0, crossing_apart_m=1.1))
    assert merged == {3: 1}


def test_a_worker_notes_only_the_pairs_it_holds_apart():
    from worldtrack.trackers.base import Frame
    stub = SimpleNamespace(register_script=lambda _: None)
    for apart_m, noted in ((0.5, {(3, 7): 1.0, (5, 7): 1.0}), (0.0, {(3, 5): 1.0, (3, 7): 1.0, (5, 7): 1.0})):
        cfg = MapConfig(crossing_s=2.0, crossing_apart_m=apart_m, affirm_candidates=False)
        link = MapLink(stub, MapKeys(), cfg, "w2", {"east": CAM})
        tracker = _Tracker()
        for pid, x in ((3, 5.0), (5, 5.2), (7, 6.0)):
            tracker.position_map.add(x, 0.0, mode="tracking", track_id=pid, confirmed=True).seen_at = 1.0
        tracks = [p.track() for p in tracker.position_map]
        link.observations(tracker, tracks, 1.0, {"east": Frame(None, t=1.0, index=10)})
        assert link.together == noted
