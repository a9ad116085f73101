"""Two ellipsoid trackers, each with its own camera, on one position map: a person walking from the
first camera's view to the second's keeps one id, and is not duplicated.

The cameras look at the left and the right of a 10 x 6 m room; their views overlap in the middle
(x 3.8-6.2 m). The person walks along y = 3 m from x = 1 to 9 m at 1.2 m/s, 10 frames/s, drawn as
an ellipsoid in each camera's frame; the trackers step in turn at each time stamp.
"""

import numpy as np
import pytest
from _ellipsoid_scenes import ellipsoid_frames, noise_backgrounds

from worldtrack.geometry import quadric as q
from worldtrack.foreground import make_foregrounds
from worldtrack.scene import scene_from_dict
from worldtrack.trackers.base import PositionMap
from worldtrack.trackers.ellipsoid import EllipsoidConfig, EllipsoidTracker

SPEED, FPS = 1.2, 10.0


def _room():
    return scene_from_dict({
        "cameras": [{"id": "A", "image_size": [160, 120], "position": [2.5, -1.5, 3.0], "look_at": [3.0, 3.0, 0.8],
                     "hfov_deg": 60},
                    {"id": "B", "image_size": [160, 120], "position": [7.5, -1.5, 3.0], "look_at": [7.0, 3.0, 0.8],
                     "hfov_deg": 60}],
        "floor": {"walkable": [{"outer": [[0, 0], [10, 0], [10, 6], [0, 6]]}]}})


def _state(person) -> tuple:
    return (person.x, person.y, person.vx, person.vy, person.score, person.mode, dict(person.counters),
            person.seen_at, person.height, person.sigma)


def _walk(shared: bool, order: str = "AB") -> tuple[list, dict]:
    """Per time stamp: (true x, {camera id: the tracks on that tracker's map}); and the trackers. Checks on the way
    that a tracker whose camera does not show the person leaves what the other wrote untouched."""
    scene = _room()
    rng = np.random.default_rng(7)
    bgs = noise_backgrounds(scene, rng)
    config = EllipsoidConfig(warm_start={"frames": 0})
    maps = [PositionMap()] * 2 if shared else [PositionMap(), PositionMap()]
    trackers = {cid: EllipsoidTracker(scene, make_foregrounds(scene, {cid: bgs[cid]}, "colour"), config,
                                      position_map=m) for cid, m in zip("AB", maps)}
    out = []
    for i in range(int(round(8.0 / SPEED * FPS)) + 1):
        x, t = 1.0 + SPEED * i / FPS, i / FPS
        frames = ellipsoid_frames(scene, bgs, *q.person_ellipsoid([[x, 3.0]], 1.65, 0.4), rng, i, fps=FPS)
        for cid in order:
            others = [p for p in trackers[cid].position_map if p.t == t]   # already updated at t by the other
            blind = (cid == "B" and x < 3.2) or (cid == "A" and x > 6.8)
            before = [_state(p) for p in others]
            trackers[cid].step({cid: frames[cid]}, t)
            if blind and shared:
                assert [_state(p) for p in others] == before, (cid, x)
        # What each tracker's map holds once both have stepped at t.
        out.append((x, {cid: tr.position_map.tracks() for cid, tr in trackers.items()}))
    return out, trackers


def _check_one_person_one_id(walk: list) -> None:
    ids = set()
    for x, reported in walk:
        a, b = reported["A"], reported["B"]
        # One map: both trackers see the same people, and never two for one person.
        assert [(tr.id, tr.born) for tr in a] == [(tr.id, tr.born) for tr in b], x
        assert len(b) == 1, x
        assert np.hypot(b[0].x - x, b[0].y - 3.0) < 0.15, x
        ids.add(b[0].id)
    assert ids == {walk[0][1]["B"][0].id}
    assert walk[-1][1]["B"][0].born == 0.0          # the person found at the start, in A's view only


@pytest.mark.parametrize("order", ["AB", "BA"])
def test_a_person_handed_from_one_view_to_the_other_keeps_one_id(order):
    walk, trackers = _walk(shared=True, order=order)
    _check_one_person_one_id(walk)
    person = next(iter(trackers["B"].position_map))
    assert person.seen_by == ("B",) and trackers["A"].position_map.cameras == {"A", "B"}


def test_without_a_shared_map_the_hand_over_is_lost():
    # The check above fails when each tracker has its own map: B starts its own person (born when
    # they enter its view) and A reports nobody once they have left its view.
    walk, _ = _walk(shared=False)
    with pytest.raises(AssertionError):
        _check_one_person_one_id(walk)
    assert walk[-1][1]["B"][0].born > 2.0 and walk[-1][1]["A"] == []
