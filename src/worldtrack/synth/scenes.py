"""The rooms the built-in scenarios use, as scene mappings (the same format as scene files).

They live in code so that an installed package can synthesise without the repository's
``examples/`` folder; ``examples/scenes/*.yaml`` hold the same scenes for users to read and edit,
and a test checks the two agree. ``KATO_LAB`` copies ``examples/scenes/kato_lab.yaml``.
"""

from __future__ import annotations

import copy

KATO_LAB = {
    "name": "kato-lab",
    "cameras": [
        {"id": "cam1", "image_size": [160, 120], "position": [-1.00, -1.74, 2.64],
         "look_at": [-1.00, 0.90, 0.68], "hfov_deg": 60},
        {"id": "cam2", "image_size": [160, 120],
         "K": [[90.0, 0.0, 79.5], [0.0, 90.0, 59.5], [0.0, 0.0, 1.0]],
         "R": [[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]],
         "t": [-1.32, 1.07, 3.09], "distortion": [-0.25, 0.05, 0.0, 0.0, 0.0]},
    ],
    "floor": {"walkable": [{"outer": [[-3.5, -2.5], [1.5, -2.5], [1.5, 4.5], [-3.5, 4.5]]}]},
    "obstacles": [
        {"name": "desk", "type": "box", "centre": [-1.0, 2.4, 0.365], "size": [1.2, 0.6, 0.73], "yaw_deg": 0},
        {"name": "shelf", "type": "box", "centre": [1.2, 1.0, 0.9], "size": [0.5, 1.6, 1.8]},
    ],
    "entry_regions": [{"name": "door", "polygon": [[-3.5, 3.0], [-2.8, 3.0], [-2.8, 4.2], [-3.5, 4.2]]}],
    "people": {"height": 1.65, "width": 0.40},
}

# A 10 x 8 m hall with two pillars and a table; four cameras high in the corners looking in.
HALL = {
    "name": "hall",
    "cameras": [
        {"id": "c1", "image_size": [640, 480], "position": [0.3, 0.3, 3.6], "look_at": [5.0, 4.0, 0.6], "hfov_deg": 75},
        {"id": "c2", "image_size": [640, 480], "position": [9.7, 7.7, 3.6], "look_at": [5.0, 4.0, 0.6], "hfov_deg": 75},
        {"id": "c3", "image_size": [640, 480], "position": [9.7, 0.3, 3.6], "look_at": [5.0, 4.0, 0.6], "hfov_deg": 75},
        {"id": "c4", "image_size": [640, 480], "position": [0.3, 7.7, 3.6], "look_at": [5.0, 4.0, 0.6], "hfov_deg": 75},
    ],
    "floor": {"walkable": [{"outer": [[0.0, 0.0], [10.0, 0.0], [10.0, 8.0], [0.0, 8.0]]}]},
    "obstacles": [
        {"name": "pillar_w", "type": "box", "centre": [3.5, 4.0, 1.9], "size": [0.4, 0.4, 3.8]},
        {"name": "pillar_e", "type": "box", "centre": [6.5, 4.0, 1.9], "size": [0.4, 0.4, 3.8]},
        {"name": "table", "type": "box", "centre": [5.0, 1.4, 0.375], "size": [1.6, 0.7, 0.75]},
    ],
    "entry_regions": [
        {"name": "west_door", "polygon": [[0.0, 3.4], [0.6, 3.4], [0.6, 4.6], [0.0, 4.6]]},
        {"name": "east_door", "polygon": [[9.4, 3.4], [10.0, 3.4], [10.0, 4.6], [9.4, 4.6]]},
    ],
    "people": {"height": 1.70, "width": 0.45},
}

# An 8 x 6 m lobby entered through a short corridor in the south wall (seed 004), with a second
# door corridor in the east wall; one camera high on the north wall looking at the south door.
LOBBY = {
    "name": "lobby",
    "cameras": [
        {"id": "cam", "image_size": [640, 480], "position": [4.0, 5.7, 3.2], "look_at": [4.0, 1.6, 0.4],
         "hfov_deg": 72},
    ],
    "floor": {"walkable": [{"outer": [[0.0, 0.0], [3.3, 0.0], [3.3, -1.6], [4.7, -1.6], [4.7, 0.0], [8.0, 0.0],
                                      [8.0, 2.5], [9.6, 2.5], [9.6, 3.8], [8.0, 3.8], [8.0, 6.0], [0.0, 6.0]]}]},
    "obstacles": [
        {"name": "planter", "type": "box", "centre": [1.0, 5.2, 0.3], "size": [1.0, 0.6, 0.6]},
        {"name": "counter", "type": "box", "centre": [6.6, 5.3, 0.55], "size": [1.8, 0.6, 1.1]},
    ],
    "entry_regions": [
        {"name": "south_door", "polygon": [[3.3, -1.6], [4.7, -1.6], [4.7, 0.3], [3.3, 0.3]]},
        {"name": "east_door", "polygon": [[7.7, 2.5], [9.6, 2.5], [9.6, 3.8], [7.7, 3.8]]},
    ],
    "people": {"height": 1.70, "width": 0.45},
}

# A 16 x 8 m open-plan office: a corridor along y = 4 m, desks on both sides, low partitions
# between four bays, and four ceiling cameras looking down on the corridor, 4 m apart, whose
# views do not overlap (seed 002).
_OFFICE_CAMS = [{"id": f"cam{k + 1}", "image_size": [640, 480], "position": [x, 4.0, 2.85],
                 "look_at": [x, 4.35, 0.0], "hfov_deg": 58} for k, x in enumerate((2.0, 6.0, 10.0, 14.0))]
OFFICE_4CAMS = {
    "name": "office-4cams",
    "cameras": _OFFICE_CAMS,
    "floor": {"walkable": [{"outer": [[0.0, 0.0], [16.0, 0.0], [16.0, 8.0], [0.0, 8.0]]}]},
    "obstacles": (
        [{"name": f"desk_s{k + 1}", "type": "box", "centre": [x, 2.2, 0.365], "size": [1.6, 0.8, 0.73]}
         for k, x in enumerate((2.0, 6.0, 10.0, 14.0))]
        + [{"name": f"desk_n{k + 1}", "type": "box", "centre": [x, 5.8, 0.365], "size": [1.6, 0.8, 0.73]}
           for k, x in enumerate((2.0, 6.0, 10.0, 14.0))]
        + [{"name": f"partition_s{k + 1}", "type": "box", "centre": [x, 1.3, 0.7], "size": [0.05, 2.6, 1.4]}
           for k, x in enumerate((4.0, 8.0, 12.0))]
        + [{"name": f"partition_n{k + 1}", "type": "box", "centre": [x, 6.7, 0.7], "size": [0.05, 2.6, 1.4]}
           for k, x in enumerate((4.0, 8.0, 12.0))]
        + [{"name": "cabinet", "type": "box", "centre": [15.6, 4.0, 0.6], "size": [0.5, 1.2, 1.2]}]
    ),
    "entry_regions": [{"name": "west_end", "polygon": [[0.0, 3.2], [0.7, 3.2], [0.7, 4.8], [0.0, 4.8]]}],
    "people": {"height": 1.70, "width": 0.45},
}

# The same office with a screen across the corridor between every two cameras, each leaving one
# 0.8 m passage, on alternate sides (north at x = 4 and 12 m, south at x = 8 m): nobody can walk
# straight from one camera's view to the next (seed 002's detours).
OFFICE_4CAMS_DETOURS = copy.deepcopy(OFFICE_4CAMS)
OFFICE_4CAMS_DETOURS["name"] = "office-4cams-detours"
OFFICE_4CAMS_DETOURS["obstacles"] = OFFICE_4CAMS["obstacles"] + [
    {"name": f"screen{k + 1}", "type": "box", "centre": [x, yc, 0.9], "size": [0.05, 2.0, 1.8]}
    for k, (x, yc) in enumerate(((4.0, 3.6), (8.0, 4.4), (12.0, 3.6)))]
#: The passage through each screen (x, y of its middle), for walkers' routes.
OFFICE_DOORS = ((4.0, 5.0), (8.0, 3.0), (12.0, 5.0))

# A 16 x 12 m paved courtyard between buildings, open to the sky (seed 001's robot follows a
# person here). The camera is the robot's stereo head; its pose here is only the first frame's.
COURTYARD = {
    "name": "courtyard",
    "cameras": [
        {"id": "robot", "image_size": [640, 480], "position": [2.0, 2.0, 1.1], "look_at": [4.0, 2.0, 0.95],
         "hfov_deg": 66},
    ],
    "floor": {"walkable": [{"outer": [[0.0, 0.0], [16.0, 0.0], [16.0, 12.0], [0.0, 12.0]]}]},
    "obstacles": [
        {"name": "bench", "type": "box", "centre": [8.0, 6.0, 0.225], "size": [1.8, 0.5, 0.45]},
        {"name": "kiosk", "type": "box", "centre": [12.5, 9.0, 1.2], "size": [1.5, 1.5, 2.4]},
    ],
    "entry_regions": [],
    "people": {"height": 1.70, "width": 0.45},
}

# A 4 x 4 m booth for seed 003's close-ups: the person stands at (2.0, 2.8) facing -Y; the RGB-D
# camera's pose is set by the scenario (face or upper body).
BOOTH = {
    "name": "booth",
    "cameras": [
        {"id": "kinect", "image_size": [640, 480], "position": [2.0, 1.95, 1.61], "look_at": [2.0, 2.8, 1.61],
         "hfov_deg": 57},
    ],
    "floor": {"walkable": [{"outer": [[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]]}]},
    "obstacles": [],
    "entry_regions": [],
    "people": {"height": 1.72, "width": 0.45},
}

# Two 6 x 5 m rooms side by side, joined by a 1.2 m door in the wall at x = 6 m; one camera high on
# each end wall looking at the door, so the door and a little of the room beyond it are in both
# views (a person walking from one room to the other is handed from one camera to the other).
TWO_ROOMS = {
    "name": "two-rooms",
    "cameras": [
        {"id": "west", "image_size": [640, 480], "position": [0.3, 2.5, 3.0], "look_at": [4.6, 2.5, 0.4],
         "hfov_deg": 78},
        {"id": "east", "image_size": [640, 480], "position": [11.7, 2.5, 3.0], "look_at": [7.4, 2.5, 0.4],
         "hfov_deg": 78},
    ],
    "floor": {"walkable": [{"outer": [[0.0, 0.0], [12.0, 0.0], [12.0, 5.0], [0.0, 5.0]]}]},
    "obstacles": [
        {"name": "wall_south", "type": "box", "centre": [6.0, 0.95, 1.3], "size": [0.15, 1.9, 2.6]},
        {"name": "wall_north", "type": "box", "centre": [6.0, 4.05, 1.3], "size": [0.15, 1.9, 2.6]},
        {"name": "table_west", "type": "box", "centre": [2.5, 4.2, 0.375], "size": [1.4, 0.7, 0.75]},
        {"name": "cabinet_east", "type": "box", "centre": [10.0, 0.45, 0.9], "size": [1.2, 0.5, 1.8]},
    ],
    "entry_regions": [],
    "people": {"height": 1.70, "width": 0.45},
}

BUILTIN = {"kato_lab": KATO_LAB, "hall": HALL, "lobby": LOBBY, "office_4cams": OFFICE_4CAMS,
           "office_4cams_detours": OFFICE_4CAMS_DETOURS, "courtyard": COURTYARD, "booth": BOOTH,
           "two_rooms": TWO_ROOMS}


def scene_dict(name: str) -> dict:
    """A deep copy of a built-in scene mapping."""
    return copy.deepcopy(BUILTIN[name])
