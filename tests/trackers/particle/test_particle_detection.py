"""Detection filters (§3.2) and the ends of tracks: entry regions (also doors out of view), leaving
through an exit, and watching where a track was lost."""

from __future__ import annotations

import numpy as np
import pytest

from worldtrack.errors import InputError
from worldtrack.scene import scene_from_dict
from worldtrack.trackers.particle import ParticleConfig, ParticleTracker

from particle_scenes import CAM, FPS, HEIGHT, WIDTH, foregrounds, make_scene, run, tracker_for


def test_a_door_out_of_view_is_watched_where_its_floor_comes_into_view():
    """The only door is on floor the camera does not see (x < −6.2 at y = 3.8–4.8; the view's left
    edge is at x ≈ −4 there, more than ``entry_margin_m`` away). A person walks in from it along
    y = 4.3. The door's detection filter covers the floor in view next to the floor out of view
    near it (``entry_reach_m``), so the person gets a track soon after showing; without it the
    door is not watched at all, and the tracker says so."""
    d = {"name": "particle-test", "cameras": [CAM], "people": {"height": HEIGHT, "width": WIDTH},
         "floor": {"walkable": [{"outer": [[-7, 0.5], [3, 0.5], [3, 6.5], [-7, 6.5]]}]},
         "entry_regions": [{"name": "side", "polygon": [[-7, 3.8], [-6.2, 3.8], [-6.2, 4.8], [-7, 4.8]]}]}
    scene = scene_from_dict(d)
    cam = scene.cameras["cam"]

    def walker_from_side(t):
        return [(-6.6 + 1.0 * t, 4.3)]

    tracker, bgs = tracker_for(scene)
    side = [r for r in tracker.detection.detectors if r.region.name == "side"]
    assert len(side) == 1
    cells = side[0].region
    j, i = np.nonzero(cells.raster.inside)
    xy = cells.origin + (np.column_stack([i, j]) + 0.5) * cells.raster.resolution
    assert np.all(tracker.detection.in_view(xy))
    assert xy[:, 0].max() < -6.2 + 2.0 + 1.0 + 0.05              # within reach + margin of the door
    # Fully in view (feet and head in the image) from:
    shown = next(k for k in range(40) if all(cam.in_image(cam.project(
        np.array([[*walker_from_side(k / FPS)[0], z]])))[0] for z in (0.0, HEIGHT)))
    out = run(tracker, scene, bgs, walker_from_side, shown + 12)
    first = next(k for k, (_, _, tracks) in enumerate(out) if tracks)
    assert first <= shown + 5
    t, truth, tracks = out[-1]
    assert len(tracks) == 1 and np.hypot(tracks[0].x - truth[0][0], tracks[0].y - truth[0][1]) < 0.15
    with pytest.raises(InputError, match="no entry region of scene 'particle-test' is in view"):
        tracker_for(scene, detection__entry_reach_m=0.0)


def _walks_out_and_waits(wait_until):
    """Walks left from x = −1 at 1 m/s out through the door region to the floor's edge (x = −3),
    stands at x = −2.85 until ``wait_until`` s, then is gone."""
    return lambda t: [(max(-1.0 - 1.0 * t, -2.85), 3.0)] if t < wait_until else []


def test_a_track_leaving_through_the_exit_ends_and_is_not_detected_again():
    # The object velocity: the person stops 0.15 m from the floor's edge, and the particles' own
    # velocities (motion.model="state") slow down with them, so 0.3 s ahead may end short of the edge.
    scene = make_scene()
    tracks_by_frame = {}
    for name, options in (("exit", {}), ("no exit rule", {"tracking__exit_lookahead_s": 0.0}),
                          ("no hold", {"tracking__exit_hold_s": 0.0})):
        tracker, bgs = tracker_for(scene, motion__model="object", **options)
        tracker.init_track(-1.0, 3.0)
        out = run(tracker, scene, bgs, _walks_out_and_waits(2.25), 35)
        tracks_by_frame[name] = [[tr.id for tr in tracks] for _, _, tracks in out]
    exit_, no_rule, no_hold = (tracks_by_frame[k] for k in ("exit", "no exit rule", "no hold"))
    # Followed through the door; ended near the floor's edge (x ≈ −2.7 at 1.7 s: 0.3 s ahead is off
    # the floor), and the person still standing there for 0.45 s is not detected as somebody new.
    assert exit_[16] == [1]
    last = max(k for k, ids in enumerate(exit_) if ids)
    assert 16 <= last <= 19
    assert all(not ids for ids in exit_[last + 1:])
    # Without the rule the filter stays on the person at the edge, past their last frame (22).
    assert no_rule[22] == [1]
    # Without the hold, the person at the edge is detected again as a new track.
    assert any(ids and ids[0] != 1 for ids in no_hold[last + 1:])


def test_exit_rule_needs_an_entry_region_and_outward_motion():
    scene = make_scene()
    tracker, _ = tracker_for(scene)
    tracker.init_track(-2.85, 3.0)
    tr = tracker.position_map[1]
    for (x, vx, vy), leaving in (((-2.85, -1.0, 0.0), True),    # in the door, walking off the edge
                                 ((-2.85, 1.0, 0.0), False),    # in the door, walking in
                                 ((-2.85, -0.2, 0.0), False),   # too slow to be walking out
                                 ((-2.5, -1.0, 0.0), False),    # 0.2 s ahead still on the floor
                                 ((2.85, 1.0, 0.0), False)):    # off the right edge, no entry region there
        tr.x, tr.vx, tr.vy = x, vx, vy
        assert tracker.life.leaving([tr]).tolist() == [leaving], (x, vx, vy)
    tr.x, tr.vx = -2.85, -1.0
    assert tracker.life.leaving([tr, tr]).tolist() == [True, True]      # several tracks at once
    paper = ParticleTracker(scene, foregrounds(scene)[0], ParticleConfig.paper())
    assert paper.life.leaving([tr]).tolist() == [False]


def test_tracks_held_after_an_exit_are_forgotten_after_the_hold_even_without_detection():
    scene = make_scene()
    tracker, bgs = tracker_for(scene, detection__births="none")
    tracker.init_track(-1.0, 3.0)
    out = run(tracker, scene, bgs, lambda t: [(-1.0 - 1.0 * t, 3.0)] if t < 1.95 else [], 21)
    assert not out[-1][2] and len(tracker.life.exited) == 1      # ended at the edge, held
    for k in range(21, 29):                                   # 0.8 s later: past exit_hold_s
        tracker.step({"cam": bgs["cam"]}, k / FPS)
    assert tracker.life.exited == []


def _watches(tracker):
    return [d for d in tracker.detection.detectors if d.until is not None]


def test_a_track_lost_mid_room_is_watched_there_for_lost_hold_s_and_not_after():
    scene = make_scene()
    tracker, bgs = tracker_for(scene, detection__births="entry+lost", tracking__end_after_s=0.0,
                               detection__lost_radius_m=0.8, detection__lost_hold_s=1.0)
    assert len(tracker.detection.detectors) == 1 and not _watches(tracker)      # the door's
    tracker.init_track(1.0, 3.0)
    out = run(tracker, scene, bgs, lambda t: [(1.0, 3.0)] if t < 0.45 else [], 8)
    ended = next(k for k, (_, _, tracks) in enumerate(out) if not tracks)
    assert 5 <= ended <= 6                                            # ended by β once the person is gone
    (w,) = _watches(tracker)
    t_end = ended / FPS
    assert w.until == pytest.approx(t_end + 1.0)
    # The floor in view within lost_radius of the last position, and only there.
    last = out[ended - 1][2][0]
    assert np.hypot(last.x - 1.0, last.y - 3.0) < 0.15
    pts = w.region.sample(2000, np.random.default_rng(0))
    d = np.hypot(pts[:, 0] - last.x, pts[:, 1] - last.y)
    assert d.max() <= 0.8 + 0.05 * np.sqrt(2) and d.min() < 0.1 and w.region.area > 0.8 * np.pi * 0.8 ** 2
    assert tracker.detection.in_view(pts).all() and w.region.contains([[1.0, 3.0]]).tolist() == [True]
    k = 8
    while k / FPS <= t_end + 1.0 + 1e-9:                              # kept for lost_hold_s ...
        tracker.step({"cam": bgs["cam"]}, k / FPS)
        assert len(_watches(tracker)) == 1, k
        k += 1
    tracker.step({"cam": bgs["cam"]}, k / FPS)                        # ... and none afterwards
    assert not _watches(tracker) and len(tracker.detection.detectors) == 1


@pytest.mark.parametrize("births, same_id", [("entry+lost", True), ("entry+lost", False), ("entry", True)])
def test_a_lost_person_who_shows_again_nearby_is_found_with_entry_lost_only(births, same_id):
    """Gone from the image for 0.4 s mid-room, then standing 0.3 m from the track's last position:
    found again under the lost track's id (``lost_same_id``) or a new one."""
    scene = make_scene()
    tracker, bgs = tracker_for(scene, detection__births=births, tracking__end_after_s=0.0,
                               detection__lost_same_id=same_id)
    tracker.init_track(1.0, 3.0)
    out = run(tracker, scene, bgs, lambda t: [(1.0, 3.0)] if t < 0.45 else [] if t < 0.85 else [(1.3, 3.0)], 16)
    assert not out[7][2]
    tracks = out[-1][2]
    if births == "entry":
        assert not tracks
        return
    assert len(tracks) == 1 and tracks[0].id == (1 if same_id else 2)
    assert np.hypot(tracks[0].x - 1.3, tracks[0].y - 3.0) < 0.15
    assert not _watches(tracker)                                       # the watch that found it is dropped


def test_no_watch_where_an_entry_region_already_watches_or_for_tracks_not_ended_by_beta():
    scene = make_scene()
    tracker, bgs = tracker_for(scene, detection__births="entry+lost", tracking__end_after_s=0.0)
    tracker.init_track(-2.3, 3.0)                                     # in the door region, nobody there
    run(tracker, scene, bgs, lambda t: [], 3)
    assert not tracker.clouds and not _watches(tracker)
    tracker, bgs = tracker_for(scene, detection__births="entry+lost", motion__model="object")   # as in the exit test
    tracker.init_track(-1.0, 3.0)                                     # leaves through the exit
    out = run(tracker, scene, bgs, _walks_out_and_waits(2.25), 22)
    assert not out[-1][2] and len(tracker.life.exited) == 1 and not _watches(tracker)


def test_by_default_a_scene_with_entry_regions_watches_lost_tracks_and_the_paper_does_not():
    scene = make_scene()
    for cfg, watched in ((ParticleConfig(), True), (ParticleConfig.paper(), False)):
        d = cfg.detection
        tracker, bgs = tracker_for(scene, detection__births=d.births, detection__lost_hold_s=d.lost_hold_s,
                                   detection__lost_same_id=d.lost_same_id, tracking__end_after_s=0.0)
        tracker.init_track(1.0, 3.0)
        run(tracker, scene, bgs, lambda t: [(1.0, 3.0)] if t < 0.45 else [], 8)
        assert not tracker.clouds and len(_watches(tracker)) == int(watched)
    tracker, _ = tracker_for(make_scene(entry=False))
    assert tracker.detection.births == "anywhere"
