"""Trackers: each has ``step(frames, t) -> list[Track]`` over a shared :class:`PositionMap`.

``make_tracker(method, scene, foregrounds, ...)`` builds one by name, as the command line and the
YAML select them:

* ``ellipsoid`` — analysis by synthesis with ellipsoid people (paper 000), the default;
* ``particle`` — 3-D particle filters with the height-column likelihood (paper 004), one or more
  cameras (the likelihood multiplies over the cameras that see a particle);
* ``blobs`` — the tracking-by-detection baseline (MOG2 blobs + Stone Soup), for comparison.

Each method's configuration is a :class:`~worldtrack.config.Section` tree
(:func:`method_config`), set from a file or per field with dotted paths
(``{"match.step_m": 0.1}``); ``preset="paper"`` starts from the method as published.
"""

from __future__ import annotations

from typing import Any, Mapping

from worldtrack.config import Section, with_overrides
from worldtrack.errors import InputError
from worldtrack.registry import Registry
from worldtrack.trackers.base import Frame, Person, PositionMap, Track, Tracker, TrackerBase, warm_started

METHODS = ("ellipsoid", "particle", "blobs")
PRESETS = ("default", "paper")

#: Tracker classes by method name (imported when first used: they compile kernels).
TRACKERS: Registry[type] = Registry("--method")
#: Their configuration classes (light modules: pydantic only).
CONFIGS: Registry[type] = Registry("--method")
for _name, _module in (("ellipsoid", "ellipsoid"), ("particle", "particle"), ("blobs", "blobs")):
    _cls = {"ellipsoid": "Ellipsoid", "particle": "Particle", "blobs": "Blob"}[_name]
    TRACKERS.add_lazy(_name, f"worldtrack.trackers.{_module}:{_cls}Tracker")
    CONFIGS.add_lazy(_name, f"worldtrack.trackers.{_module}:{_cls}Config")


def method_config(method: str, preset: str = "default", overrides: Mapping[str, Any] | None = None) -> Any:
    """The configuration of ``method`` for ``preset``, with ``overrides`` (dotted paths) applied.

    Raises :class:`InputError` naming the method, preset or field at fault.
    """
    cls = CONFIGS[method]
    if preset not in PRESETS:
        raise InputError(f"--preset: expected {' or '.join(PRESETS)}, got {preset!r}")
    if preset == "paper":
        if not hasattr(cls, "paper"):
            raise InputError(f"--preset paper: the {method} tracker has no published configuration")
        config = cls.paper()
    else:
        config = cls()
    if overrides:
        config = _override(config, overrides, method)
    return config


def _override(config: Section, overrides: Mapping[str, Any], method: str) -> Section:
    return with_overrides(config, overrides, root=method)


def method_threshold(method: str) -> float | None:
    """The foreground threshold ``method`` runs with when none is given (None: the foreground kind's
    default, :data:`worldtrack.foreground.DEFAULT_THRESHOLDS`).

    >>> method_threshold("ellipsoid"), method_threshold("particle")
    (None, 25.0)
    """
    return CONFIGS[method].foreground_threshold


def method_shadow_test(method: str, preset: str = "default") -> str | None:
    """The foreground shadow test ``method`` runs with when none is given (None: the foreground's
    default, "colour"); the paper preset always has None (no published method has the test).

    >>> method_shadow_test("ellipsoid"), method_shadow_test("particle"), method_shadow_test("particle", "paper")
    (None, 'evidence', None)
    """
    if preset == "paper":
        return None
    return getattr(CONFIGS[method], "foreground_shadow_test", None)


def make_tracker(method: str, scene, foregrounds: Mapping, config: Any = None, *, preset: str = "default",
                 overrides: Mapping[str, Any] | None = None, position_map: PositionMap | None = None,
                 **options: Any) -> Tracker:
    """Build a tracker by name.

    Parameters
    ----------
    method : one of :data:`METHODS`
    scene : Scene
    foregrounds : {camera_id: foreground model}
    config : the method's configuration; default :func:`method_config` of ``preset``
    preset : "default" (with worldtrack's extensions) or "paper" (the method as published)
    overrides : {dotted field path: value}, applied to the configuration
    position_map : share one map between trackers (default: a new one)
    options : fields by name (top-level fields of a configuration, as ``overrides``)
    """
    changes = {**dict(options), **dict(overrides or {})}
    if config is None:
        config = method_config(method, preset, changes)
    elif changes:
        config = _override(config, changes, method)
    tracker_cls = TRACKERS[method]
    if position_map is not None:
        return tracker_cls(scene, foregrounds, config, position_map=position_map)
    return tracker_cls(scene, foregrounds, config)


__all__ = ["CONFIGS", "METHODS", "PRESETS", "TRACKERS", "Frame", "Person", "PositionMap", "Track", "Tracker",
           "TrackerBase", "method_shadow_test", "method_threshold", "make_tracker", "method_config", "warm_started"]
