"""Candidates two workers confirm together (worldtrack.map.affirm), on a real Redis server: a person
one worker proposes but cannot confirm alone (right under its camera) is confirmed when another
worker's camera shows somebody at that place, and only then."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from worldtrack.geometry.camera import Camera
from worldtrack.map.config import MapConfig
from worldtrack.map.connection import MapKeys, connect
from worldtrack.map.evidence import people_boxes
from worldtrack.map.messages import MapState
from worldtrack.map.shared_ids import SharedPositionMap
from worldtrack.map.worker import MapLink

#: The far camera sees the place 8 m away; the near one stands 1 m from it, looking down the room.
FAR = Camera.look_at("west", 320, 240, [0.0, 0.0, 3.0], [4.0, 0.0, 0.0], hfov_deg=60)
NEAR = Camera.look_at("east", 320, 240, [9.0, 0.0, 3.0], [4.0, 0.0, 0.0], hfov_deg=60)
PLACE = np.array([8.0, 0.0])
T0 = 1.0e9            # capture times are wall-clock seconds (stream ids, retention: not near 0)
#: The map as the workers read it: which cameras have reported (whose observations they read).
STATE = MapState(T0, (), reports=(("east", T0, T0), ("west", T0, T0)))


def _worker(url: str, name: str, camera: Camera, mask: np.ndarray | None, cfg: MapConfig):
    link = MapLink(connect(url), MapKeys(), cfg, name, {camera.id: camera})
    link.register()
    assert link.leases[camera.id].acquire()
    tracker = SimpleNamespace(position_map=SharedPositionMap(link.new_id),
                              overlay=lambda c: SimpleNamespace(mask=mask))
    return link, tracker


def _step(link: MapLink, tracker, t: float, tracks=()) -> tuple:
    """One worker step without an image tracker, on live cameras as MapTracker runs it: read the
    other cameras' newest observations (after the previous step's publish), sync, publish."""
    if link.exchange is not None:
        link.exchange.read(STATE)
    link.sync(tracker, t)
    cam = next(iter(link.cameras))
    obs = link.observations(tracker, list(tracks), t, {cam: SimpleNamespace(t=t, index=int(round((t - T0) * 10)))})
    link.publish(obs)
    return obs[0]


def _somebody_at(xy: np.ndarray) -> np.ndarray:
    mask = np.zeros((240, 320), np.uint8)
    u0, v0, u1, v1 = np.clip(people_boxes(FAR, np.array([[*xy, 1.7, 0.45]]))[0, :4], 0, 319).astype(int)
    mask[v0:v1, u0:u1] = 1
    return mask


def _run(url: str, far_mask: np.ndarray, cfg: MapConfig = MapConfig(), far_tracks=()):
    """The near worker proposes a candidate at PLACE at T0; the far worker (its mask ``far_mask``)
    steps 0.1 s later; the near worker 0.2 s later. Returns the near map, the far worker's
    observation and the near worker's first observation."""
    near, near_tracker = _worker(url, "w-east", NEAR, None, cfg)
    far, far_tracker = _worker(url, "w-west", FAR, far_mask, cfg)
    near_tracker.position_map.add(*PLACE, 1.7, 0.45, time=T0, tentative=True)
    first = _step(near, near_tracker, T0)
    seen = _step(far, far_tracker, T0 + 0.1, far_tracks)
    if near.exchange is not None:
        near.exchange.read(STATE)
    near.sync(near_tracker, T0 + 0.2)
    return near_tracker.position_map, seen, first


def test_a_candidate_another_workers_camera_shows_somebody_at_is_confirmed(redis_url):
    local, far_obs, near_obs = _run(redis_url, _somebody_at(PLACE))
    assert near_obs.candidates == ((8.0, 0.0, 1.7, 0.45),)
    assert far_obs.affirms == (("w-east", 8.0, 0.0),)
    [p] = list(local)
    assert p.id > 0 and p.confirmed and p.mode == "tracking" and (p.x, p.y) == (8.0, 0.0)


def test_a_candidate_is_not_confirmed_on_an_empty_view_nor_on_somebody_elsewhere_nor_when_off(redis_url):
    import redis
    empty = np.zeros((240, 320), np.uint8)
    for mask, cfg in ((empty, MapConfig()), (_somebody_at(PLACE + [0.0, 1.5]), MapConfig()),
                      (_somebody_at(PLACE), MapConfig(affirm_candidates=False))):
        redis.Redis.from_url(redis_url).flushall()
        local, far_obs, _ = _run(redis_url, mask, cfg)
        assert far_obs.affirms == () and [p.id for p in local] == [-1]


def test_the_far_worker_does_not_affirm_a_person_it_already_tracks(redis_url):
    held = SimpleNamespace(x=8.0, y=0.4, height=1.7, width=0.45, id=3)      # 0.4 m aside: their box leaves room
    local, far_obs, _ = _run(redis_url, _somebody_at(PLACE), far_tracks=[held])
    assert far_obs.affirms == () and [p.id for p in local] == [-1]


@pytest.mark.parametrize("radius", [0.5])
def test_only_the_candidates_own_worker_confirms_it(redis_url, radius):
    from worldtrack.map.affirm import confirm_affirmed
    from worldtrack.map.messages import Observation
    from worldtrack.trackers.base import PositionMap
    m = PositionMap()
    m.add(*PLACE, time=0.0, tentative=True)
    m.add(*(PLACE + [0.0, 2.0]), time=0.0, tentative=True)
    to_other = Observation("west", 0.1, "w-west", 1, 0.1, affirms=(("w-north", 8.0, 0.0),))
    own = Observation("east", 0.1, "w-east", 1, 0.1, affirms=(("w-east", 8.0, 0.0),))
    assert confirm_affirmed(m, [to_other, own], "w-east", 0.2, radius) == []     # not for it; its own camera's
    mine = Observation("west", 0.1, "w-west", 1, 0.1, affirms=(("w-east", 8.2, 0.3),))
    assert confirm_affirmed(m, [mine], "w-east", 0.2, radius) == [1]
    assert sorted(p.id for p in m) == [-2, 1]                                    # the one 2 m away stays
