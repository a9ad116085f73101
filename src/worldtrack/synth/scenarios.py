"""Built-in scenarios: the papers' experiments and a few more, each a function and a CLI name.

>>> from worldtrack.synth import make_scenario, list_scenarios
>>> sorted(list_scenarios())[:3]
['crowd', 'desk-occlusion', 'entry']
>>> sc = make_scenario("two-crossing", size=(160, 120), frames=5, seed=0)
>>> sc.fps, sc.n_frames, sc.camera_ids
(10.0, 5, ['cam1', 'cam2'])

Every scenario takes ``size`` (W, H), ``frames``, ``seed`` and the common options of
:class:`Common` (``fps``, ``noise``, ``shadow_strength``, ``reflection``, ``blur``, ``light_drift``,
``vignetting``, ``white_balance``), plus its own keyword parameters (see each function).
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass, fields, replace
from typing import Callable

import numpy as np

from worldtrack.errors import InputError
from worldtrack.geometry.camera import look_at_rotation
from worldtrack.scene.load import scene_from_dict
from worldtrack.scene.model import Scene
from worldtrack.synth import scenes
from worldtrack.synth.bodies import (JointAngles, body_parts, draw_body_shape, limb_rotation, HEAD, TORSO,
                                     L_UPPER_ARM, L_FOREARM, R_UPPER_ARM, R_FOREARM, PARTS_PER_PERSON)
from worldtrack.synth.environment import Environment, Window
from worldtrack.synth.motion import (Track, Waypoint, WalkerSettings, finish_track, follow_target as robot_follow,
                                     graph_route, random_walkers, scripted_track, track_from_robot)
from worldtrack.synth.photometry import (Light, LightingSchedule, LightSegment, SensorNoise, WhiteBalance,
                                         light_direction)
from worldtrack.synth.render import RenderOptions
from worldtrack.synth.sensors import SensorSpec
from worldtrack.synth.sequence import CameraRig, Person, Scenario, head_pose


@dataclass(frozen=True)
class Common:
    """Options every scenario accepts (override with ``make_scenario(..., name=value)``).

    Parameters
    ----------
    fps : float — frame rate; time = frame / fps
    noise : float — sensor read noise σ (display units; 0 = noise-free, also no shot noise)
    shadow_strength : float in [0, 1] — 0 switches cast shadows off
    reflection : float in [0, 1] or None — floor reflectivity (None: the scenario's default)
    blur : float — optical blur σ in pixels at 640 px width
    light_drift : float — relative amplitude of the slow illumination drift
    vignetting : float — brightness fall-off at the corners
    white_balance : "auto" or "fixed"
    light_steps : tuple of (time_s, level) — the room light switches to ``level`` (relative) at
        ``time_s`` seconds, e.g. ((5.0, 0.6),) dims it by 40 % five seconds in
    limb_swing : float in [0, 1.5] — scale of the walking limb swing (legs and arms); 0 makes walkers
        glide with the limbs held as when standing, for ablations: how much of a tracker's error
        the gait causes (the paths, speeds and everything else stay the same)
    """

    fps: float = 10.0
    noise: float = 1.8
    shadow_strength: float = 0.6
    reflection: float | None = None
    blur: float = 0.8
    light_drift: float = 0.03
    vignetting: float = 0.12
    white_balance: str = "auto"
    light_steps: tuple = ()
    limb_swing: float = 1.0


_REGISTRY: dict[str, Callable[..., Scenario]] = {}
_DOCS: dict[str, str] = {}


def _register(name: str, summary: str):
    def deco(fn):
        _REGISTRY[name] = fn
        _DOCS[name] = summary
        return fn
    return deco


def list_scenarios() -> dict[str, str]:
    """Names of the built-in scenarios → one-line description."""
    return dict(_DOCS)


def scenario_parameters(name: str) -> dict[str, object]:
    """The scenario's own keyword parameters and their defaults (besides size/frames/seed/Common)."""
    fn = _lookup(name)
    return {k: p.default for k, p in inspect.signature(fn).parameters.items()
            if p.kind == p.KEYWORD_ONLY and k not in ("size", "frames")}


def _lookup(name: str):
    if name not in _REGISTRY:
        raise InputError(f"unknown scenario {name!r} (known: {', '.join(sorted(_REGISTRY))})")
    return _REGISTRY[name]


def make_scenario(name: str, size: tuple[int, int] | str | None = None, frames: int | None = None, seed: int = 0,
                  **overrides) -> Scenario:
    """Build a built-in scenario by name.

    Parameters
    ----------
    name : str — see :func:`list_scenarios`
    size : (width, height) pixels or "WxH", optional — every camera is scaled to it (same aspect)
    frames : int, optional — number of frames (default: the scenario's natural length)
    seed : int — one seed for everything random
    **overrides : the scenario's parameters and :class:`Common` options

    Raises
    ------
    InputError
        Unknown scenario or parameter, or a value out of range.
    """
    fn = _lookup(name)
    common_names = {f.name for f in fields(Common)}
    own = scenario_parameters(name)
    common_kw, own_kw = {}, {}
    for k, v in overrides.items():
        if k in common_names:
            common_kw[k] = v
        elif k in own:
            own_kw[k] = v
        else:
            valid = sorted(set(own) | common_names)
            raise InputError(f"scenario {name!r} has no parameter {k!r} (parameters: {', '.join(valid)})")
    common = Common(**common_kw)
    _check_common(common)
    if frames is not None and (int(frames) != frames or frames < 1):
        raise InputError(f"frames: expected a positive integer, got {frames!r}")
    if not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InputError(f"seed: expected a non-negative integer, got {seed!r}")
    sc = fn(int(seed), common, size=parse_size(size) if size is not None else None,
            frames=int(frames) if frames is not None else None, **own_kw)
    if common.limb_swing != 1.0:
        for person in sc.people:
            person.track.amplitude = person.track.amplitude * float(common.limb_swing)
    sc.params = {"scenario": name, "seed": int(seed), "size": list(_first_size(sc)), "frames": sc.n_frames,
                 **{f.name: getattr(common, f.name) for f in fields(Common)}, **own, **own_kw}
    return sc


def parse_size(size) -> tuple[int, int]:
    """(W, H) from a tuple or a string "WxH"."""
    if isinstance(size, str):
        try:
            w, h = (int(x) for x in size.lower().split("x"))
        except ValueError:
            raise InputError(f"size: expected WxH in pixels (e.g. 320x240), got {size!r}") from None
    else:
        try:
            w, h = (int(x) for x in size)
        except (TypeError, ValueError):
            raise InputError(f"size: expected (width, height) in pixels, got {size!r}") from None
    if w < 16 or h < 12 or w > 4096 or h > 4096:
        raise InputError(f"size: expected 16x12 to 4096x4096 pixels, got {w}x{h}")
    return w, h


def _first_size(sc: Scenario) -> tuple[int, int]:
    cam = next(iter(sc.scene.cameras.values()))
    return cam.width, cam.height


def _check_common(c: Common) -> None:
    if not 0.1 <= c.fps <= 1000:
        raise InputError(f"fps: expected 0.1–1000 frames per second, got {c.fps}")
    for k in ("noise", "blur", "light_drift", "vignetting"):
        if getattr(c, k) < 0:
            raise InputError(f"{k}: expected a value ≥ 0, got {getattr(c, k)}")
    if not 0 <= c.limb_swing <= 1.5:
        raise InputError(f"limb_swing: expected a value in [0, 1.5], got {c.limb_swing}")
    if not 0 <= c.shadow_strength <= 1:
        raise InputError(f"shadow_strength: expected a value in [0, 1], got {c.shadow_strength}")
    if c.reflection is not None and not 0 <= c.reflection <= 1:
        raise InputError(f"reflection: expected a value in [0, 1], got {c.reflection}")
    if c.white_balance not in ("auto", "fixed"):
        raise InputError(f"white_balance: expected 'auto' or 'fixed', got {c.white_balance!r}")
    try:
        steps = [(float(t), float(level)) for t, level in c.light_steps]
    except (TypeError, ValueError):
        raise InputError(f"light_steps: expected pairs (time_s, level), got {c.light_steps!r}") from None
    if any(t < 0 or level < 0 for t, level in steps):
        raise InputError(f"light_steps: expected times and levels ≥ 0, got {c.light_steps!r}")


# ------------------------------------------------------------------------------------ helpers

def _scene(data: dict, size: tuple[int, int] | None, cameras: list[str] | None = None) -> Scene:
    """Scene from a mapping, keeping ``cameras`` (in that order) scaled to ``size`` (same aspect)."""
    scene = scene_from_dict(data, label=data.get("name", "scene"))
    cams = {c: scene.cameras[c] for c in (cameras or list(scene.cameras))}
    if size is not None:
        out = {}
        for cid, cam in cams.items():
            f = size[0] / cam.width
            if abs(cam.height * f - size[1]) > 0.5:
                raise InputError(f"size: camera {cid!r} is {cam.width}x{cam.height}; expected the same aspect "
                                 f"ratio, e.g. {size[0]}x{int(round(cam.height * f))}, got {size[0]}x{size[1]}")
            out[cid] = cam if f == 1 else cam.scaled(f)
        cams = out
    return scene.with_cameras(cams)


def _options(common: Common, reflection_default: float = 0.0) -> RenderOptions:
    shot = 0.05 if common.noise > 0 else 0.0
    return RenderOptions(SensorNoise(common.noise, shot, common.blur, common.vignetting), common.shadow_strength,
                         reflection_default if common.reflection is None else common.reflection)


def _lighting(common: Common, rng: np.random.Generator, base: Light, segments: tuple = ()) -> LightingSchedule:
    steps = tuple(LightSegment(float(t), "", level=float(level)) for t, level in common.light_steps)
    return LightingSchedule(base, drift=common.light_drift, drift_period=float(rng.uniform(25.0, 60.0)),
                            drift_phase=float(rng.uniform(0, 2 * np.pi)), segments=tuple(segments) + steps)


def _rigs(scene: Scene, common: Common, sensors: dict[str, SensorSpec] | None = None,
          schedule: dict | None = None) -> dict[str, CameraRig]:
    return {cid: CameraRig(sensor=(sensors or {}).get(cid, SensorSpec()),
                           white_balance=WhiteBalance(mode=common.white_balance, schedule=dict(schedule or {})))
            for cid in scene.cameras}


def _route_length(tracks: list[Track], tail_s: float, fps: float, cap: int) -> int:
    """Frames until every scripted track has stopped for good (or left), plus a tail."""
    last = 0
    for tr in tracks:
        moving = np.flatnonzero((tr.speed > 0) & tr.present)
        gone = np.flatnonzero(tr.present)
        end = max(moving.max() if len(moving) else 0, 0)
        if len(gone) and gone.max() < len(tr) - 1:
            end = max(end, gone.max())
        last = max(last, end)
    return int(min(cap, last + 1 + round(tail_s * fps)))


def _trim(track: Track, n: int) -> Track:
    return Track(*(getattr(track, f.name)[:n] for f in fields(Track)))


def _route_frames(route: list[Waypoint], fps: float, start_time: float = 0.0, accel: float = 1.2) -> int:
    """Enough frames to walk ``route`` (distances, dwells, braking), with a margin."""
    t = start_time + route[0].dwell
    for a, b in zip(route[:-1], route[1:]):
        t += np.hypot(b.x - a.x, b.y - a.y) / b.speed + b.speed / accel + b.dwell
    return int(np.ceil((t + 2.0) * fps)) + 2


def _shape(rng, env: Environment, height=None, width=None):
    return draw_body_shape(rng, height=height, shoulder_width=width, camouflage=env.background_colours())


_MAX_FRAMES = 20000
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


def _pad(track: Track, n: int) -> Track:
    """Extend a track to n frames by holding its last state (standing still)."""
    T = len(track)
    if n <= T:
        return track
    extra = n - T
    def hold(a, zero=False):
        last = np.repeat(a[-1:], extra, axis=0)
        return np.concatenate([a, np.zeros_like(last) if zero else last])
    return Track(hold(track.xy), hold(track.yaw), hold(track.speed, True), hold(track.present), hold(track.sit),
                 hold(track.phase), hold(track.amplitude, True))


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


# ------------------------------------------------------------------------------------ seed 001

SUN_WARM = (0.86, 0.97, 1.08)      # BGR tint of sunlight
SHADE_BLUE = (1.15, 1.0, 0.86)     # BGR tint of skylight in shade


@_register("follow-target", "paper 001: a robot's stereo camera follows a target among 3 others; "
                            "front light, backlight, shade; white-balance jumps")
def follow_target(seed: int, common: Common, *, size=None, frames=None, others: int = 3, baseline: float = 0.12,
                  distance: float = 1.8, camera_height: float = 1.1, wb_jumps: tuple = (),
                  segments: tuple = ("front", "backlight", "shade-front", "shade-back"),
                  wb_jump_steps: float = 0.0, wb_jump_every: tuple = (1.0, 2.0), crossers: int = 1,
                  crossings: int = 2, cross_speed: tuple = (1.3, 1.3), lookalike: int = 0,
                  clear_route: bool = False, cross_pause: tuple = (0.0, 0.0)) -> Scenario:
    """A target walks a loop in a courtyard; a robot (never drawn) follows at ``distance`` m with a
    stereo camera (``baseline`` m) at ``camera_height``. Of the ``others``, one crosses between
    robot and target twice (short occlusions), the rest walk at random. The sequence is cut into
    lighting ``segments`` (sun behind the camera, sun in front with lowered exposure, building
    shade with bluish skylight lit from the front or back); the automatic white balance jumps when
    the light's colour changes, and ``wb_jumps`` (frames) add scheduled jumps. 320×240 by default.
    Per-frame robot poses go to frames.csv / camera_poses.csv.

    Harder variants (issue 35): ``wb_jump_steps`` > 0 makes the white balance wander off by
    itself every ``wb_jump_every`` seconds (uniform range) by a jump of |ΔR| + |ΔB| uniform in
    0…``wb_jump_steps`` gain steps, on top of its automatic setting (the gains in frames.csv are
    what the camera applied); ``crossers`` of the others cross the robot–target line, ``crossings``
    times in all, at ``cross_speed`` m/s (uniform range; slower crossings hide the target longer),
    stopping ``cross_pause`` seconds (uniform range) in the line of sight;
    ``lookalike`` of the others wear the target's clothes (colours within ±8 %). The original loop
    cuts through the kiosk's corner, and the robot, which drives straight at the target, then
    sticks at the kiosk or the bench for the rest of a long sequence; ``clear_route`` moves every
    waypoint and leg of the loop 0.8 m clear of walls and obstacles, makes the robot steer round
    obstacles, keeps crossers 0.7 m clear of the target and the robot, and makes the others step
    aside when the target walks at them while they stand. The defaults keep the original sequence.
    """
    known = {"front", "backlight", "shade-front", "shade-back"}
    if not segments or any(s not in known for s in segments):
        raise InputError(f"segments: expected a list from {sorted(known)}, got {segments!r}")
    if not 0 <= int(others) <= 10:
        raise InputError(f"others: expected 0 to 10, got {others}")
    _check_follow_extras(crossers, crossings, cross_speed, lookalike, wb_jump_steps, wb_jump_every)
    rng = np.random.default_rng(seed)
    extra = np.random.default_rng([seed, 35])   # draws of the issue-35 options (the defaults draw nothing)
    base_scene = _scene(scenes.scene_dict("courtyard"), size or (320, 240))
    env = Environment(wall_height=6.0, ceiling=False, floor_style="paving", floor_colour=(140, 150, 160),
                      wall_colour=(160, 175, 190), obstacle_colours={"bench": (50, 70, 90), "kiosk": (120, 90, 80)},
                      posters=10, seed=13)
    n = frames or 200
    fps = common.fps
    target_shape = _shape(rng, env)
    loop = [(4.0, 3.0), (11.0, 2.6), (13.5, 5.5), (11.5, 9.5), (5.0, 9.2), (2.8, 6.0)]
    wps = [Waypoint(*loop[0], dwell=1.0)]
    for lap in range(6):
        for k, (x, y) in enumerate(loop[1:] + loop[:1]):
            wps.append(Waypoint(x + rng.uniform(-0.5, 0.5), y + rng.uniform(-0.5, 0.5), speed=rng.uniform(0.9, 1.2),
                                dwell=float(rng.choice([0.0, 0.0, 1.5]))))
    if clear_route:
        wps = _clear_of_obstacles(wps, base_scene.distance_field(0.05), 0.8)
    target = scripted_track(wps, fps, n, target_shape.height, initial_yaw=0.0)
    robot = robot_follow(base_scene, target, fps, distance=distance, avoid=bool(clear_route))
    # Crossers: people crossing the robot–target line, by default one at 30 % and 70 % of the sequence.
    shapes = [target_shape]
    tracks = [target]
    n_cross = min(int(crossers), int(others))
    at = np.round(0.1 + 0.8 * (np.arange(int(crossings)) + 0.5) / max(int(crossings), 1), 12)  # 2: 0.3, 0.7
    speeds = (np.full(len(at), float(cross_speed[0])) if cross_speed[0] == cross_speed[1]
              else extra.uniform(*cross_speed, len(at)))
    pauses = np.zeros(len(at)) if max(cross_pause) <= 0 else extra.uniform(*cross_pause, len(at))
    for c in range(n_cross):
        cross_shape = _shape(rng if c == 0 else extra, env)
        tracks.append(_crosser(base_scene, robot, target, fps, n, cross_shape.height, tuple(at[c::n_cross]),
                               speeds[c::n_cross], keep_clear=0.7 if clear_route else 0.0,
                               pauses=pauses[c::n_cross]))
        shapes.append(cross_shape)
    n_random = max(0, int(others) - n_cross)
    if n_random:
        rshapes = [_shape(rng, env) for _ in range(n_random)]
        tracks += random_walkers(base_scene, n_random, fps, n, rng, [s.height for s in rshapes],
                                 WalkerSettings(dwell_yields=bool(clear_route)),
                                 others=[track_from_robot(robot, fps)] + tracks, other_radius=0.7)
        shapes += rshapes
    for i in range(1, 1 + min(int(lookalike), len(shapes) - 1)):
        shapes[i] = _dressed_like(shapes[i], target_shape, extra)
    persons = [Person(i + 1, shapes[i], tracks[i]) for i in range(len(tracks))]
    # Camera poses: on the robot, looking along its heading, tilted 4° down.
    poses = []
    for (x, y), yaw in zip(robot.xy, robot.yaw):
        fwd = np.array([np.cos(yaw), np.sin(yaw), 0.0])
        pos = np.array([x, y, camera_height]) + 0.1 * fwd
        R = look_at_rotation(pos, pos + fwd + np.array([0.0, 0.0, -np.tan(np.radians(4.0))]))
        poses.append((R, -R @ pos))
    cam0 = base_scene.cameras["robot"].moved(*poses[0])
    scene = base_scene.with_cameras({"robot": cam0})
    seg_len = n / fps / len(segments)
    segs = []
    for k, name in enumerate(segments):
        t0 = k * seg_len
        if name == "front":
            segs.append(LightSegment(t0, name, ambient=0.5, direct=0.75, direction=light_direction(180.0 + 25, 38.0),
                                     tint=SUN_WARM, exposure=1.0, relative_to_camera=True))
        elif name == "backlight":
            segs.append(LightSegment(t0, name, ambient=0.45, direct=0.8, direction=light_direction(15.0, 22.0),
                                     tint=SUN_WARM, exposure=0.62, relative_to_camera=True))
        elif name == "shade-front":
            segs.append(LightSegment(t0, name, ambient=0.7, direct=0.12, direction=light_direction(200.0, 45.0),
                                     tint=SHADE_BLUE, exposure=1.15, relative_to_camera=True))
        else:
            segs.append(LightSegment(t0, name, ambient=0.7, direct=0.12, direction=light_direction(20.0, 45.0),
                                     tint=SHADE_BLUE, exposure=1.05, relative_to_camera=True))
    schedule = {}
    for f in wb_jumps:
        f = int(f)
        if not 0 <= f < n:
            raise InputError(f"wb_jumps: frame {f} is outside 0–{n - 1}")
        schedule[f] = (int(rng.integers(380, 700)), int(rng.integers(380, 700)))
    sensors = {"robot": SensorSpec("stereo", baseline=baseline)}
    rigs = _rigs(scene, common, sensors, schedule)
    rigs["robot"].poses = poses
    rigs["robot"].white_balance.threshold = 30
    if wb_jump_steps > 0:
        rigs["robot"].white_balance.offsets = _wb_wander(extra, n, fps, float(wb_jump_steps), wb_jump_every)
    return Scenario("follow-target", scene, fps, n, persons, env,
                    _lighting(common, rng, Light(tint=SUN_WARM), tuple(segs)), _options(common), rigs, seed,
                    description="paper 001: robot stereo camera following person 1 (the target)")


def _clear_of_obstacles(wps: list[Waypoint], df, clearance: float, step: float = 0.2) -> list[Waypoint]:
    """The route with every waypoint pushed out to ``clearance`` metres from walls and obstacles
    (along the distance field's gradient), and pushed-out waypoints inserted in any leg that
    passes closer (recursively, up to 16 per leg)."""

    def push(xy: np.ndarray) -> np.ndarray:
        for _ in range(80):
            if df.sample(xy[None], outside=-1.0)[0] >= clearance:
                break
            g = df.gradient(xy[None])[0]
            xy = xy + 0.05 * g / max(np.linalg.norm(g), 1e-9)
        return xy

    def leg(a: np.ndarray, b: np.ndarray, depth: int) -> list[np.ndarray]:
        m = max(2, int(np.ceil(np.linalg.norm(b - a) / step)))
        pts = a + np.linspace(0, 1, m)[:, None] * (b - a)
        d = df.sample(pts, outside=-1.0)
        if d.min() >= clearance - 0.05 or depth == 0:
            return []
        mid = push(pts[int(np.argmin(d))])
        return leg(a, mid, depth - 1) + [mid] + leg(mid, b, depth - 1)

    first = push(np.array([wps[0].x, wps[0].y]))
    out = [replace(wps[0], x=float(first[0]), y=float(first[1]))]
    for wp in wps[1:]:
        a, b = np.array([out[-1].x, out[-1].y]), push(np.array([wp.x, wp.y]))
        out += [Waypoint(float(p[0]), float(p[1]), speed=wp.speed) for p in leg(a, b, 4)]
        out.append(replace(wp, x=float(b[0]), y=float(b[1])))
    return out


def _check_follow_extras(crossers, crossings, cross_speed, lookalike, wb_jump_steps, wb_jump_every) -> None:
    if not 0 <= int(crossers) <= 10:
        raise InputError(f"crossers: expected 0 to 10 (at most ``others`` cross), got {crossers}")
    if not 0 <= int(crossings) <= 40:
        raise InputError(f"crossings: expected 0 to 40, got {crossings}")
    if len(cross_speed) != 2 or not 0.2 <= float(cross_speed[0]) <= float(cross_speed[1]) <= 3.0:
        raise InputError(f"cross_speed: expected (low, high) m/s within 0.2–3, got {cross_speed!r}")
    if not 0 <= int(lookalike) <= 10:
        raise InputError(f"lookalike: expected 0 to 10 (at most ``others`` dress alike), got {lookalike}")
    if not 0 <= wb_jump_steps <= 1023:
        raise InputError(f"wb_jump_steps: expected 0–1023 gain steps, got {wb_jump_steps}")
    if len(wb_jump_every) != 2 or not 0.05 <= float(wb_jump_every[0]) <= float(wb_jump_every[1]):
        raise InputError(f"wb_jump_every: expected (low, high) seconds ≥ 0.05, got {wb_jump_every!r}")


def _dressed_like(shape, model, rng: np.random.Generator):
    """``shape`` (its own build, skin and hair) in ``model``'s clothes, each colour within ±8 %."""
    jitter = lambda c: tuple(float(v) for v in np.clip(np.asarray(c) * rng.uniform(0.92, 1.08, 3), 5, 250))
    return replace(shape, top=jitter(model.top), bottom=jitter(model.bottom), shoes=jitter(model.shoes),
                   short_sleeves=model.short_sleeves, shorts=model.shorts, stripes=model.stripes)


WB_WANDER_LIMIT = 300   # steps: the wandering offset stays within ±this on each gain


def _wb_wander(rng: np.random.Generator, n: int, fps: float, max_jump: float, every: tuple) -> dict:
    """frame → (dr, db): a jump of |dr − dr'| + |db − db'| uniform in 0…``max_jump`` every
    ``every`` seconds (uniform range), split at random between the gains, random signs, each
    offset kept within ±WB_WANDER_LIMIT (a component that would leave it is mirrored back, then clipped)."""
    out, cur, t = {}, np.zeros(2), 0.0
    while True:
        t += rng.uniform(*every)
        k = int(round(t * fps))
        if k >= n:
            return out
        size = rng.uniform(0.0, max_jump)
        share = rng.uniform(0.0, 1.0)
        step = size * np.array([share, 1.0 - share]) * rng.choice([-1.0, 1.0], 2)
        new = cur + step
        new = np.where(np.abs(new) > WB_WANDER_LIMIT, cur - step, new)
        cur = np.clip(np.rint(new), -WB_WANDER_LIMIT, WB_WANDER_LIMIT)
        out[k] = (int(cur[0]), int(cur[1]))


def _crosser(scene: Scene, robot, target: Track, fps: float, n: int, height: float, at: tuple,
             speeds=None, keep_clear: float = 0.0, pauses=None) -> Track:
    """A person who walks across the robot–target line at the given fractions of the sequence,
    appearing 3 m to one side and vanishing 3 m to the other (``speeds``: m/s per crossing, 1.3).

    With ``keep_clear`` > 0 a crossing that would come nearer than that to the target or the robot
    (it walks a straight line while they move on) is moved along the line (40–70 % of the way to the
    target) or in time (±1, ±2 s), and left out if nothing works. ``pauses`` (s per crossing): the
    crosser stands that long on the line of sight, halfway.
    """
    df = scene.distance_field(0.05)
    out = Track(np.zeros((n, 2)), np.zeros(n), np.zeros(n), np.zeros(n, bool), np.zeros(n), np.zeros(n), np.zeros(n))
    speeds = np.full(len(at), 1.3) if speeds is None else np.asarray(speeds, dtype=float)
    pauses = np.zeros(len(at)) if pauses is None else np.asarray(pauses, dtype=float)
    tries = [(0.5, 0)] if keep_clear <= 0 else [(f, s) for s in (0, 1, -1, 2, -2) for f in (0.5, 0.4, 0.6, 0.7)]
    for frac, speed, pause in zip(at, speeds, pauses):
        for along, shift in tries:
            kc = int(np.clip(int(frac * (n - 1)) + round(shift * fps), 0, n - 1))
            ks, xy = _crossing(df, robot, target, kc, along, speed, fps, n, pause)
            if ks is None:
                break
            near = min(np.hypot(*(xy - target.xy[ks]).T).min(), np.hypot(*(xy - robot.xy[ks]).T).min())
            if keep_clear <= 0 or near >= keep_clear:
                seg = finish_track(xy, fps, height)
                for f in ("xy", "yaw", "speed", "phase", "amplitude"):
                    getattr(out, f)[ks] = getattr(seg, f)
                out.present[ks] = True
                break
    return out


def _crossing(df, robot, target: Track, kc: int, along: float, speed: float, fps: float, n: int,
              pause: float = 0.0, half: float = 3.0):
    """Frames and positions of one crossing through the point ``along`` of the robot–target line at
    frame ``kc``, perpendicular to it, from ``half`` m to one side to ``half`` m to the other;
    (None, None) if too short. With ``pause`` > 0 the crosser, on reaching the line of sight, walks
    along with it (staying ``along`` of the way from the robot to the target) for ``pause``
    seconds before going on across: someone cutting in between them for a moment."""
    line_at = lambda k: robot.xy[k] + along * (target.xy[k] - robot.xy[k])  # noqa: E731

    def perp_at(k):
        line = target.xy[k] - robot.xy[k]
        return np.array([-line[1], line[0]]) / max(np.linalg.norm(line), 1e-9)

    steps = int(round(2 * half / speed * fps))
    hold = int(round(pause * fps))
    if hold == 0:
        mid, perp = line_at(kc), perp_at(kc)
        a, b = mid - half * perp, mid + half * perp
        if not df.sample(np.array([a, b]), outside=-1.0).min() > 0.35:
            a, b = b, a
        k0 = kc - steps // 2
        ks = np.arange(max(k0, 0), min(k0 + steps + 1, n))
        if len(ks) < 3:
            return None, None
        s_ = (ks - k0) / steps
        return ks, a + s_[:, None] * (b - a)
    k1 = kc - hold // 2                      # reaches the line
    k2 = min(k1 + hold, n - 1)               # leaves it
    k0, k3 = k1 - steps // 2, k2 + steps // 2
    if k1 < 0 or k0 + 3 > n:
        return None, None
    side = 1.0
    ends = np.array([line_at(k1) - half * perp_at(k1), line_at(k2) + half * perp_at(k2)])
    if not df.sample(ends, outside=-1.0).min() > 0.35:
        side = -1.0
    a = line_at(k1) - side * half * perp_at(k1)
    ks = np.arange(max(k0, 0), min(k3 + 1, n))
    xy = np.empty((len(ks), 2))
    for i, k in enumerate(ks):
        if k < k1:
            xy[i] = a + (k - k0) / max(k1 - k0, 1) * (line_at(k1) - a)
        elif k <= k2:
            xy[i] = line_at(k)
        else:
            xy[i] = line_at(k2) + side * (k - k2) / max(k3 - k2, 1) * half * perp_at(k2)
    return ks, xy


# ------------------------------------------------------------------------------------ seed 002

@_register("non-overlapping", "paper 002: an office with walls and desks seen by 4 cameras whose views do not overlap")
def non_overlapping(seed: int, common: Common, *, size=None, frames=None, people: int = 2, legs: int = 14,
                    speed: tuple = (1.0, 1.3), layout: str = "open") -> Scenario:
    """A 16 × 8 m office: a corridor along y = 4 m with desks and partitions on both sides and four
    ceiling cameras looking down on it, 4 m apart, with gaps between their views. People walk
    random routes along the corridor and stop at desks; between cameras nobody sees them.
    ``layout="detours"`` puts a screen across the corridor between every two cameras with one
    passage on alternate sides, so every walk from one view to the next is a detour.
    320×240 by default."""
    if not 1 <= int(people) <= 6:
        raise InputError(f"people: expected 1 to 6, got {people}")
    if layout not in ("open", "detours"):
        raise InputError(f"layout: expected 'open' or 'detours', got {layout!r}")
    rng = np.random.default_rng(seed)
    scene = _scene(scenes.scene_dict("office_4cams" if layout == "open" else "office_4cams_detours"), size or (320, 240))
    colours = {o.name: ((75, 105, 140) if o.name.startswith("desk") else (150, 140, 125)) for o in scene.obstacles}
    env = Environment(wall_height=3.0, floor_style="carpet", floor_colour=(120, 115, 105), wall_colour=(200, 205, 210),
                      obstacle_colours=colours, posters=8, seed=17)
    n = frames or 300
    nodes, edges, fixed = _office_graph(layout)
    persons = []
    for i in range(int(people)):
        shape = _shape(rng, env)
        lane = (i % 3 - 1) * 0.35
        route_idx = graph_route(nodes, edges, int(rng.integers(0, 15)), int(legs), rng)
        wps = []
        v = rng.uniform(*speed)
        for j in route_idx:
            x, y = nodes[j]
            dwell = float(rng.uniform(1.5, 4.0)) if fixed.get(j) == "desk" else 0.0
            wps.append(Waypoint(x, y + (lane if j not in fixed else 0.0), dwell=dwell, speed=v))
        wps[0] = Waypoint(wps[0].x, wps[0].y, dwell=float(rng.uniform(0.0, 4.0)))
        tr = scripted_track(wps, common.fps, n, shape.height)
        persons.append(Person(i + 1, shape, tr))
    light = Light(ambient=0.6, direct=0.45, direction=light_direction(70.0, 70.0))
    return Scenario("non-overlapping", scene, common.fps, n, persons, env, _lighting(common, rng, light),
                    _options(common), _rigs(scene, common), seed,
                    description="paper 002: four non-overlapping cameras in an office")


def _office_graph(layout: str = "open"):
    """Corridor nodes at y = 4 m every metre, desk stops beside each camera's desks; with detours
    the corridor nodes at the screens move into their passages. Returns nodes, edges and the nodes
    walked exactly (no lane offset): index → "desk" or "door"."""
    doors = dict(((int(x), (x, y)) for x, y in scenes.OFFICE_DOORS)) if layout == "detours" else {}
    corridor = [doors.get(x, (float(x), 4.0)) for x in range(1, 16)]
    nodes = list(corridor)
    edges = [(i, i + 1) for i in range(len(corridor) - 1)]
    fixed = {i: "door" for i, (x, _) in enumerate(corridor) if int(x) in doors}
    for xc in (2.0, 6.0, 10.0, 14.0):
        c = corridor.index((xc, 4.0))
        for y in (3.15, 4.85):
            nodes.append((xc + 0.3, y))
            fixed[len(nodes) - 1] = "desk"
            edges.append((c, len(nodes) - 1))
    return np.array(nodes), edges, fixed


# ------------------------------------------------------------------------------------ seed 003

def _booth(size, depth_step_mm, cam_pos, cam_target):
    data = scenes.scene_dict("booth")
    data["cameras"][0].update(position=[float(v) for v in cam_pos], look_at=[float(v) for v in cam_target])
    scene = _scene(data, size or (320, 240))
    env = Environment(wall_height=2.6, floor_style="wood", floor_colour=(90, 120, 150), wall_colour=(170, 180, 185),
                      posters=3, seed=19)
    if depth_step_mm <= 0:
        raise InputError(f"depth_step_mm: expected a positive step in mm, got {depth_step_mm}")
    sensors = {"kinect": SensorSpec("rgbd", baseline=0.075, depth_step=depth_step_mm / 1000.0)}
    return scene, env, sensors


def _smooth_signal(rng, n, fps, amplitude, f_range=(0.08, 0.35), terms=2):
    """Sum of sinusoids with random frequencies (Hz) and phases, peak ≈ ``amplitude``."""
    t = np.arange(n) / fps
    out = np.zeros(n)
    for _ in range(terms):
        out += np.sin(2 * np.pi * rng.uniform(*f_range) * t + rng.uniform(0, 2 * np.pi))
    return amplitude * out / terms


BOOTH_XY = (2.0, 2.8)


def _booth_person(rng, env, height, n, fps):
    shape = _shape(rng, env, height, None)
    T = np.ones(n, bool)
    xy = np.tile(BOOTH_XY, (n, 1))
    tr = Track(xy, np.full(n, -np.pi / 2), np.zeros(n), T, np.zeros(n), np.zeros(n), np.zeros(n))
    ja = JointAngles.neutral(np.array([BOOTH_XY]), np.array([-np.pi / 2]))
    parts = body_parts([shape], ja)
    return shape, tr, parts


def _quat(R: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z), w ≥ 0, of a rotation matrix."""
    w = np.sqrt(max(0.0, 1 + R[0, 0] + R[1, 1] + R[2, 2])) / 2
    x = np.sqrt(max(0.0, 1 + R[0, 0] - R[1, 1] - R[2, 2])) / 2
    y = np.sqrt(max(0.0, 1 - R[0, 0] + R[1, 1] - R[2, 2])) / 2
    z = np.sqrt(max(0.0, 1 - R[0, 0] - R[1, 1] + R[2, 2])) / 2
    x = np.copysign(x, R[2, 1] - R[1, 2])
    y = np.copysign(y, R[0, 2] - R[2, 0])
    z = np.copysign(z, R[1, 0] - R[0, 1])
    q = np.array([w, x, y, z])
    return q / np.linalg.norm(q)


@_register("face-pose", "paper 003: RGB-D close-up of a face with small or large 6-DoF head motion")
def face_pose(seed: int, common: Common, *, size=None, frames=None, motion: str = "small", distance: float = 0.8,
              depth_step_mm: float = 5.0, height: float = 1.72) -> Scenario:
    """A person stands facing a Kinect-like camera ``distance`` m in front of the head and moves the
    head: ``motion="small"`` (about ±6° yaw, ±4° pitch, ±3° roll, ±1 cm) or ``"large"`` (±35°,
    ±20°, ±12°, ±5 cm), smooth random sinusoids. Depth in ``depth_step_mm`` steps (seed 003's
    simulation used 5 mm). pose.csv: the head centre (m), its head → world quaternion, and the head's
    angles relative to the torso (rz, ry, rx in degrees; ZYX). 320×240 by default."""
    if motion not in ("small", "large"):
        raise InputError(f"motion: expected small or large, got {motion!r}")
    if not 0.3 <= distance <= 3.0:
        raise InputError(f"distance: expected 0.3–3 m, got {distance}")
    rng = np.random.default_rng(seed)
    n = frames or 100
    fps = common.fps
    env0 = Environment()
    shape, tr, parts0 = _booth_person(rng, env0, height, n, fps)
    head_c = parts0.centre[HEAD]
    cam_pos = head_c + np.array([0.0, -distance, 0.0])
    scene, env, sensors = _booth(size, depth_step_mm, cam_pos, head_c)
    amp = {"small": (6.0, 4.0, 3.0, 0.01), "large": (35.0, 20.0, 12.0, 0.05)}[motion]
    head = np.column_stack([_smooth_signal(rng, n, fps, np.radians(a)) for a in amp[:3]])
    offset = np.column_stack([_smooth_signal(rng, n, fps, amp[3]) for _ in range(3)])
    person = Person(1, shape, tr, pose={"head": head, "torso_offset": offset})

    def rows(k, t, people, parts):
        out = []
        for i, p in enumerate(people):
            c, R = head_pose(parts, i)
            q = _quat(R)
            rz, ry, rx = np.degrees(p.pose["head"][k])
            out.append({"frame": k, "time": round(t, 6), "id": p.id, "tx": round(c[0], 6), "ty": round(c[1], 6),
                        "tz": round(c[2], 6), "qw": round(q[0], 8), "qx": round(q[1], 8), "qy": round(q[2], 8),
                        "qz": round(q[3], 8), "rz_deg": round(rz, 5), "ry_deg": round(ry, 5), "rx_deg": round(rx, 5)})
        return out

    light = Light(ambient=0.55, direct=0.6, direction=light_direction(-60.0, 35.0))
    return Scenario("face-pose", scene, fps, n, [person], env, _lighting(common, rng, light), _options(common),
                    _rigs(scene, common, sensors), seed, pose_rows=rows,
                    description=f"paper 003: face pose, {motion} motion")


@_register("upper-body", "paper 003: RGB-D view of an upper body with 14-DoF motion "
                          "(torso 6, shoulders 2+2, elbows 2+2)")
def upper_body(seed: int, common: Common, *, size=None, frames=None, distance: float = 1.9,
               depth_step_mm: float = 5.0, height: float = 1.72) -> Scenario:
    """A person faces a Kinect-like camera ``distance`` m away and moves torso and arms: torso
    translation (±3 cm) and ``Rz·Ry·Rx`` rotation (±9°, ±5°, ±5°), each shoulder ``Rz·Ry`` and each
    elbow ``Rz·Ry`` (see :mod:`worldtrack.synth.bodies` for the limb frames). pose.csv: the 14
    parameters (m, degrees) and the world unit axes of both upper arms and forearms (for seed 003's
    limb-axis error). 320×240 by default."""
    if not 0.8 <= distance <= 4.0:
        raise InputError(f"distance: expected 0.8–4 m, got {distance}")
    rng = np.random.default_rng(seed)
    n = frames or 100
    fps = common.fps
    env0 = Environment()
    shape, tr, parts0 = _booth_person(rng, env0, height, n, fps)
    chest = parts0.centre[TORSO] + np.array([0.0, 0.0, 0.1])
    cam_pos = chest + np.array([0.0, -distance, 0.15])
    scene, env, sensors = _booth(size, depth_step_mm, cam_pos, chest)
    sig = lambda a, f=(0.08, 0.3): _smooth_signal(rng, n, fps, a, f)
    torso = np.column_stack([sig(np.radians(9)), sig(np.radians(5)), sig(np.radians(5))])
    offset = np.column_stack([sig(0.03), sig(0.03), sig(0.01)])
    sh_rz = np.column_stack([-0.6 + sig(0.6), 0.6 + sig(0.6)])           # left: − forward; right: + forward
    sh_ry = np.column_stack([0.85 + sig(0.55), 0.85 + sig(0.55)])         # lowered from horizontal
    el_rz = np.column_stack([-(0.8 + sig(0.5)), 0.8 + sig(0.5)])          # forearm bends forward
    el_ry = np.column_stack([sig(0.25), sig(0.25)])
    shoulder = np.stack([limb_rotation(sh_rz[:, k], sh_ry[:, k]) for k in (0, 1)], axis=1)
    elbow = np.stack([limb_rotation(el_rz[:, k], el_ry[:, k]) for k in (0, 1)], axis=1)
    person = Person(1, shape, tr, pose={"torso": torso, "torso_offset": offset, "shoulder": shoulder, "elbow": elbow})

    def rows(k, t, people, parts):
        out = []
        for i, p in enumerate(people):
            base = i * PARTS_PER_PERSON
            lumbar = parts.centre[base + TORSO] - parts.axes[base + TORSO][2] * (0.11 * p.shape.height)
            row = {"frame": k, "time": round(t, 6), "id": p.id,
                   "torso_tx": round(lumbar[0], 6), "torso_ty": round(lumbar[1], 6), "torso_tz": round(lumbar[2], 6)}
            for name, val in zip(("torso_rz_deg", "torso_ry_deg", "torso_rx_deg"), np.degrees(torso[k])):
                row[name] = round(val, 5)
            for s, side in enumerate("lr"):
                row[f"{side}_shoulder_rz_deg"] = round(np.degrees(sh_rz[k, s]), 5)
                row[f"{side}_shoulder_ry_deg"] = round(np.degrees(sh_ry[k, s]), 5)
                row[f"{side}_elbow_rz_deg"] = round(np.degrees(el_rz[k, s]), 5)
                row[f"{side}_elbow_ry_deg"] = round(np.degrees(el_ry[k, s]), 5)
            for name, part in (("l_upper_arm", L_UPPER_ARM), ("l_forearm", L_FOREARM),
                               ("r_upper_arm", R_UPPER_ARM), ("r_forearm", R_FOREARM)):
                a, b = parts.centre[base + part], parts.end[base + part]
                ax = (b - a) / np.linalg.norm(b - a)
                for c, v in zip("xyz", ax):
                    row[f"{name}_axis_{c}"] = round(v, 8)
            out.append(row)
        return out

    light = Light(ambient=0.55, direct=0.6, direction=light_direction(-60.0, 40.0))
    return Scenario("upper-body", scene, fps, n, [person], env, _lighting(common, rng, light), _options(common),
                    _rigs(scene, common, sensors), seed, pose_rows=rows,
                    description="paper 003: upper-body pose, 14 DoF")


SCENARIOS = tuple(_REGISTRY)
