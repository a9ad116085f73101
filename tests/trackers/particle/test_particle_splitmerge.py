"""Splitting a filter on two objects and merging two filters on one."""

from __future__ import annotations

import numpy as np

from particle_scenes import make_scene, run, tracker_for



def test_people_entering_together_then_parting_get_two_tracks():
    """Two people come in side by side (0.5 m apart, across the line of sight), then walk apart."""
    scene = make_scene(entry=False)

    def pair(t):
        y = 5.5 - 0.8 * t
        s = 0.25 + max(0.0, t - 1.5) * 0.6
        return [(-s, y), (s, y)]

    tracker, bgs = tracker_for(scene)
    out = run(tracker, scene, bgs, pair, 45)
    t, truth, tracks = out[-1]
    assert len(tracks) == 2
    for x, y in truth:
        assert min(np.hypot(tr.x - x, tr.y - y) for tr in tracks) < 0.15
    assert len({tr.id for _, _, tr_ in out for tr in tr_}) == 2


def test_one_filter_on_two_people_is_split_when_they_part():
    scene = make_scene(entry=False)
    tracker, bgs = tracker_for(scene, detection__births="none")

    def parting(t):
        s = 0.15 + 0.5 * t
        return [(-s, 3.0), (s, 3.0)]

    tracker.init_track(0.0, 3.0, spread=0.15)
    out = run(tracker, scene, bgs, parting, 25)
    t, truth, tracks = out[-1]
    assert len(tracks) == 2
    for x, y in truth:
        assert min(np.hypot(tr.x - x, tr.y - y) for tr in tracks) < 0.15


def test_duplicate_filters_on_one_person_are_merged():
    scene = make_scene(entry=False)
    tracker, bgs = tracker_for(scene, detection__births="none", explain__filters="detection")
    tracker.init_track(0.0, 3.0)
    tracker.init_track(0.1, 3.05)
    out = run(tracker, scene, bgs, lambda t: [(0.0, 3.0)], 8)
    assert [tr.id for tr in out[-1][2]] == [1]


def test_filters_one_behind_the_other_on_the_floor_are_merged_only_if_it_lasts():
    """Two filters whose image boxes overlap (0.86 of the smaller box here) are merged after
    ``merge.after_s`` if they stand within ``merge.distance_m`` on the floor, else after
    ``merge.far_after_s``: one camera's boxes also overlap while two people pass one behind the other.
    The merge ends the younger track. The waits are seconds: frames at the real frame interval."""
    scene = make_scene(entry=False)

    def frames_to_merge(second, dt=0.1, **options):
        tracker, _ = tracker_for(scene, detection__births="none", **options)
        tracker.init_track(0.0, 3.0)
        tracker.init_track(*second)
        for k in range(1, 30):
            # the filters stay where they were put
            tracker.merger.merge(list(tracker.clouds.values()), tracker.position_map, dt, tracker._end)
            if len(tracker.clouds) < 2:
                assert list(tracker.clouds) == [1] and [p.id for p in tracker.position_map] == [1]
                return k
        return None

    assert frames_to_merge((0.1, 3.3)) == 3                    # 0.32 m apart: one object
    assert frames_to_merge((0.1, 4.0)) == 6                    # 1.0 m apart: one behind the other
    assert frames_to_merge((0.1, 4.0), merge__far_after_s=0.9) == 9
    assert frames_to_merge((0.1, 4.0), merge__distance_m=np.inf) == 3   # boxes alone (the former rule)
    assert frames_to_merge((1.0, 3.0)) is None                 # side by side: boxes apart
    # Beyond ``merge.depth_m`` from the camera the distance that counts as one object grows with it:
    # the pair stands 4 and 5 m from the camera, 1 m apart: one object when depth_m is 2 m
    # (0.6 m × 4.5 / 2 = 1.35 m), still one behind the other when it is 4 m (0.6 m × 4.5 / 4 = 0.68 m).
    assert frames_to_merge((0.1, 4.0), merge__depth_m=2.0) == 3
    assert frames_to_merge((0.1, 4.0), merge__depth_m=4.0) == 6
    # The same 0.3 s and 0.6 s at 25 and 7 frames/s.
    assert frames_to_merge((0.1, 3.3), dt=0.04) == 8 and frames_to_merge((0.1, 4.0), dt=0.04) == 15
    assert frames_to_merge((0.1, 3.3), dt=1 / 7) == 3 and frames_to_merge((0.1, 4.0), dt=1 / 7) == 5


def test_a_cloud_is_split_after_split_after_s_at_any_frame_rate():
    """A cloud of two lumps side by side is due for splitting once it has been two lumps for
    ``split.after_s`` (0.2 s): at least that long, 2 frames at 10 frames/s, 2 at 7, 5 at 25; one lump never is."""
    from worldtrack.trackers.base import PositionMap
    from worldtrack.trackers.particle.cloud import Cloud, CloudStack

    scene = make_scene(entry=False)
    tracker, _ = tracker_for(scene, detection__births="none")
    rng = np.random.default_rng(3)
    two = np.column_stack([np.r_[rng.normal(-0.4, 0.05, 250), rng.normal(0.4, 0.05, 250)],
                           rng.normal(3.0, 0.05, 500), np.zeros(500)])
    one = two.copy()
    one[:, 0] = rng.normal(0.0, 0.05, 500)

    def frames_to_split(xyz, dt):
        pm = PositionMap()
        p = pm.add(0.0, 3.0, mode="tracking")
        c = Cloud(xyz, np.zeros_like(xyz), person=p.id)
        for k in range(1, 12):
            if tracker.splitter.due([c], [p], CloudStack(), k * dt, dt):
                return k
        return None

    assert [frames_to_split(two, dt) for dt in (0.1, 1 / 7, 0.04)] == [2, 2, 5]
    assert frames_to_split(one, 0.1) is None
