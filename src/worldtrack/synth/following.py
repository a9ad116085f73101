"""Paper 001's world: a robot's stereo camera follows a target among other people, through
lighting segments and white-balance jumps, with crossers and look-alikes.

Registered as ``follow-target``.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from worldtrack.errors import InputError
from worldtrack.geometry.camera import look_at_rotation
from worldtrack.scene.model import Scene
from worldtrack.synth import scenes
from worldtrack.synth.environment import Environment
from worldtrack.synth.motion import (Track, Waypoint, WalkerSettings, finish_track, follow_target as robot_follow,
                                     random_walkers, scripted_track, track_from_robot)
from worldtrack.synth.photometry import Light, LightSegment, light_direction
from worldtrack.synth.scenarios import Common, _register, _scene, _options, _lighting, _rigs, _shape
from worldtrack.synth.sensors import SensorSpec
from worldtrack.synth.sequence import Person, Scenario


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
