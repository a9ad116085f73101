"""Ground-truth heads and head pixels of a scenario, and the office with detours (seed 002)."""

import numpy as np
import pytest

from worldtrack.synth import make_scenario
from worldtrack.synth.observations import head_pixels, head_tracks
from worldtrack.trajectory.environment import inside_obstacles, segment_crossings


@pytest.fixture(scope="module")
def detours():
    sc = make_scenario("non-overlapping", frames=400, seed=2, people=2, layout="detours", size=(640, 480), legs=14)
    return sc, head_tracks(sc)


def test_head_pixels_are_the_projected_head_tops_inside_the_image(detours):
    sc, tracks = detours
    px = head_pixels(sc, noise_px=0.0, tracks=tracks)
    assert len(px.time) > 20 and np.all(np.diff(px.time) >= 0)
    for cid, cam in sc.scene.cameras.items():
        sel = px.camera == cid
        if sel.any():
            np.testing.assert_allclose(px.uv[sel], cam.project(px.truth[sel]), atol=1e-9)
            assert cam.in_image(px.uv[sel]).all()
    k = np.rint(px.time * sc.fps).astype(int)
    for pid in np.unique(px.id):
        sel = px.id == pid
        np.testing.assert_allclose(px.truth[sel], tracks[pid].points[k[sel]])
    noisy = head_pixels(sc, noise_px=2.0, rng=1, tracks=tracks)
    d = noisy.uv - px.uv
    assert 1.5 < d.std() < 2.5


def test_head_tops_follow_the_bodies(detours):
    sc, tracks = detours
    for p in sc.people:
        tr = tracks[p.id]
        assert np.abs(tr.points[:, :2] - p.track.xy).max() < 0.25          # the head sways over the feet
        assert p.shape.height - 0.08 < np.median(tr.points[:, 2]) <= p.shape.height + 0.01


def test_detours_make_every_walk_between_views_leave_the_straight_line(detours):
    sc, tracks = detours
    field = sc.scene.distance_field(0.05)
    names = [o.name for o in sc.scene.obstacles]
    assert {"screen1", "screen2", "screen3"} <= set(names)
    screens = np.array([[[4.0, 2.6], [4.0, 4.6]], [[8.0, 3.4], [8.0, 5.4]], [[12.0, 2.6], [12.0, 4.6]]])
    for p in sc.people:
        assert not inside_obstacles(field, p.track.xy).any()                # people walk round them
        assert not segment_crossings(p.track.xy, screens).any()
    # the corridor line between two cameras is blocked
    assert segment_crossings(np.array([[2.0, 4.0], [6.0, 4.0], [10.0, 4.0], [14.0, 4.0]]), screens).all()


def test_the_layout_is_checked():
    from worldtrack.errors import InputError
    with pytest.raises(InputError, match="layout"):
        make_scenario("non-overlapping", frames=2, layout="maze")
