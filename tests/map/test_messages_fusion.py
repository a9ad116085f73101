"""Message formats and the fusion rule, without a server (pure functions)."""

import math
import time

import numpy as np
import pytest

from worldtrack.errors import InputError
from worldtrack.map.config import MapConfig, map_settings
from worldtrack.map.connection import hide_passwords, redacted, with_credentials
from worldtrack.map.fusion import FusionState, floor_information, fuse_bucket, provisional_state
from worldtrack.map.messages import (Estimate, MapPerson, MapState, Observation, decode_map_state,
                                     decode_observation, encode_map_state, encode_observation)


def est(pid, x, y, support=0.8, seen=True, info=(1.0, 0.0, 1.0)):
    return Estimate(pid, x, y, 1.7, 0.45, 0.0, 0.0, 0.5, support, seen, *info)


def obs(cam, t, worker, people, ended=()):
    return Observation(cam, t, worker, int(t * 10), t + 0.01, tuple(people), tuple(ended))


def test_observation_and_map_state_round_trip_with_nan():
    o = obs("cam1", 12.34, "w", [Estimate(3, 1.25, 2.5, 1.7, 0.45, 0.1, -0.2, 0.7, float("nan"), False, 40.0, -3.0, 900.0)],
            ended=[5])
    back = decode_observation(encode_observation(o))
    assert back.people[0].id == 3 and back.people[0].seen is False and math.isnan(back.people[0].support)
    assert back.people[0][:4] == (3, 1.25, 2.5, 1.7) and back.people[0].iyy == 900.0 and back.ended == (5,)
    assert math.isnan(back.people[0].cxx)                         # no covariance from the tracker
    measured = Estimate(3, 1.0, 2.0, 1.7, 0.45, 0, 0, 0.7, 0.8, True, 40.0, -3.0, 900.0, 1.0, 0.09, -0.01, 0.0025)
    assert decode_observation(encode_observation(obs("cam1", 1.0, "w", [measured]))).people[0] == measured
    # A worker from before the covariance (14 columns) still reads: NaN covariance.
    old = decode_observation({"v": "2", "t": "1.0", "o": '["c", "w", 1, 1.0, [[1, 2, 3, 1.7, 0.45, 0, 0, 0.5, 0.6, '
                                                       '1, 10, 0, 10, 1.0]], []]'})
    assert old.people[0].x == 2 and math.isnan(old.people[0].cyy)
    s = MapState(12.3, (MapPerson(3, 1.0, 2.0, 1.7, 0.45, 0.0, 0.0, 0.5, 0.6, "lost", 11.0, 3.0, 1),),
                 (("cam1", 12.34, 12.35),), {7: 3}, 12.5, 2)
    assert decode_map_state(encode_map_state(s)) == s


@pytest.mark.parametrize("fields, problem", [({"v": "0"}, "format version"), ({"v": "2", "t": "1"}, "KeyError"),
                                             ({"v": "2", "t": "1", "o": '["c", "w", 1, 1.0, [[1, 2]'}, "JSONDecodeError"),
                                             ({"v": "2", "t": "1", "o": '["c", "w", 1, 1.0, [[1, 2]], []]'},
                                              "IndexError")])
def test_malformed_observations_are_named(fields, problem):
    with pytest.raises(ValueError, match=problem):
        decode_observation(fields)


def test_support_and_geometry_weigh_two_workers():
    cfg = MapConfig()
    # Same resolution: the support decides, 0.9 against 0.3.
    s = fuse_bucket(FusionState(), 10, [obs("a", 1.0, "w1", [est(1, 2.0, 0.0, 0.9)]),
                                        obs("b", 1.02, "w2", [est(1, 2.4, 0.0, 0.3)])], cfg)
    assert s.people[0].x == pytest.approx((0.9 * 2.0 + 0.3 * 2.4) / 1.2)
    # A camera that resolves x ten times finer wins along x only.
    s = fuse_bucket(FusionState(), 10, [obs("a", 1.0, "w1", [est(1, 2.0, 1.0, info=(100.0, 0.0, 1.0))]),
                                        obs("b", 1.0, "w2", [est(1, 3.0, 2.0, info=(10.0, 0.0, 1.0))])], cfg)
    assert s.people[0].x == pytest.approx((100 * 2.0 + 10 * 3.0) / 110) and s.people[0].y == pytest.approx(1.5)



def test_a_model_error_along_each_line_of_sight_when_asked():
    # Two cameras looking along x (one axis): w1 resolves x 4x finer by pixels (400 against 100 /m²).
    a, b = est(1, 2.0, 1.0, info=(400.0, 0.0, 4000.0)), est(1, 3.0, 1.2, info=(100.0, 0.0, 4000.0))
    two = [obs("a", 1.0, "w1", [a]), obs("b", 1.0, "w2", [b])]
    p, = fuse_bucket(FusionState(), 10, two, MapConfig()).people
    assert p.x == pytest.approx((400 * 2.0 + 100 * 3.0) / 500)           # off: by pixels alone
    p, = fuse_bucket(FusionState(), 10, two, MapConfig(ray_error_m=0.3)).people
    va, vb = 1 / (0.8 * 400) + 0.09, 1 / (0.8 * 100) + 0.09             # support 0.8; + 0.3² m² along the ray
    assert p.x == pytest.approx((2.0 / va + 3.0 / vb) / (1 / va + 1 / vb))   # about alike: 2.46 m
    assert p.y == pytest.approx(1.1)                                     # across: as before
    # At right angles (w2 looks along y): each fixes the other's depth, as before.
    c = est(1, 3.0, 1.2, info=(4000.0, 0.0, 100.0))
    p, = fuse_bucket(FusionState(), 10, [obs("a", 1.0, "w1", [a]), obs("b", 1.0, "w2", [c])],
                     MapConfig(ray_error_m=0.3)).people
    assert p.x == pytest.approx(3.0, abs=0.01) and p.y == pytest.approx(1.0, abs=0.01)


def test_the_height_from_the_views_that_show_the_person_when_asked():
    a = est(1, 2.0, 1.0)._replace(height=1.60)                 # shows the whole body as its own
    b = est(1, 2.0, 1.0)._replace(height=1.80, own=0.2)        # the person behind somebody: the head only
    two = [obs("a", 1.0, "w1", [a]), obs("b", 1.0, "w2", [b])]
    p, = fuse_bucket(FusionState(), 10, two, MapConfig()).people
    assert p.height == pytest.approx(1.70)                     # off: by support alone (0.8 each)
    p, = fuse_bucket(FusionState(), 10, two, MapConfig(height_by_view=True)).people
    assert p.height == pytest.approx((1.60 + 0.2 * 1.80) / 1.2) and p.x == pytest.approx(2.0)

def test_weighed_by_the_trackers_covariances_when_asked_and_every_estimate_has_one():
    cfg = MapConfig(weigh_by="tracker")
    # w1 measured σ 0.1 m along x, w2 0.3 m: information 100 against 11.1 along x; y equal.
    a = est(1, 2.0, 1.0)._replace(cxx=0.01, cxy=0.0, cyy=0.0025)
    b = est(1, 3.0, 2.0)._replace(cxx=0.09, cxy=0.0, cyy=0.0025)
    p, = fuse_bucket(FusionState(), 10, [obs("a", 1.0, "w1", [a]), obs("b", 1.0, "w2", [b])], cfg).people
    assert p.x == pytest.approx((100 * 2.0 + 3.0 / 0.09) / (100 + 1 / 0.09)) and p.y == pytest.approx(1.5)
    assert p.lead == "w1"                                        # the smaller covariance
    # One estimate without a covariance: support × geometry for both (here equal: the mean).
    p, = fuse_bucket(FusionState(), 10, [obs("a", 1.0, "w1", [a]), obs("b", 1.0, "w2", [est(1, 3.0, 2.0)])],
                     cfg).people
    assert p.x == pytest.approx(2.5)
    # By default (geometry) the covariances are not used.
    p, = fuse_bucket(FusionState(), 10, [obs("a", 1.0, "w1", [a]), obs("b", 1.0, "w2", [b])], MapConfig()).people
    assert p.x == pytest.approx(2.5)


def test_the_live_map_refines_a_bucket_as_reports_come_and_leaves_the_others_as_they_were():
    cfg = MapConfig()
    state = FusionState()
    fuse_bucket(state, 10, [obs("a", 1.0, "w1", [est(1, 2.0, 0.0)]), obs("c", 1.0, "w3", [est(3, 7.0, 1.0)])], cfg)
    committed = state.to_json()
    first = obs("a", 1.1, "w1", [est(1, 2.1, 0.0, 0.9)])
    live = {p.id: p for p in provisional_state(state, {11: [first]}, cfg).people}
    # Person 1 is where w1's report puts them; person 3, whose worker has not reported bucket 11
    # yet, stays where bucket 10 had them, still present (not lost).
    assert live[1].x == pytest.approx(2.1) and live[1].last_seen == pytest.approx(1.1)
    assert live[3].x == 7.0 and live[3].mode == "tracking" and live[3].last_seen == pytest.approx(1.0)
    # w2's later report of person 1 in the same bucket refines it, weighed as in a complete bucket.
    second = obs("b", 1.12, "w2", [est(1, 2.5, 0.0, 0.3)])
    live = {p.id: p for p in provisional_state(state, {11: [first, second]}, cfg).people}
    assert live[1].x == pytest.approx((0.9 * 2.1 + 0.3 * 2.5) / 1.2) and live[1].workers == 2
    assert state.to_json() == committed                         # the committed state is not touched
    # Once complete, the bucket fuses to the same estimate.
    done = {p.id: p for p in fuse_bucket(state, 11, [first, second], cfg).people}
    assert done[1].x == pytest.approx(live[1].x) and done[3].mode == "lost"


def test_held_estimates_count_only_when_nobody_sees_the_person():
    cfg = MapConfig()
    s = fuse_bucket(FusionState(), 10, [obs("a", 1.0, "w1", [est(1, 2.0, 0.0, seen=True)]),
                                        obs("b", 1.0, "w2", [est(1, 5.0, 0.0, seen=False)])], cfg)
    assert s.people[0].x == pytest.approx(2.0) and s.people[0].workers == 1
    s = fuse_bucket(FusionState(), 10, [obs("b", 1.0, "w2", [est(1, 5.0, 0.0, seen=False)])], cfg)
    assert s.people[0].x == pytest.approx(5.0) and s.people[0].mode == "tracking"


def test_lost_forgotten_and_ended():
    cfg = MapConfig(forget_after_s=1.0)
    st = FusionState()
    fuse_bucket(st, 10, [obs("a", 1.0, "w1", [est(1, 2.0, 0.0), est(2, 4.0, 0.0)])], cfg)
    s = fuse_bucket(st, 11, [obs("a", 1.1, "w1", [est(2, 4.0, 0.0)])], cfg)
    assert [(p.id, p.mode) for p in s.people] == [(1, "lost"), (2, "tracking")]
    assert [p.id for p in s.present()] == [2]
    s = fuse_bucket(st, 12, [obs("a", 1.2, "w1", [], ended=[2])], cfg)       # walked out of the door
    assert [p.id for p in s.people] == [1]
    s = fuse_bucket(st, 21, [obs("a", 2.1, "w1", [])], cfg)                   # 1.1 s unseen > forget_after_s
    assert s.people == ()


def test_two_ids_of_one_person_from_two_workers_merge_into_the_elder():
    cfg = MapConfig(merge_after_s=0.25)
    st = FusionState()
    fuse_bucket(st, 10, [obs("a", 1.0, "w1", [est(4, 2.0, 0.0)])], cfg)
    merged = None
    for b in range(11, 16):
        s = fuse_bucket(st, b, [obs("a", b / 10, "w1", [est(4, 2.0, 0.0)]), obs("b", b / 10, "w2", [est(9, 2.2, 0.0)])],
                        cfg)
        merged = merged or (s.aliases or None)
    assert merged == {9: 4} and [p.id for p in s.people] == [4]
    # Later observations under the merged id land on the elder.
    s = fuse_bucket(st, 16, [obs("b", 1.6, "w2", [est(9, 2.1, 0.0)])], cfg)
    assert [p.id for p in s.present()] == [4]
    # The same worker holding two people close together: two people, never merged.
    st2 = FusionState()
    for b in range(10, 20):
        s = fuse_bucket(st2, b, [obs("a", b / 10, "w1", [est(1, 2.0, 0.0), est(2, 2.2, 0.0)])], cfg)
    assert [p.id for p in s.people] == [1, 2]


def test_two_workers_starting_the_same_person_together_are_merged_at_once():
    cfg = MapConfig(merge_after_s=0.2)
    s = fuse_bucket(FusionState(), 10, [obs("a", 1.0, "w1", [est(4, 2.0, 0.0)]),
                                        obs("b", 1.0, "w2", [est(9, 2.2, 0.0)])], cfg)
    assert s.aliases == {9: 4} and [p.id for p in s.people] == [4]


def test_two_people_crossing_in_one_workers_view_are_not_merged_when_another_worker_sees_one():
    # w2 sees both people (ids 1 and 2) as they cross; w1 sees only person 1 (2 is behind 1 there).
    cfg = MapConfig(merge_after_s=0.2)
    st = FusionState()
    for b in range(10, 20):
        s = fuse_bucket(st, b, [obs("a", b / 10, "w1", [est(1, 2.0, 0.0)]),
                                obs("b", b / 10, "w2", [est(1, 2.0, 0.0), est(2, 2.2, 0.0)])], cfg)
        assert not s.aliases
    assert [p.id for p in s.people] == [1, 2]


def test_fusion_state_survives_json():
    cfg = MapConfig()
    st = FusionState()
    fuse_bucket(st, 10, [obs("a", 1.0, "w1", [est(1, 2.0, 0.0)]), obs("b", 1.0, "w2", [est(2, 2.1, 0.0)])], cfg)
    back = FusionState.from_json(st.to_json())
    assert back.people == st.people and back.close_since == st.close_since and back.last_bucket == 10


def test_floor_information_is_finer_near_the_camera_and_along_its_image_plane():
    from worldtrack.geometry.camera import Camera
    cam = Camera.look_at("c", 320, 240, [0.0, 0.0, 3.0], [4.0, 0.0, 0.0], hfov_deg=60)
    near = floor_information([cam], np.array([2.5, 0.0]), 1.7)
    far = floor_information([cam], np.array([6.0, 0.0]), 1.7)
    assert near[0] > 4 * far[0] and near[2] > far[2]
    assert far[2] > far[0]              # across the line of sight resolves better than along it
    assert all(math.isnan(v) for v in floor_information([cam], np.array([-3.0, 0.0]), 1.7))   # behind it


def test_a_person_behind_another_is_resolved_worse_along_the_line_of_sight():
    from worldtrack.geometry.camera import Camera
    from worldtrack.map.fusion import people_boxes
    cam = Camera.look_at("c", 320, 240, [0.0, 0.0, 3.0], [4.0, 0.0, 0.0], hfov_deg=60)
    front = people_boxes(cam, np.array([[3.0, 0.0, 1.7, 0.45]]))
    u0, v0, u1, v1, dist = front[0]
    assert dist == pytest.approx(3.0) and u0 < 160 < u1 and v0 < 120 < v1          # a box around the image's centre
    free = floor_information([cam], np.array([6.0, 0.0]), 1.7)
    behind = floor_information([cam], np.array([6.0, 0.0]), 1.7, blockers=[front])
    assert behind[0] < 0.8 * free[0]            # feet hidden: depth along the line of sight resolves worse
    ahead = floor_information([cam], np.array([2.0, 0.0]), 1.7, blockers=[front])
    assert ahead == floor_information([cam], np.array([2.0, 0.0]), 1.7)     # in front of the other: unchanged
    beside = np.array([6.0, 2.5])
    assert floor_information([cam], beside, 1.7, blockers=[front]) == floor_information([cam], beside, 1.7)
    assert people_boxes(cam, np.array([[-2.0, 0.0, 1.7, 0.45]]))[0, 4] == np.inf   # behind the camera: no box


def test_passwords_never_shown_and_taken_from_the_environment():
    assert redacted("redis://u:pw@h:1/0") == "redis://u:***@h:1/0"
    assert hide_passwords("x rtsp://a:b@c/d redis://h:1") == "x rtsp://a:***@c/d redis://h:1"
    env = {"WORLDTRACK_REDIS_USER": "trk", "WORLDTRACK_REDIS_PASSWORD": "s3 cr/et"}
    assert with_credentials("rediss://h:6380/2", env) == "rediss://trk:s3%20cr%2Fet@h:6380/2"
    assert with_credentials("redis://me:mine@h/0", env) == "redis://me:mine@h/0"     # the URL's own win


def test_map_settings_errors_name_the_field():
    assert map_settings(sets=["map.lease_s=2", "map.renew_s=0.5"]).renew_s == 0.5
    with pytest.raises(InputError, match=r"^map.renew_s: expected at most half of lease_s"):
        map_settings(sets=["map.renew_s=0.9"])
    with pytest.raises(InputError, match=r"^--set ellipsoid.x: only the map's settings"):
        map_settings(sets=["ellipsoid.x=1"])


def test_which_worker_starts_a_person_from_the_maps_estimate():
    from types import SimpleNamespace

    from worldtrack.map.worker import MapLink

    def follows(rule, workers, lead, mine=True):
        link = SimpleNamespace(cfg=MapConfig(share_rule=rule), mine_seen={7} if mine else set(), name="w1")
        p = MapPerson(7, 1.0, 2.0, 1.7, 0.45, 0.0, 0.0, 0.5, 0.6, "tracking", 1.0, 0.0, workers, lead)
        return MapLink._follows_map(link, p)
    assert follows("information", 1, "w1", mine=False) and follows("support-lead", 1, "w1", mine=False)  # not shown
    assert not follows("information", 1, "w1") and not follows("support-lead", 1, "w1")   # its own person alone
    # Seen by two workers: under the information rule both start from the map's estimate, even the lead.
    assert follows("information", 2, "w1") and follows("information", 2, "w2")
    assert not follows("support-lead", 2, "w1") and follows("support-lead", 2, "w2")


class _Record:
    """The map stream of a batch run, as far as a worker's read of the record needs (no server)."""

    def __init__(self):
        self.entries: list[tuple[str, dict]] = []

    def register_script(self, _):
        return None

    def add(self, bucket: int, aliases: dict) -> None:
        state = MapState(bucket / 10, (MapPerson(4, 1.0, 2.0, 1.7, 0.45, 0.0, 0.0, 0.5, 0.6, "tracking", 0.0, 0.0, 1),),
                         aliases=aliases)
        self.entries.append((f"{bucket * 100}-0", encode_map_state(state)))

    def xrevrange(self, _key, count):
        return self.entries[::-1][:count]

    def xrange(self, _key, min, max):
        return [e for e in self.entries if int(e[0].split("-")[0]) > int(min[1:].split("-")[0])]


def test_a_batch_worker_does_not_miss_a_merge_between_two_steps():
    from worldtrack.map.connection import MapKeys
    from worldtrack.map.worker import MapLink
    record = _Record()
    link = MapLink(record, MapKeys(), MapConfig(), "w1", {})
    link.lockstep = True
    record.add(0, {9: 4})                      # id 9 merged into 4 in bucket 0
    record.add(1, {})
    assert link.read_map().aliases == {9: 4}   # the first read takes the recent records, not only the newest
    record.add(2, {11: 4})
    record.add(3, {})
    link.read_map()                            # the lockstep wait reads more than once before a step
    record.add(4, {})
    assert link.read_map().aliases == {9: 4, 11: 4}
    for b in range(5, 40):
        record.add(b, {})
    assert link.read_map().aliases == {}       # forgotten after forget_after_s (3 s)


def test_a_worker_renames_its_copy_of_a_merged_person_and_keeps_tracking_it():
    from types import SimpleNamespace

    from worldtrack.map.connection import MapKeys
    from worldtrack.map.shared_ids import SharedPositionMap
    from worldtrack.map.worker import MapLink
    record = _Record()
    link = MapLink(record, MapKeys(), MapConfig(), "w1", {})
    link.lockstep = True
    local = SharedPositionMap(lambda x, y: 100)
    mine = local.add(1.0, 2.0, track_id=9, mode="tracking")
    link.mine_seen = {9}
    record.add(0, {9: 4})                            # the map folded this worker's 9 into 4
    link.sync(SimpleNamespace(position_map=local), 0.05)
    assert [p.id for p in local] == [4] and local[4] is mine and link.mine_seen == {4}


def test_new_ids_do_not_depend_on_which_worker_asks_first(redis_url):
    """Ids from each worker's slot (the scene index of its first camera): the same in any order of
    asking, never one id twice, and a standby for the same cameras continues the slot's counter."""
    from worldtrack.map.connection import MapKeys, connect
    from worldtrack.map.worker import MapLink
    client, scene = connect(redis_url), ["west", "east", "north"]

    def run(order):
        client.flushdb()
        links = {"a": MapLink(client, MapKeys(), MapConfig(), "a", {"west": None}, scene_cameras=scene),
                 "b": MapLink(client, MapKeys(), MapConfig(), "b", {"north": None, "east": None}, scene_cameras=scene)}
        got = {"a": [], "b": []}
        for who in order:
            got[who].append(links[who].new_id(0.0, 0.0))
        return got
    first, second = run("ababb"), run("bbaab")
    assert first == second == {"a": [1, 4], "b": [2, 5, 8]}
    standby = MapLink(client, MapKeys(), MapConfig(), "c", {"east": None}, scene_cameras=scene)
    assert standby.new_id(0.0, 0.0) == 11                       # b's slot, after b's 8
    assert MapLink(client, MapKeys(), MapConfig(), "d", {"west": None}).new_id(0.0, 0.0) == 1  # no scene: one counter


def test_a_batch_worker_waits_for_the_map_of_its_first_frame_before_its_second():
    from worldtrack.map.connection import MapKeys
    from worldtrack.map.worker import MapLink
    link = MapLink(_Record(), MapKeys(), MapConfig(), "w1", {}, fps=10.0)
    link.lockstep, link.lockstep_wait_s = True, 0.3
    t0 = time.monotonic()
    link._wait_for_map(100.05)                 # frame 0: nothing to wait for
    assert time.monotonic() - t0 < 0.1
    link._wait_for_map(100.15)                 # frame 1: bucket 0 is not in the record, so it waits
    assert time.monotonic() - t0 >= 0.3


def test_the_worker_that_shows_a_person_as_their_own_weighs_more_and_leads():
    """Two workers see person 7: w1 whole (own share 1.0, support 0.4), w2 mostly behind somebody
    it holds (own 0.3, support 0.9). Weighed by support × own share w1 counts more and leads."""
    a = Observation("west", 5.02, "w1", 50, 5.03, (Estimate(7, 1.0, 2.0, 1.7, 0.45, 0, 0, 0.8, 0.4, True, own=1.0),))
    b = Observation("east", 5.04, "w2", 50, 5.05, (Estimate(7, 1.4, 2.0, 1.7, 0.45, 0, 0, 0.8, 0.9, True, own=0.3),))
    p, = fuse_bucket(FusionState(), 50, [a, b], MapConfig(weigh_own=True)).people     # opt-in (issue-39h)
    assert p.lead == "w1" and p.x == pytest.approx((0.4 * 1.0 + 0.27 * 1.4) / 0.67)
    q, = fuse_bucket(FusionState(), 50, [b, a], MapConfig()).people     # by support alone (default)
    assert q.lead == "w2" and q.x == pytest.approx((0.4 * 1.0 + 0.9 * 1.4) / 1.3)


def test_a_far_views_first_estimate_merges_with_a_near_views_within_their_covariances():
    # Frame 0: the west worker starts a person 2 m from its camera (sigma_x 0.07 m), the east worker
    # the same person through the door 10 m away, 0.56 m off along its line of sight (sigma_x 0.24 m):
    # beyond merge_distance_m, within the 99 % gate of their covariances -> one person at once.
    near = est(1, 2.02, 3.34)._replace(cxx=0.0053, cxy=0.0, cyy=0.0019)
    far = est(2, 1.46, 3.37)._replace(cxx=0.057, cxy=0.0, cyy=0.0029)
    s = fuse_bucket(FusionState(), 0, [obs("west", 0.0, "w1", [near]), obs("east", 0.0, "w2", [far])], MapConfig())
    assert s.aliases == {2: 1} and [p.id for p in s.people] == [1]
    # Two sure estimates 0.56 m apart are two people; so are these with the gate off, with a
    # worker holding both, with no covariance, or once they are older than merge_after_s.
    sure = far._replace(cxx=0.0053, cyy=0.0019)
    cases = [([obs("west", 0.0, "w1", [near]), obs("east", 0.0, "w2", [sure])], MapConfig(), FusionState()),
             ([obs("west", 0.0, "w1", [near]), obs("east", 0.0, "w2", [far])], MapConfig(newborn_gate=0), FusionState()),
             ([obs("west", 0.0, "w1", [near, far]), obs("east", 0.0, "w2", [far])], MapConfig(), FusionState()),
             ([obs("west", 0.0, "w1", [near]), obs("east", 0.0, "w2", [est(2, 1.46, 3.37)])], MapConfig(), FusionState())]
    old = FusionState()
    fuse_bucket(old, 0, [obs("west", 0.0, "w1", [near])], MapConfig())
    fuse_bucket(old, 1, [obs("east", 0.1, "w2", [far._replace(id=2)])], MapConfig())
    cases.append(([obs("west", 0.5, "w1", [near]), obs("east", 0.5, "w2", [far])], MapConfig(), old))
    for k, (observations, cfg, st) in enumerate(cases):
        s = fuse_bucket(st, 5 if st is old else 0, observations, cfg)
        assert not s.aliases and sorted(p.id for p in s.people) == [1, 2], k
