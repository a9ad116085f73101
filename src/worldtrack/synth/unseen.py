"""A scenario built to be harder than the ones the ellipsoid tracker was tuned on (issue 37).

``line-of-sight``: one camera 2.5–3 m high on the short wall of an 8 × 11 m room, people 5–10 m
away from it, so that the distance along the camera's line of sight rests on how tall a person
looks. Every seed deals:

- two people of very different heights (1.50–1.60 m and 1.85–1.95 m) who cross on the camera's
  line of sight at different distances (the tall far one's head lines up with the short near one's);
- people in clothes the colour of the floor (trousers, and for some the top too);
- a walker along the line of sight (towards or away from the camera), where depth changes fastest;
- people standing in the middle of the room at frame 0, and people who appear and vanish in the
  middle of the room, away from any door.

>>> from worldtrack.synth import make_scenario
>>> sc = make_scenario("line-of-sight", size=(160, 120), frames=3, seed=0)
>>> sc.camera_ids, len(sc.people) >= 5
(['cam'], True)
>>> bool(2.5 <= sc.scene.cameras["cam"].centre[2] <= 3.0)
True
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from worldtrack.errors import InputError
from worldtrack.synth.bodies import draw_body_shape
from worldtrack.synth.environment import Environment
from worldtrack.synth.motion import Waypoint, scripted_track
from worldtrack.synth.photometry import Light, light_direction
from worldtrack.synth.scenarios import (_MAX_FRAMES, Common, _lighting, _options, _pad, _register, _rigs, _scene,
                                        _trim)
from worldtrack.synth.sequence import Person, Scenario

ROOM_X, ROOM_Y = 8.0, 11.0
CAMERA_X = ROOM_X / 2
FLOOR = (118.0, 122.0, 126.0)   # a grey floor: grey trousers on it are the hard case


def room(camera_height: float) -> dict:
    """The scene mapping: the room, one camera on the south wall looking 7 m in."""
    return {
        "name": "long-room",
        "cameras": [{"id": "cam", "image_size": [640, 480], "position": [CAMERA_X, 0.15, camera_height],
                     "look_at": [CAMERA_X, 7.0, 0.6], "hfov_deg": 62}],
        "floor": {"walkable": [{"outer": [[0.0, 0.0], [ROOM_X, 0.0], [ROOM_X, ROOM_Y], [0.0, ROOM_Y]]}]},
        "obstacles": [],
        "entry_regions": [{"name": "west_door", "polygon": [[0.0, 4.0], [0.6, 4.0], [0.6, 5.5], [0.0, 5.5]]}],
        "people": {"height": 1.70, "width": 0.45},
    }


def _floor_clothes(rng, shape, both: bool):
    """Trousers (and with ``both`` the top) within a few grey levels of the floor."""
    near = lambda: tuple(float(v) for v in np.clip(np.asarray(FLOOR) * rng.uniform(0.95, 1.05)
                                                   + rng.normal(0, 3, 3), 5, 250))
    fields = {"bottom": near()}
    if both:
        fields["top"] = near()
    return replace(shape, **fields)


def _crossing_pair(rng, speed: float) -> tuple[list, list, tuple]:
    """Routes of a short near person and a tall far one who meet on one line of sight mid-way.

    Both walk across the room (along x) and pass the camera's axis (x = CAMERA_X) at the same
    moment; they walk in opposite directions so their images cross.
    """
    near_y, far_y = rng.uniform(5.0, 6.2), rng.uniform(8.2, 9.8)
    meet_x = CAMERA_X + rng.uniform(-0.6, 0.6)
    # Same angle from the camera at the meeting time: far_x - CAMERA_X = (near_x - CAMERA_X) * far/near.
    half = rng.uniform(2.0, 2.6)
    direction = 1.0 if rng.random() < 0.5 else -1.0
    near = [Waypoint(meet_x - direction * half, near_y, dwell=0.6), Waypoint(meet_x + direction * half, near_y,
                                                                            speed=speed)]
    scale = (far_y - 0.15) / (near_y - 0.15)
    far_meet = CAMERA_X + (meet_x - CAMERA_X) * scale
    far = [Waypoint(far_meet + direction * half, far_y, dwell=0.6), Waypoint(far_meet - direction * half, far_y,
                                                                            speed=speed)]
    heights = (rng.uniform(1.50, 1.60), rng.uniform(1.85, 1.95))
    if rng.random() < 0.5:   # sometimes the tall one is near
        heights = heights[::-1]
    return near, far, heights


def _mid_room(rng, n: int) -> list[tuple[float, float]]:
    return [(rng.uniform(1.5, ROOM_X - 1.5), rng.uniform(5.0, 9.8)) for _ in range(n)]


@_register("line-of-sight", "issue 37: one camera 2.5-3 m high, people 5-10 m away crossing on its line of "
                            "sight, floor-coloured clothes, appearing and vanishing mid-room")
def line_of_sight(seed: int, common: Common, *, size=None, frames=None, camera_height: float | None = None,
                  floor_clothes: int = 2, speed: float = 1.0) -> Scenario:
    """Five people in a long room seen by one camera (see the module docstring). 640×480 by default.

    ``camera_height`` (metres, 2.5–3.0) is drawn from the seed unless given; ``floor_clothes``
    people (0–5) wear trousers of the floor's grey, the first of them a grey top too.
    """
    rng = np.random.default_rng(seed)
    h_cam = float(rng.uniform(2.5, 3.0)) if camera_height is None else float(camera_height)
    if not 2.5 <= h_cam <= 3.0:
        raise InputError(f"camera_height: expected 2.5–3.0 m, got {camera_height}")
    if not 0 <= int(floor_clothes) <= 5:
        raise InputError(f"floor_clothes: expected 0 to 5, got {floor_clothes}")
    scene = _scene(room(h_cam), size or (640, 480))
    env = Environment(wall_height=3.2, floor_style="tiles", floor_colour=FLOOR, wall_colour=(185, 190, 195),
                      posters=3, seed=int(rng.integers(1000)))
    n = frames or 120
    near, far, (h_near, h_far) = _crossing_pair(rng, speed)
    a, b, c, d = _mid_room(rng, 4)
    radial_dir = 1.0 if rng.random() < 0.5 else -1.0
    x_radial = rng.uniform(1.8, ROOM_X - 1.8)
    y0, y1 = (5.0, 9.8) if radial_dir > 0 else (9.8, 5.0)
    appear_at = rng.uniform(2.0, 4.0)
    plans = [  # (route, height, start_s, vanishes)
        (near, h_near, 0.0, False),
        (far, h_far, 0.0, False),
        ([Waypoint(x_radial, y0, dwell=rng.uniform(0.5, 1.5)), Waypoint(x_radial, y1, speed=speed * 0.9)],
         None, 0.0, False),
        ([Waypoint(*a, dwell=rng.uniform(1.0, 2.0)), Waypoint(*b, speed=speed)], None, 0.0, True),
        ([Waypoint(*c, dwell=0.5), Waypoint(*d, speed=speed)], None, appear_at, True),
    ]
    shapes, tracks = [], []
    for k, (route, height, start, vanish) in enumerate(plans):
        shape = draw_body_shape(rng, height=height)
        if k >= 2 and k - 2 < int(floor_clothes):
            shape = _floor_clothes(rng, shape, both=(k == 2))
        elif k < 2 and int(floor_clothes) >= 4 + k:
            shape = _floor_clothes(rng, shape, both=False)
        shapes.append(shape)
        tracks.append(scripted_track(route, common.fps, max(n, 1), shape.height, start_time=start,
                                     leave_at_end=vanish))
    people = [Person(i + 1, shapes[i], _trim(_pad(tracks[i], n), n)) for i in range(len(tracks))]
    light = Light(ambient=0.55, direct=0.55, direction=light_direction(200.0, 55.0))
    return Scenario("line-of-sight", scene, common.fps, min(n, _MAX_FRAMES), people, env,
                    _lighting(common, rng, light), _options(common), _rigs(scene, common), seed,
                    description=f"issue 37: one camera at {h_cam:.2f} m, people 5-10 m away")
