"""The configuration of a tracking run: which method, its preset, the foreground and every method's
settings, resolved from defaults, a file (``--config``), the command line's flags and ``--set``.

Precedence, lowest first: the method's defaults (or its published configuration with
``preset: paper``), the file, the command line's named flags (``--method``, ``--foreground``,
``--threshold``, ``--births``), then each ``--set PATH=VALUE`` in order. :func:`dump_run_config`
writes the resolved configuration as YAML (``--print-config``, ``run.yaml``); reading that file back
with :func:`resolve_run_config` gives the same configuration.

>>> cfg = resolve_run_config(sets=[("method", "blobs"), ("blobs.filter.gate", 4.0)])
>>> cfg.method, cfg.section("blobs").filter.gate
('blobs', 4.0)
>>> resolve_run_config(sets=[("blobs.filter.gat", 4.0)])
Traceback (most recent call last):
...
worldtrack.errors.InputError: blobs.filter.gat: unknown setting (expected one of: process_noise, measurement_noise_m, initial_speed_sigma, gate)
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import yaml

from worldtrack.config import Section, dump_yaml, from_mapping, to_mapping, with_overrides
from worldtrack.errors import InputError
from worldtrack.foreground.config import DEFAULT_SHADOW_TEST, ForegroundConfig

METHODS = ("ellipsoid", "particle", "blobs")
PRESETS = ("default", "paper")
#: Settings of stages besides the tracker, by top-level name: ``module:Section`` (imported when used).
STAGES = {"map": "worldtrack.map.config:MapConfig"}


@dataclass(frozen=True)
class RunConfig:
    """A resolved configuration: the method to run, its preset, the foreground, every method's settings.

    Attributes
    ----------
    method : str — one of :data:`METHODS`
    preset : str — "default" or "paper"
    foreground : ForegroundConfig
    methods : {method: its configuration section} — every method's, so a file can hold all three
    stages : {name: section} — the other stages' settings (:data:`STAGES`: ``map``, the shared map)
    """

    method: str
    preset: str
    foreground: ForegroundConfig
    methods: Mapping[str, Section]
    stages: Mapping[str, Section] = field(default_factory=dict)

    def section(self, method: str | None = None) -> Section:
        """The configuration of ``method`` (default: the one that runs)."""
        return self.methods[method or self.method]

    def to_mapping(self) -> dict[str, Any]:
        """Plain nested values, in the layout of a configuration file."""
        return {"method": self.method, "preset": self.preset, "foreground": to_mapping(self.foreground),
                **{m: to_mapping(s) for m, s in self.methods.items()},
                **{n: to_mapping(s) for n, s in self.stages.items()}}

    def stage(self, name: str) -> Section:
        """The settings of stage ``name`` (e.g. ``"map"``)."""
        return self.stages[name]


def _stage_class(name: str) -> type[Section]:
    import importlib
    module, _, cls = STAGES[name].partition(":")
    return getattr(importlib.import_module(module), cls)


def _method_config_class(method: str) -> type[Section]:
    from worldtrack.trackers import CONFIGS
    return CONFIGS[method]


def _method_threshold(method: str) -> float | None:
    from worldtrack.trackers import method_threshold
    return method_threshold(method)


def _method_shadow_test(method: str, preset: str) -> str:
    from worldtrack.trackers import method_shadow_test
    return method_shadow_test(method, preset) or DEFAULT_SHADOW_TEST


def _base(method: str, preset: str) -> Section:
    cls = _method_config_class(method)
    if preset == "paper":
        if not hasattr(cls, "paper"):
            return cls()          # no published configuration (the blobs baseline): its defaults
        return cls.paper()
    return cls()


def _choice(value: Any, options: Sequence[str], what: str) -> str:
    if value not in options:
        raise InputError(f"{what}: expected one of {', '.join(options)}, got {value!r}")
    return str(value)


def resolve_run_config(data: Mapping[str, Any] | None = None, *, method: str | None = None,
                       preset: str | None = None, flags: Mapping[str, Any] | None = None,
                       sets: Sequence[tuple[str, Any]] = ()) -> RunConfig:
    """Resolve a run's configuration.

    Parameters
    ----------
    data : a configuration file's mapping (``method``, ``preset``, ``foreground``, and a section per
        method), or None
    method, preset : the command line's ``--method`` / ``--preset`` (None: the file's, else
        ellipsoid / default)
    flags : the command line's named settings: ``foreground`` (kind), ``threshold`` (default the
        method's own, e.g. 25 for the particle tracker, else the kind's; ``foreground.shadow_test`` likewise
        defaults to the method's own, evidence for the particle tracker), ``births``
        (where new people may appear; set on the method that runs)
    sets : ``--set`` pairs (dotted path from the top, value), applied last in order

    Raises
    ------
    InputError — one line naming the setting at fault.
    """
    data = dict(data or {})
    unknown = [k for k in data if k not in ("method", "preset", "foreground", *METHODS, *STAGES)]
    if unknown:
        raise InputError(f"{unknown[0]}: unknown setting (expected one of: method, preset, foreground, "
                         f"{', '.join(METHODS + tuple(STAGES))})")
    top_sets = {path: value for path, value in sets if path in ("method", "preset")}
    method = _choice(top_sets.get("method", method or data.get("method", "ellipsoid")), METHODS, "method")
    preset = _choice(top_sets.get("preset", preset or data.get("preset", "default")), PRESETS, "preset")
    methods: dict[str, Section] = {}
    for m in METHODS:
        base = _base(m, preset)
        given = data.get(m)
        if given is not None:
            if not isinstance(given, Mapping):
                raise InputError(f"{m}: expected a mapping of settings, got {given!r}"[:120])
            base = from_mapping(type(base), _deep_merge(to_mapping(base), given), root=m)
        methods[m] = base
    foreground = from_mapping(ForegroundConfig, data.get("foreground"), root="foreground")
    stages = {n: from_mapping(_stage_class(n), data.get(n), root=n) for n in STAGES}
    flags = dict(flags or {})
    fg_changes = {k: v for k, v in (("kind", flags.get("foreground")), ("threshold", flags.get("threshold")))
                  if v is not None}
    if fg_changes:
        foreground = with_overrides(foreground, fg_changes, root="foreground")
    if flags.get("births") is not None:
        path = _find_field(methods[method], "births")
        if path is None:
            raise InputError(f"--births: the {method} tracker has no births setting")
        methods[method] = with_overrides(methods[method], {path: flags["births"]}, root=method)
    for path, value in sets:
        head, _, rest = path.partition(".")
        if head in ("method", "preset"):
            if rest:
                raise InputError(f"{path}: {head} is a value, not a section")
            continue
        if head == "foreground":
            if not rest:
                raise InputError("foreground: is a section (set one of its fields, e.g. foreground.threshold)")
            foreground = with_overrides(foreground, {rest: value}, root="foreground")
        elif head in METHODS:
            if not rest:
                raise InputError(f"{head}: is a section (set one of its fields)")
            methods[head] = with_overrides(methods[head], {rest: value}, root=head)
        elif head in STAGES:
            if not rest:
                raise InputError(f"{head}: is a section (set one of its fields)")
            stages[head] = with_overrides(stages[head], {rest: value}, root=head)
        else:
            raise InputError(f"{head}: unknown setting (expected one of: method, preset, foreground, "
                             f"{', '.join(METHODS + tuple(STAGES))})")
    if foreground.threshold is None and foreground.kind in ("grey", "colour") and \
            _method_threshold(method) is not None:        # the method's own threshold (the particle's γ)
        foreground = with_overrides(foreground, {"threshold": _method_threshold(method)}, root="foreground")
    if foreground.shadow_test is None:                    # the method's own shadow test (the particle's evidence)
        foreground = with_overrides(foreground, {"shadow_test": _method_shadow_test(method, preset)},
                                    root="foreground")
    return RunConfig(method, preset, foreground, methods, stages)


def _deep_merge(base: dict[str, Any], given: Mapping[str, Any]) -> dict[str, Any]:
    out = dict(base)
    for k, v in given.items():
        out[k] = _deep_merge(out[k], v) if isinstance(v, Mapping) and isinstance(out.get(k), dict) else v
    return out


def _find_field(section: Section, name: str, prefix: str = "") -> str | None:
    """The dotted path of the first field called ``name`` in ``section`` (depth first), or of its
    ``where`` if ``name`` is a section with one (``births.where``), or None."""
    for field, value in ((f, getattr(section, f)) for f in type(section).model_fields):
        path = f"{prefix}{field}"
        if field == name and not isinstance(value, Section):
            return path
        if field == name and "where" in type(value).model_fields:
            return f"{path}.where"
        if isinstance(value, Section):
            found = _find_field(value, name, path + ".")
            if found is not None:
                return found
    return None


def dump_run_config(cfg: RunConfig, described: bool = True) -> str:
    """The configuration as YAML, each field's description as a comment: what ``--print-config``
    prints and ``run.yaml`` holds under ``config``."""
    head = yaml.safe_dump({"method": cfg.method, "preset": cfg.preset}, sort_keys=False)
    parts = [head.rstrip(), "foreground:", _indent(dump_yaml(cfg.foreground, described))]
    for m, section in cfg.methods.items():
        parts += [f"{m}:", _indent(dump_yaml(section, described))]
    for n, section in cfg.stages.items():
        parts += [f"{n}:", _indent(dump_yaml(section, described))]
    return "\n".join(p.rstrip("\n") for p in parts) + "\n"


def _indent(text: str) -> str:
    return "\n".join("  " + line if line else line for line in text.splitlines())


__all__ = ["METHODS", "PRESETS", "STAGES", "RunConfig", "dump_run_config", "resolve_run_config"]
