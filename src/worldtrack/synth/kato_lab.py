"""Paper 000's experiments in the Kato lab: standing at the grid points (Table 1), behind a desk
(Table 2), two people crossing (Figs. 9–10), sitting down.

Registered with :func:`worldtrack.synth.make_scenario` as ``static-grid``, ``desk-occlusion``,
``two-crossing`` and ``sit-down``.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from worldtrack.errors import InputError
from worldtrack.scene.model import Scene
from worldtrack.synth import scenes
from worldtrack.synth.environment import Environment
from worldtrack.synth.motion import Waypoint, scripted_track
from worldtrack.synth.photometry import Light, light_direction
from worldtrack.synth.scenarios import (Common, _register, _scene, _options, _lighting, _rigs, _route_length, _trim,
                                        _route_frames, _shape, _pad, _MAX_FRAMES)
from worldtrack.synth.sequence import Person, Scenario


_FACE_CAMERA = -np.pi / 2  # in the kato lab, facing -Y looks at camera 1


def _kato_env(scene: Scene) -> Environment:
    top = max(c.centre[2] for c in scene.cameras.values())
    return Environment(wall_height=max(2.7, top + 0.25), floor_style="tiles", floor_colour=(150, 158, 162),
                       wall_colour=(185, 195, 200), obstacle_colours={"desk": (70, 110, 150), "shelf": (120, 125, 128),
                                                                     "stool": (60, 60, 70)}, posters=3, seed=3)


def _kato_light() -> Light:
    return Light(ambient=0.55, direct=0.6, direction=light_direction(110.0, 62.0))


def _dwell_route(points: list[tuple[float, float]], dwell: float, speed: float, face: float | None) -> list[Waypoint]:
    return [Waypoint(x, y, dwell=dwell, speed=speed, face=face) for x, y in points]


# ------------------------------------------------------------------------------------ seed 000

# Table 1 of seed 000: camera 1 at 15 points — (a) full body at (0, 0)…(−2, 2), (b) lower body only at
# y = 3, (c) upper body only at y = −0.5, where the paper's range is (0.5, −0.5)…(−1.5, −0.5);
# camera 2 at the 12 points (0, 0)…(−2, 3).
CAM1_GRID = ([(x, -0.5) for x in (0.5, -0.5, -1.5)]
             + [(x, y) for y in (0.0, 1.0, 2.0, 3.0) for x in (0.0, -1.0, -2.0)])
CAM2_GRID = [(x, y) for y in (0.0, 1.0, 2.0, 3.0) for x in (0.0, -1.0, -2.0)]


def _serpentine(points: list[tuple[float, float]]) -> list[tuple[float, float]]:
    rows = sorted({p[1] for p in points})
    out = []
    for k, y in enumerate(rows):
        xs = sorted({p[0] for p in points if p[1] == y}, reverse=(k % 2 == 0))
        out += [(x, y) for x in xs]
    return out


@_register("static-grid", "paper 000 Table 1: one person standing still at the measurement grid points")
def static_grid(seed: int, common: Common, *, size=None, frames=None, camera: str = "cam1", dwell: float = 1.5,
                height: float | None = 1.66, width: float | None = 0.42, speed: float = 0.6) -> Scenario:
    """One person walks slowly between the paper's grid points and stands still ``dwell`` seconds at each.

    ``camera``: "cam1" (15 points, Table 1 (a)–(c)), "cam2" (12 points) or "both" (camera 1's points).
    Defaults are the paper's subject (1.66 m, 0.42 m); ``height=None`` draws one. 160×120 by default.
    """
    if camera not in ("cam1", "cam2", "both"):
        raise InputError(f"camera: expected cam1, cam2 or both, got {camera!r}")
    if dwell <= 0 or speed <= 0:
        raise InputError("dwell and speed: expected positive values (s, m/s)")
    rng = np.random.default_rng(seed)
    data = scenes.scene_dict("kato_lab")
    data["obstacles"] = [o for o in data["obstacles"] if o["name"] != "desk"]
    cams = ["cam1", "cam2"] if camera == "both" else [camera]
    scene = _scene(data, size or (160, 120), cams)
    env = _kato_env(scene)
    shape = _shape(rng, env, height, width)
    pts = _serpentine(CAM2_GRID if camera == "cam2" else CAM1_GRID)
    route = _dwell_route(pts, dwell, speed, _FACE_CAMERA)
    track = scripted_track(route, common.fps, _route_frames(route, common.fps), shape.height,
                           initial_yaw=_FACE_CAMERA)
    n = frames or _route_length([track], dwell + 0.3, common.fps, _MAX_FRAMES)
    people = [Person(1, shape, _trim(_pad(track, n), n))]
    return Scenario("static-grid", scene, common.fps, n, people, env, _lighting(common, rng, _kato_light()),
                    _options(common, 0.1), _rigs(scene, common), seed,
                    description="paper 000 Table 1: a person standing still at grid points (speed 0 while standing)")


DESK_ROWS = (0.0, 1.0, 2.0, 3.0)


@_register("desk-occlusion", "paper 000 Table 2: a 0.73 m desk hides the feet (and the image border the head)")
def desk_occlusion(seed: int, common: Common, *, size=None, frames=None, hide: str = "feet", dwell: float = 1.5,
                   height: float | None = 1.66, width: float | None = 0.42, speed: float = 0.6,
                   camera: str = "cam1") -> Scenario:
    """Rows of 0.73 m desks, one 0.45 m in front of each grid row (the paper moved one desk each time).

    ``hide="feet"``: the 9 points of rows y = 0, 1, 2 (feet hidden, head visible — Table 2 (a));
    ``hide="head-and-feet"``: row y = 3, where the image border also cuts the head (Table 2 (b));
    ``hide="all"``: all 12 points. The person walks round the desks' west ends between rows.
    """
    if hide not in ("feet", "head-and-feet", "all"):
        raise InputError(f"hide: expected feet, head-and-feet or all, got {hide!r}")
    if camera not in ("cam1", "both"):
        raise InputError(f"camera: expected cam1 or both, got {camera!r}")
    rng = np.random.default_rng(seed)
    rows = {"feet": DESK_ROWS[:3], "head-and-feet": DESK_ROWS[3:], "all": DESK_ROWS}[hide]
    data = scenes.scene_dict("kato_lab")
    data["obstacles"] = [o for o in data["obstacles"] if o["name"] != "desk"]
    data["obstacles"] += [{"name": f"desk_{k}", "type": "box", "centre": [-1.0, y - 0.45, 0.365],
                           "size": [2.8, 0.6, 0.73]} for k, y in enumerate(DESK_ROWS)]
    scene = _scene(data, size or (160, 120), ["cam1", "cam2"] if camera == "both" else ["cam1"])
    env = _kato_env(scene)
    env = replace(env, obstacle_colours={**{f"desk_{k}": (70, 110, 150) for k in range(4)},
                                         "shelf": (120, 125, 128)})
    shape = _shape(rng, env, height, width)
    route: list[Waypoint] = []
    for y in rows:
        route.append(Waypoint(-3.0, y, speed=speed))
        route += _dwell_route([(-2.0, y), (-1.0, y), (0.0, y)], dwell, speed, _FACE_CAMERA)
        route.append(Waypoint(-3.0, y, speed=speed))
    route = route[:-1]
    track = scripted_track(route, common.fps, _route_frames(route, common.fps), shape.height)
    n = frames or _route_length([track], dwell + 0.3, common.fps, _MAX_FRAMES)
    people = [Person(1, shape, _trim(_pad(track, n), n))]
    return Scenario("desk-occlusion", scene, common.fps, n, people, env, _lighting(common, rng, _kato_light()),
                    _options(common, 0.1), _rigs(scene, common), seed,
                    description=f"paper 000 Table 2: desks hide the feet ({hide})")


@_register("two-crossing", "paper 000 Fig. 9-10: two people crossing in camera 1's image (and passing close by)")
def two_crossing(seed: int, common: Common, *, size=None, frames=None, passing: str = "image",
                 speed: float = 0.9, heights: tuple | None = (1.73, 1.66),
                 widths: tuple | None = (0.48, 0.42)) -> Scenario:
    """Two people in the kato lab: person 1 (1.73 m, 0.48 m) walks left→right 1.6 m beyond person 2
    (1.66 m, 0.42 m) who walks right→left, so one passes behind the other in camera 1's image.

    ``passing="close"``: instead they walk past each other along Y, 0.5 m apart (identity swaps);
    ``"both"``: the image crossing, then the close pass. ``heights=None`` draws the people.
    """
    if passing not in ("image", "close", "both"):
        raise InputError(f"passing: expected image, close or both, got {passing!r}")
    rng = np.random.default_rng(seed)
    scene = _scene(scenes.scene_dict("kato_lab"), size or (160, 120))
    env = _kato_env(scene)
    hs = heights or (None, None)
    ws = widths or (None, None)
    shapes = [_shape(rng, env, hs[i], ws[i]) for i in range(2)]
    v = speed
    image = ([Waypoint(-3.0, 1.6, dwell=0.5), Waypoint(0.6, 1.6, speed=v)],
             [Waypoint(0.6, 0.1, dwell=0.5), Waypoint(-3.0, 0.1, speed=v)])
    close = ([Waypoint(-2.45, 3.7, speed=v), Waypoint(-2.45, -0.9, speed=v)],
             [Waypoint(-1.95, -0.9, speed=v), Waypoint(-1.95, 3.7, speed=v)])
    if passing == "image":
        routes = image
    elif passing == "close":
        routes = ([Waypoint(close[0][0].x, close[0][0].y, dwell=0.5)] + close[0][1:],
                  [Waypoint(close[1][0].x, close[1][0].y, dwell=0.5)] + close[1][1:])
    else:
        routes = (image[0] + [Waypoint(0.6, 3.7, speed=v), Waypoint(-2.45, 3.7, speed=v, dwell=0.5)] + close[0][1:],
                  image[1] + [Waypoint(-3.0, -0.9, speed=v), Waypoint(-1.95, -0.9, speed=v, dwell=0.5)] + close[1][1:])
    tracks = [scripted_track(r, common.fps, _route_frames(r, common.fps), s.height) for r, s in zip(routes, shapes)]
    if passing == "both":
        # Start the close pass together: hold whoever arrives first at its start.
        tracks = _synchronise_last_leg(routes, tracks, shapes, common.fps)
    n = frames or _route_length(tracks, 1.0, common.fps, _MAX_FRAMES)
    people = [Person(i + 1, shapes[i], _trim(_pad(tracks[i], n), n)) for i in range(2)]
    return Scenario("two-crossing", scene, common.fps, n, people, env, _lighting(common, rng, _kato_light()),
                    _options(common, 0.12), _rigs(scene, common), seed,
                    description=f"paper 000 Fig. 9-10: two people crossing ({passing})")


def _synchronise_last_leg(routes, tracks, shapes, fps):
    """Re-plan so both people begin their last leg at the same time (for the close pass)."""
    arrive = []
    for r, tr in zip(routes, tracks):
        start = np.array([r[-2].x, r[-2].y])
        at = np.flatnonzero(np.linalg.norm(tr.xy - start, axis=1) < 1e-6)
        arrive.append(at[0] / fps if len(at) else 0.0)
    t0 = max(arrive) + 0.5
    out = []
    for r, s, a in zip(routes, shapes, arrive):
        r = list(r)
        r[-2] = Waypoint(r[-2].x, r[-2].y, dwell=t0 - a + r[-2].dwell, speed=r[-2].speed)
        out.append(scripted_track(r, fps, _route_frames(r, fps), s.height))
    return out


@_register("sit-down", "paper 000's posture change: a person walks to a stool, sits down, stands up, walks on")
def sit_down(seed: int, common: Common, *, size=None, frames=None, sit_seconds: float = 5.0,
             height: float | None = None, width: float | None = None) -> Scenario:
    """The kato lab with a stool at (−1.8, 1.0): a person comes in by the door, sits facing camera 1
    for ``sit_seconds``, then walks to the front of the room. The ground point while seated is the
    pelvis over the stool; the feet are a thigh length in front of it."""
    rng = np.random.default_rng(seed)
    data = scenes.scene_dict("kato_lab")
    data["obstacles"].append({"name": "stool", "type": "box", "centre": [-1.8, 1.0, 0.21], "size": [0.4, 0.4, 0.42],
                              "blocks_walking": False})
    scene = _scene(data, size or (160, 120))
    env = _kato_env(scene)
    shape = _shape(rng, env, height, width)
    route = [Waypoint(-3.15, 3.6, dwell=0.3), Waypoint(-2.6, 2.6, speed=1.0), Waypoint(-1.8, 1.6, speed=1.0),
             Waypoint(-1.8, 1.0, dwell=sit_seconds + 2.4, speed=0.5, sit=True, face=_FACE_CAMERA),
             Waypoint(-0.6, 0.2, speed=1.0), Waypoint(0.2, -0.6, speed=1.0)]
    track = scripted_track(route, common.fps, _route_frames(route, common.fps), shape.height)
    n = frames or _route_length([track], 1.0, common.fps, _MAX_FRAMES)
    people = [Person(1, shape, _trim(_pad(track, n), n))]
    return Scenario("sit-down", scene, common.fps, n, people, env, _lighting(common, rng, _kato_light()),
                    _options(common, 0.1), _rigs(scene, common), seed, description="paper 000: sitting down")
