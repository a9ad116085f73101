"""Many people: a crowd in a hall with pillars (1–4 cameras), two rooms joined by a door (one camera
each), and paper 004's entry through a door side by side.

Registered as ``crowd``, ``two-rooms`` and ``entry``.
"""

from __future__ import annotations

import numpy as np

from worldtrack.errors import InputError
from worldtrack.synth import scenes
from worldtrack.synth.environment import Environment, Window
from worldtrack.synth.motion import Waypoint, WalkerSettings, random_walkers, scripted_track
from worldtrack.synth.photometry import Light, light_direction
from worldtrack.synth.scenarios import (Common, _register, _scene, _options, _lighting, _rigs, _route_length, _trim,
                                        _route_frames, _shape, _pad, _MAX_FRAMES)
from worldtrack.synth.sequence import Person, Scenario


# ------------------------------------------------------------------------------------ crowd

@_register("crowd", "N random walkers (up to 50) in a 10 x 8 m hall seen by 1-4 corner cameras")
def crowd(seed: int, common: Common, *, size=None, frames=None, people: int = 10, cameras: int = 2,
          min_separation: float = 0.6, speed: tuple = (0.9, 1.4), p_stop: float = 0.3) -> Scenario:
    """Random walkers that keep ``min_separation`` metres apart and 0.3 m inside the walkable area,
    stop now and then (speed 0), and walk round the pillars and the table. 320×240 by default."""
    if not 1 <= int(people) <= 50:
        raise InputError(f"people: expected 1 to 50, got {people}")
    if not 1 <= int(cameras) <= 4:
        raise InputError(f"cameras: expected 1 to 4, got {cameras}")
    rng = np.random.default_rng(seed)
    data = scenes.scene_dict("hall")
    scene = _scene(data, size or (320, 240), [c["id"] for c in data["cameras"][:int(cameras)]])
    env = Environment(wall_height=4.2, floor_style="wood", floor_colour=(95, 130, 165), wall_colour=(200, 205, 200),
                      obstacle_colours={"pillar_w": (170, 170, 165), "pillar_e": (170, 170, 165),
                                        "table": (60, 80, 100)}, posters=6, seed=5)
    n = frames or 100
    shapes = [_shape(rng, env) for _ in range(int(people))]
    settings = WalkerSettings(speed=tuple(speed), min_separation=min_separation, p_stop=p_stop)
    tracks = random_walkers(scene, int(people), common.fps, n, rng, [s.height for s in shapes], settings)
    persons = [Person(i + 1, shapes[i], tracks[i]) for i in range(int(people))]
    light = Light(ambient=0.55, direct=0.55, direction=light_direction(40.0, 58.0))
    return Scenario("crowd", scene, common.fps, n, persons, env, _lighting(common, rng, light), _options(common),
                    _rigs(scene, common), seed, description=f"{people} random walkers")


# ------------------------------------------------------------------------------------ two rooms

@_register("two-rooms", "two rooms joined by a door, one camera each: people walk from one view into the other")
def two_rooms(seed: int, common: Common, *, size=None, frames=None, people: int = 2, stagger: float = 3.0,
              speed: tuple = (0.9, 1.3)) -> Scenario:
    """Two 6 × 5 m rooms joined by a 1.2 m door at x = 6 m, a camera on each end wall looking at the
    door. Person k starts in one room (alternating west, east), waits ``stagger`` · k seconds, walks
    through the door into the other room to a random point and stops there; the door is seen by
    both cameras. 320×240 by default."""
    if not 1 <= int(people) <= 6:
        raise InputError(f"people: expected 1 to 6, got {people}")
    rng = np.random.default_rng(seed)
    scene = _scene(scenes.scene_dict("two_rooms"), size or (320, 240))
    env = Environment(wall_height=3.2, floor_style="tiles", floor_colour=(140, 150, 160), wall_colour=(195, 200, 190),
                      obstacle_colours={"wall_south": (195, 200, 190), "wall_north": (195, 200, 190),
                                        "table_west": (70, 100, 140), "cabinet_east": (120, 120, 125)},
                      posters=4, seed=23)
    shapes, routes = [], []
    for k in range(int(people)):
        side = 1.0 if k % 2 == 0 else -1.0           # +1: starts west
        lane = float(rng.uniform(2.1, 2.9))
        start = (6.0 - side * rng.uniform(3.5, 4.8), float(rng.uniform(1.2, 3.6)))
        goal = (6.0 + side * rng.uniform(2.5, 4.5), float(rng.uniform(1.5, 3.5)))
        v = float(rng.uniform(*speed))
        routes.append([Waypoint(*start, dwell=stagger * k + 0.5), Waypoint(6.0 - side * 1.2, lane, speed=v),
                       Waypoint(6.0 + side * 1.2, lane, speed=v), Waypoint(*goal, speed=v, dwell=1.0)])
        shapes.append(_shape(rng, env))
    tracks = [scripted_track(r, common.fps, _route_frames(r, common.fps), s.height) for r, s in zip(routes, shapes)]
    n = frames or _route_length(tracks, 1.0, common.fps, _MAX_FRAMES)
    persons = [Person(k + 1, shapes[k], _trim(_pad(tracks[k], n), n)) for k in range(int(people))]
    light = Light(ambient=0.6, direct=0.45, direction=light_direction(200.0, 60.0))
    return Scenario("two-rooms", scene, common.fps, n, persons, env, _lighting(common, rng, light), _options(common),
                    _rigs(scene, common), seed, description=f"{people} people walking between two rooms")


# ------------------------------------------------------------------------------------ seed 004

@_register("entry", "paper 004: people enter side by side through a door region, then split up and leave")
def entry(seed: int, common: Common, *, size=None, frames=None, pairs: int = 2, singles: int = 1,
          spacing: float = 0.5, split_after: float = 2.0, interval: float = 6.0, speed: float = 1.0,
          backlight: bool = True) -> Scenario:
    """One fixed camera on a lobby's north wall looking at the south door. Every ``interval`` seconds
    a pair walks in through the door side by side, ``spacing`` m apart (centre to centre), walks
    ``split_after`` m together, then the two split to different points, wait, and leave through the
    east door or back through the south door. ``singles`` more people cross from the east door.
    People appear in the door corridors and vanish on leaving them. With ``backlight`` the south
    wall beside the door is bright glass, so people coming in are seen against the light.
    320×240 by default."""
    if not 0 <= int(pairs) <= 6 or not 0 <= int(singles) <= 6 or int(pairs) + int(singles) == 0:
        raise InputError(f"pairs, singles: expected 0–6 each and at least one person, got {pairs}, {singles}")
    if not 0.3 <= spacing <= 1.5:
        raise InputError(f"spacing: expected 0.3–1.5 m, got {spacing}")
    rng = np.random.default_rng(seed)
    scene = _scene(scenes.scene_dict("lobby"), size or (320, 240))
    glass = tuple(Window(np.array([[x0, 0.01, 0.3], [x1, 0.01, 0.3], [x1, 0.01, 2.6], [x0, 0.01, 2.6]]),
                         (245.0, 240.0, 235.0)) for x0, x1 in ((0.4, 3.0), (5.0, 7.6)))
    env = Environment(wall_height=3.5, floor_style="tiles", floor_colour=(120, 135, 150), wall_colour=(175, 190, 205),
                      obstacle_colours={"planter": (50, 90, 60), "counter": (90, 100, 120)}, posters=3, seed=11,
                      windows=glass if backlight else ())
    south_exit = [Waypoint(4.0, 0.6, speed=speed), Waypoint(4.0, -1.45, speed=speed)]
    east_exit = [Waypoint(7.6, 3.15, speed=speed), Waypoint(9.45, 3.15, speed=speed)]
    routes, starts, shapes = [], [], []
    for k in range(int(pairs)):
        t0 = 0.5 + k * interval
        split_y = 0.3 + split_after
        goals = [(rng.uniform(1.2, 2.8), rng.uniform(2.2, 4.3)), (rng.uniform(5.2, 6.8), rng.uniform(1.8, 4.3))]
        for side, dx in enumerate((-spacing / 2, spacing / 2)):
            gx, gy = goals[side]
            exit_ = east_exit if rng.random() < 0.5 else south_exit
            r = [Waypoint(4.0 + dx, -1.45), Waypoint(4.0 + dx, split_y, speed=speed),
                 Waypoint(gx, gy, speed=speed * rng.uniform(0.9, 1.1), dwell=rng.uniform(1.0, 3.0))] + exit_
            routes.append(r)
            starts.append(t0)
            shapes.append(_shape(rng, env))
    for k in range(int(singles)):
        t0 = 3.0 + k * interval
        gx, gy = rng.uniform(1.5, 3.0), rng.uniform(2.0, 4.0)
        routes.append([Waypoint(9.45, 3.15), Waypoint(7.5, 3.15, speed=speed), Waypoint(gx, gy, speed=speed)]
                      + south_exit)
        starts.append(t0)
        shapes.append(_shape(rng, env))
    tracks = [scripted_track(r, common.fps, _route_frames(r, common.fps, t0), s.height, start_time=t0,
                             leave_at_end=True)
              for r, s, t0 in zip(routes, shapes, starts)]
    n = frames or _route_length(tracks, 1.0, common.fps, 3000)
    persons = [Person(i + 1, shapes[i], _trim(_pad(tracks[i], n), n)) for i in range(len(tracks))]
    light = Light(ambient=0.6, direct=0.5, direction=light_direction(250.0, 60.0))
    return Scenario("entry", scene, common.fps, n, persons, env, _lighting(common, rng, light), _options(common),
                    _rigs(scene, common), seed, description="paper 004: pairs entering side by side, then splitting")
