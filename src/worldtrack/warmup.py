"""Compile (or load from Numba's cache) a method's kernels before the clock starts.

The trackers' hot loops are ``@njit(cache=True)`` kernels. The first run after installing compiles
them (a minute or more on a small machine), later runs load them from ``__pycache__`` (a second
or two). Either happens on first call, so without a warm-up the first tracked frame takes all of
it and frames/s figures count compilation. :func:`warm_up` runs the configured tracker, with its
configured foreground, over a few frames of a tiny scene drawn here (two cameras, one person
walking in), which calls every kernel the method uses with the argument types a real run passes;
the run's own clock then starts with everything compiled.

``python -m worldtrack.warmup`` warms every method (``make demo``/``make test`` set-up do it once).

>>> seconds, compiled = warm_up("blobs")                  # doctest: +SKIP
"""

from __future__ import annotations

import sys
import time
from typing import Any

import numpy as np

# Image sizes of the two cameras: some steps take other paths on images over 320 px wide.
_SIZES = {"cam1": (640, 480), "cam2": (320, 240)}
_FPS = 10.0
_FRAMES = 16
# People of the tiny scene: (x, y) at frame 0 and velocity (m/frame); the first two cross, the
# third walks in over the image border, the fourth stands behind the desk (feet hidden to both
# cameras), so births, merges, partial views and hidden columns are all exercised.
_PEOPLE = (((-1.6, -0.4), (0.13, 0.03)), ((1.4, 0.5), (-0.12, -0.03)), ((2.6, 1.9), (-0.15, 0.0)),
           ((-0.2, 1.9), (0.0, 0.0)))
# A desk the third person walks behind (both cameras look over it): hidden-feet paths.
_DESK = {"name": "desk", "type": "box", "centre": [-0.2, 1.4, 0.4], "size": [1.4, 0.5, 0.8]}
# From this frame on, a wide dark band crosses every image (a passing trolley, a light change):
# foreground from border to border, as close-up people give.
_BAND_FROM = 12
# Trackers whose births come only from entry regions: the people on the floor at frame 0 (the two
# crossing, the one behind the desk) are put on the map by hand, as `--init` does, so the kernels
# of several people (occluder layers, the merge of boxes on one object) and of hidden feet (pixel
# weights of hidden columns) run too.
_PUT_ON_MAP = ("particle",)
_ON_FLOOR_AT_START = (0, 1, 3)


def _tiny_scene(camera_ids: tuple[str, ...] = tuple(_SIZES)) -> Any:
    """The warm-up room seen by ``camera_ids`` (kernels that take a tuple of cameras compile once per
    camera count: a one-camera run needs its own specialisation)."""
    from worldtrack.scene import scene_from_dict

    cams = [{"id": "cam1", "image_size": list(_SIZES["cam1"]), "position": [-3.5, -3.5, 3.0], "look_at": [0.0, 0.0, 0.8],
             "hfov_deg": 70.0},
            {"id": "cam2", "image_size": list(_SIZES["cam2"]), "position": [3.5, -3.5, 3.0], "look_at": [0.0, 0.0, 0.8],
             "hfov_deg": 70.0, "distortion": [-0.05, 0.0, 0.0, 0.0, 0.0]}]
    cams = [c for c in cams if c["id"] in camera_ids]
    return scene_from_dict({"name": "warm-up", "cameras": cams,
                            "floor": {"walkable": [{"outer": [[-2, -2], [2, -2], [2, 2.4], [-2, 2.4]]}]},
                            "obstacles": [_DESK],
                            "entry_regions": [{"name": "door", "polygon": [[-2, -2], [-1.4, -2], [-1.4, 2], [-2, 2]]}]},
                           label="warm-up")


def _frames(scene: Any) -> tuple[dict[str, np.ndarray], list[dict[str, np.ndarray]]]:
    """Textured empty images and frames of three people walking (:data:`_PEOPLE`), per camera."""
    import cv2

    from worldtrack.viz.overlay import ellipse_outline

    rng = np.random.default_rng(0)
    backgrounds = {cid: cv2.GaussianBlur(rng.integers(90, 170, (h, w, 3), dtype=np.uint8), (5, 5), 0)
                   for cid, (w, h) in _SIZES.items() if cid in scene.cameras}
    frames = []
    for k in range(_FRAMES):
        bundle = {}
        for cid, cam in scene.cameras.items():
            img = backgrounds[cid].copy()
            desk = scene.obstacles[0]
            behind = [n for n, ((x0, y0), (vx, vy)) in enumerate(_PEOPLE) if y0 + vy * k > desk.centre[1]]
            for group in (behind, [n for n in range(len(_PEOPLE)) if n not in behind]):
                for n in group:
                    (x0, y0), (vx, vy) = _PEOPLE[n]
                    outline = ellipse_outline(cam, x0 + vx * k, y0 + vy * k, 1.7, 0.45)
                    if outline is not None:
                        cv2.fillPoly(img, [np.round(outline).astype(np.int32)], (40 + 60 * n, 30, 160 - 50 * n))
                if group is behind:    # the desk hides those behind it (both cameras look from -Y)
                    _redraw_desk(img, backgrounds[cid], cam, desk)
            if k >= _BAND_FROM:
                img[-img.shape[0] // 8:-img.shape[0] // 24] = (20, 20, 20)
            bundle[cid] = img
        frames.append(bundle)
    return backgrounds, frames


def _redraw_desk(img: np.ndarray, background: np.ndarray, camera: Any, desk: Any) -> None:
    """Paint the desk (part of the background) back over whoever walks behind it, in place."""
    import cv2

    hull = cv2.convexHull(np.round(camera.project(desk.corners)).astype(np.int32))
    mask = np.zeros(img.shape[:2], np.uint8)
    cv2.fillConvexPoly(mask, hull, 1)
    img[mask > 0] = background[mask > 0]


def warm_up(method: str, config: Any = None, foreground: Any = None) -> tuple[float, int]:
    """Call every kernel ``method`` uses once, with the types of a real run.

    Parameters
    ----------
    method : "ellipsoid", "particle" or "blobs"
    config : the method's configuration (default: its defaults) — the run's own, so that numbers
        given as integers or floats compile the same specialisations the run will call
    foreground : :class:`~worldtrack.foreground.config.ForegroundConfig` (default: the method's own, as
        :func:`~worldtrack.runconfig.resolve_run_config` gives it)

    Returns
    -------
    seconds : float — how long it took
    compiled : int — kernels that had to be compiled (0 when all came from the cache)
    """
    from worldtrack.foreground import foregrounds_from_config
    from worldtrack.runconfig import resolve_run_config
    from worldtrack.trackers import make_tracker, warm_started
    from worldtrack.trackers.base import Frame

    t0 = time.perf_counter()
    before = _cache_misses()
    if foreground is None:                  # the method's own foreground model, as a run without settings has
        foreground = resolve_run_config(method=method).foreground
    for camera_ids in (tuple(_SIZES), ("cam1",)):       # two cameras, then one (its own specialisations)
        scene = _tiny_scene(camera_ids)
        backgrounds, frames = _frames(scene)
        fg = foregrounds_from_config(scene, backgrounds, foreground)
        tracker = make_tracker(method, scene, fg, config)
        if method in _PUT_ON_MAP:
            for track_id, n in enumerate(_ON_FLOOR_AT_START, start=1):
                tracker.init_track(*_PEOPLE[n][0], track_id, 0.0)
        items = ((k, k / _FPS, {c: Frame(img, k / _FPS, k) for c, img in b.items()}) for k, b in enumerate(frames))
        for _, t, bundle in warm_started(tracker, items):
            tracker.step(bundle, t)
    return time.perf_counter() - t0, _cache_misses() - before


def _cache_misses() -> int:
    """Kernels compiled so far in this process (Numba dispatchers of worldtrack with cache misses)."""
    from numba.core.registry import CPUDispatcher

    seen: dict[int, CPUDispatcher] = {}
    for name, module in list(sys.modules.items()):
        if name.startswith("worldtrack") and module is not None:
            seen.update((id(v), v) for v in vars(module).values() if isinstance(v, CPUDispatcher))
    return sum(sum(d.stats.cache_misses.values()) for d in seen.values())


def say_warm_up(method: str, config: Any = None, foreground: Any = None, stream: Any = None) -> float:
    """:func:`warm_up` with one line on ``stream`` (default standard error) saying what it did and how
    long it took; on a terminal the line first says what is being waited for."""
    stream = sys.stderr if stream is None else stream
    live = hasattr(stream, "isatty") and stream.isatty()
    if live:
        print("kernels: compiling or loading (compiling takes about a minute after an install)…",
              end="", file=stream, flush=True)
    seconds, compiled = warm_up(method, config, foreground)
    what = (f"compiled {compiled} in {seconds:.1f} s (first run only; cached for later runs)" if compiled
            else f"loaded from the cache in {seconds:.1f} s")
    print(("\r\033[K" if live else "") + f"kernels: {what}", file=stream, flush=True)
    return seconds


def warm_up_renderer() -> tuple[float, int]:
    """Render two small frames of the synthetic world (its ray-casting kernels): (seconds, compiled)."""
    from worldtrack.synth import make_scenario

    t0 = time.perf_counter()
    before = _cache_misses()
    make_scenario("two-crossing", size=(160, 120), frames=2, seed=0).render()
    return time.perf_counter() - t0, _cache_misses() - before


def main(argv: list[str] | None = None) -> int:
    """``python -m worldtrack.warmup [NAME …]``: warm the kernels of each tracking method and of the
    synthetic renderer (``synth``); default all."""
    from worldtrack.trackers import METHODS

    names = list(argv if argv is not None else sys.argv[1:]) or [*METHODS, "synth"]
    for name in names:
        seconds, compiled = warm_up_renderer() if name == "synth" else warm_up(name)
        print(f"{name}: {compiled} kernels compiled, {seconds:.1f} s", file=sys.stderr)
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
