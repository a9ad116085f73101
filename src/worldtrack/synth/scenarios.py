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

This module is the registry and the helpers every scenario shares; the scenarios themselves live by
family and register here when :mod:`worldtrack.synth` imports them: :mod:`~worldtrack.synth.kato_lab`
(paper 000), :mod:`~worldtrack.synth.halls` (crowds, two rooms, entry), :mod:`~worldtrack.synth.following`
(paper 001), :mod:`~worldtrack.synth.office` (paper 002), :mod:`~worldtrack.synth.booth` (paper 003) and
:mod:`~worldtrack.synth.unseen` (line of sight).
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass, fields
from typing import Callable

import numpy as np

from worldtrack.errors import InputError
from worldtrack.scene.load import scene_from_dict
from worldtrack.scene.model import Scene
from worldtrack.synth.bodies import draw_body_shape
from worldtrack.synth.environment import Environment
from worldtrack.synth.motion import Track, Waypoint
from worldtrack.synth.photometry import Light, LightingSchedule, LightSegment, SensorNoise, WhiteBalance
from worldtrack.synth.render import RenderOptions
from worldtrack.synth.sensors import SensorSpec
from worldtrack.synth.sequence import CameraRig, Scenario


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
