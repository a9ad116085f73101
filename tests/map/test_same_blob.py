"""Two workers' newborns one camera shows as one blob are one person (worldtrack.map.same_blob).

The numbers are development seed 23's frame 0 (issue 39k's class C): the west worker starts the
person 1.8 m from its camera at (1.77, 1.44); the east worker sees them through the door 9-10 m
away and starts them at (2.70, 1.57), 0.94 m off along its line of sight — beyond the map's
newborn gate — and in the east image the two boxes overlap by IoU 0.59 (in the west image 0.10)."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from worldtrack.map.config import MapConfig
from worldtrack.map.connection import MapKeys, connect
from worldtrack.map.fusion import FusionState, fuse_bucket
from worldtrack.map.messages import Estimate, MapPerson, MapState, Observation
from worldtrack.map.shared_ids import SharedPositionMap
from worldtrack.map.worker import MapLink

T0 = 1.0e9
NEAR_XY, FAR_XY = (1.7672, 1.4397), (2.7027, 1.5728)


@pytest.fixture(scope="module")
def cameras():
    from worldtrack.synth import make_scenario
    return make_scenario("two-rooms", seed=23).scene.cameras


def _person(pid, xy, born, lead, height=1.7):
    return MapPerson(pid, *xy, height, 0.45, 0.0, 0.0, 0.6, 0.6, "tracking", born, born, 1, lead)


def _claims(url, cameras, name, camera, own_xy, other_xy, other_born=T0, cfg=MapConfig(), born_here=True, t=T0 + 0.1):
    """One worker (``camera``) holding its newborn at ``own_xy`` while the map (bucket T0) holds another
    worker's newborn at ``other_xy``: the ``same`` pairs of its observation at ``t``."""
    link = MapLink(connect(url), MapKeys(), cfg, name, {camera: cameras[camera]})
    link.register()
    assert link.leases[camera].acquire()
    local = SharedPositionMap(link.new_id)
    own = local.add(*own_xy, 1.552, 0.45, mode="tracking", time=T0) if born_here else \
        local.add(*own_xy, 1.552, 0.45, mode="tracking", time=T0, track_id=8)
    other = 9 if own.id != 9 else 11
    link.state = MapState(T0, (_person(own.id, own_xy, T0, name), _person(other, other_xy, other_born, "w-other")),
                          reports=((camera, T0, T0),))
    tracks = [SimpleNamespace(id=own.id, x=own_xy[0], y=own_xy[1], height=1.552, width=0.45, vx=0.0, vy=0.0,
                              score=0.5)]
    tracker = SimpleNamespace(position_map=local, overlay=lambda c: SimpleNamespace(mask=None))
    [o] = link.observations(tracker, tracks, t, {camera: SimpleNamespace(t=t, index=1)})
    return o.same, own.id, other


def test_the_far_worker_says_its_newborn_is_the_near_workers_when_its_camera_shows_one_blob(redis_url, cameras):
    same, mine, theirs = _claims(redis_url, cameras, "w-east", "east", FAR_XY, NEAR_XY)
    assert same == ((mine, theirs),)


def test_no_claim_from_the_near_view_nor_for_people_apart_old_or_taken_over_nor_when_off(redis_url, cameras):
    import redis
    cases = [dict(name="w-west", camera="west", own_xy=NEAR_XY, other_xy=FAR_XY),       # the near view: IoU 0.10
             dict(name="w-east", camera="east", own_xy=FAR_XY, other_xy=(1.7672, 2.4397)),   # 1 m across the view
             dict(name="w-east", camera="east", own_xy=FAR_XY, other_xy=NEAR_XY, other_born=T0 - 1.0),   # not newborn
             dict(name="w-east", camera="east", own_xy=FAR_XY, other_xy=NEAR_XY, born_here=False),  # not its own birth
             dict(name="w-east", camera="east", own_xy=FAR_XY, other_xy=NEAR_XY, cfg=MapConfig(same_blob_iou=0))]
    for k, case in enumerate(cases):
        redis.Redis.from_url(redis_url).flushall()
        assert _claims(redis_url, cameras, **case)[0] == (), k


def _est(pid, xy, cxx):
    return Estimate(pid, *xy, 1.7, 0.45, 0.0, 0.0, 0.5, 0.6, True, cxx=cxx, cxy=0.0, cyy=0.003)


def _obs(cam, worker, frame, people, same=()):
    return Observation(cam, frame * 0.1, worker, frame, frame * 0.1 + 0.01, tuple(people), same=tuple(same))


def test_the_map_folds_a_claimed_newborn_into_the_other_workers_and_keeps_their_place():
    # Bucket 0: beyond the newborn gate (the east estimate says sigma_x 0.17 m) -> two ids, as on seed 23.
    state = FusionState()
    s = fuse_bucket(state, 0, [_obs("west", "w1", 0, [_est(1, NEAR_XY, 0.005)]),
                               _obs("east", "w2", 0, [_est(4, FAR_XY, 0.03)])], MapConfig())
    assert [p.id for p in s.people] == [1, 4]
    # Bucket 1: each worker holds both (hand-overs); the east worker says its 4 is the west's 1.
    both = [_est(1, NEAR_XY, 0.005), _est(4, FAR_XY, 0.03)]
    s = fuse_bucket(state, 1, [_obs("west", "w1", 1, both), _obs("east", "w2", 1, both, same=[(4, 1)])], MapConfig())
    assert s.aliases == {4: 1} and [p.id for p in s.people] == [1]
    assert (s.people[0].x, s.people[0].y) == pytest.approx(NEAR_XY, abs=0.01)


def test_the_map_does_not_fold_old_ids_nor_when_off():
    for cfg, frame in ((MapConfig(), 6), (MapConfig(same_blob_iou=0), 1)):
        state = FusionState()
        fuse_bucket(state, 0, [_obs("west", "w1", 0, [_est(1, NEAR_XY, 0.005)]),
                               _obs("east", "w2", 0, [_est(4, FAR_XY, 0.03)])], cfg)
        both = [_est(1, NEAR_XY, 0.005), _est(4, FAR_XY, 0.03)]
        s = fuse_bucket(state, frame, [_obs("west", "w1", frame, both),
                                       _obs("east", "w2", frame, both, same=[(4, 1)])], cfg)
        assert not s.aliases and [p.id for p in s.people] == [1, 4], (cfg.same_blob_iou, frame)
