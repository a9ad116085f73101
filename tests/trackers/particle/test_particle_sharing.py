"""Two particle trackers, each with its own camera, on one position map: a person who walks from one
camera's view into the other's keeps one id (the map is the integration point between trackers)."""

from __future__ import annotations

import numpy as np

from worldtrack.foreground.background import StaticBackground
from worldtrack.scene import scene_from_dict
from worldtrack.trackers.base import Frame, PositionMap
from worldtrack.trackers.particle import ParticleTracker

from particle_scenes import FPS, HEIGHT, WIDTH, config, render, texture

#: Two cameras side by side along a corridor; each sees about 5.6 m of it, 1.6 m of that in common.
LEFT = {"id": "left", "image_size": [320, 240], "position": [-2, -1, 3], "look_at": [-2, 3, 0.5], "hfov_deg": 70}
RIGHT = {"id": "right", "image_size": [320, 240], "position": [2, -1, 3], "look_at": [2, 3, 0.5], "hfov_deg": 70}


def _corridor():
    return scene_from_dict({"name": "corridor", "cameras": [LEFT, RIGHT],
                            "floor": {"walkable": [{"outer": [[-6, 0.5], [6, 0.5], [6, 5.5], [-6, 5.5]]}]},
                            "people": {"height": HEIGHT, "width": WIDTH}})


def _walk(shared: bool):
    """A person walks from x = −3.5 (left view only) to x = 3.5 (right view only) at 1 m/s. With
    ``shared`` the two trackers share a map; without, each has its own (then the right tracker starts
    a person of its own: the test below fails without the trackers following the shared map, checked)."""
    scene = _corridor()
    bgs = {"left": texture(0), "right": texture(1)}
    one = PositionMap()
    trackers = {cid: ParticleTracker(scene, {cid: StaticBackground(bgs[cid], 30.0, "colour")},
                                     config(column__surface_offset_m=0.0, detection__births="anywhere", seed=i),
                                     position_map=one if shared else None)
                for i, cid in enumerate(("left", "right"))}
    rng = np.random.default_rng(0)
    out = []
    for k in range(71):
        t = k / FPS
        person = [(-3.5 + 1.0 * t, 3.0)]
        tracks = {cid: tr.step({cid: Frame(render(scene.camera(cid), bgs[cid], person, rng), t, k)}, t)
                  for cid, tr in trackers.items()}
        out.append((person[0], tracks))
    return out, trackers


def test_a_person_walking_from_one_trackers_view_into_the_others_keeps_one_id():
    out, trackers = _walk(shared=True)
    ids = {tr.id for _, tracks in out for ts in tracks.values() for tr in ts}
    assert ids == {1}
    # Found early in the left view, followed across into the right view, and placed there.
    first = next(k for k, (_, tracks) in enumerate(out) if tracks["left"])
    assert first <= 5
    assert all(tracks["right"] and tracks["left"] for _, tracks in out[first:])      # one map: both report them
    (x, y), tracks = out[-1]
    (tr,) = tracks["right"]
    assert np.hypot(tr.x - x, tr.y - y) < 0.2
    # The right tracker took the person over: its camera shows them now, the left one's does not.
    person = trackers["right"].position_map[1]
    assert person.seen_by == ("right",) and trackers["left"].clouds[1].t_update is None
