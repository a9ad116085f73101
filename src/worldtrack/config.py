"""One config system for every tracker and stage: nested sections, validated, read from YAML.

A configuration is a tree of :class:`Section` models (pydantic, frozen): a tracker's config holds
one section per step of its method (``motion``, ``likelihood``, …), each a handful of fields with
a one-line description and units. Everything a user can set goes through the same path:

* construction in Python (``MotionConfig(noise_m=0.05)``) validates;
* :func:`from_mapping` reads a nested mapping (a YAML file), unknown keys are errors;
* :func:`with_overrides` applies ``{"motion.noise_m": 0.05}`` (the command line's ``--set``);
* :func:`to_mapping` and :func:`dump_yaml` write it back (``--print-config``, ``run.yaml``) and
  :func:`from_mapping` reads that back to an equal config.

Every error is an :class:`~worldtrack.errors.InputError` naming the field by its full path and
what was expected: ``particle.motion.noise_m: expected a number ≥ 0, got -1``.

>>> from worldtrack.trackers.ellipsoid.config import EllipsoidConfig      # doctest: +SKIP
>>> cfg = with_overrides(EllipsoidConfig(), {"match.step_m": 0.1}, root="ellipsoid")  # doctest: +SKIP
>>> cfg.match.step_m                                                    # doctest: +SKIP
0.1
>>> parse_assignment("particle.motion.noise_m=-1")
('particle.motion.noise_m', -1)
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, ClassVar, Mapping, TypeVar

import yaml
from pydantic import BaseModel, ConfigDict, ValidationError

from worldtrack.errors import InputError

S = TypeVar("S", bound="Section")

#: The longest excerpt of a bad value quoted in an error message.
_MAX_QUOTE = 60


class Section(BaseModel):
    """A group of related settings: frozen, no unknown fields, each field described with its unit.

    Subclasses declare fields with ``pydantic.Field(default, description=..., ge=..., ...)`` and
    nested sections as fields whose type is another :class:`Section`. Cross-field rules go in a
    ``@model_validator(mode="after")`` that raises ``ValueError("field: expected …")``.
    ``path`` (a class variable) is where the section sits in a full configuration
    (``"particle.motion"``): errors of a section built on its own are reported under it.
    """

    model_config = ConfigDict(frozen=True, extra="forbid")
    path: ClassVar[str] = ""

    def __init__(self, **data: Any) -> None:
        try:
            super().__init__(**data)
        except ValidationError as e:
            raise InputError(_message(e, type(self).path or type(self).__name__)) from None

    # Nested sections are validated by pydantic's core directly (not through this __init__), so
    # their errors reach the top with their full path.
    __init__.__pydantic_base_init__ = True  # type: ignore[attr-defined]

    def replace(self: S, **changes: Any) -> S:
        """A copy with top-level fields changed, validated (``dataclasses.replace`` for sections)."""
        return type(self)(**{**{name: getattr(self, name) for name in type(self).model_fields}, **changes})


def from_mapping(cls: type[S], data: Mapping[str, Any] | None, root: str | None = None) -> S:
    """Build section ``cls`` from a nested mapping (e.g. a YAML document), validating every field.

    Missing fields keep their defaults; unknown keys, wrong types and values out of range raise
    :class:`InputError` naming the field path (under ``root`` if given).
    """
    if data is None:
        data = {}
    if not isinstance(data, Mapping):
        raise InputError(f"{root or cls.__name__}: expected a mapping of settings, got {_quote(data)}")
    try:
        return cls.model_validate(dict(data))
    except ValidationError as e:
        raise InputError(_message(e, root if root is not None else (cls.path or None))) from None


def to_mapping(section: Section) -> dict[str, Any]:
    """The section as plain nested dicts, lists and scalars (what YAML and JSON write)."""
    return section.model_dump(mode="json")


def with_overrides(section: S, overrides: Mapping[str, Any], root: str | None = None) -> S:
    """A copy of ``section`` with fields set by dotted path (``{"motion.noise_m": 0.05}``).

    A path that names no field (or a section where a value is expected) raises
    :class:`InputError` naming it and the fields that exist there.
    """
    data = to_mapping(section)
    for path, value in overrides.items():
        _assign(data, type(section), path, value, root)
    return from_mapping(type(section), data, root)


def _assign(data: dict, cls: type[Section], path: str, value: Any, root: str | None) -> None:
    """Set ``data[a][b]… = value`` for ``path = "a.b…"``, checking each name against ``cls``."""
    parts = path.split(".")
    where = root or ""
    node, model = data, cls
    for i, name in enumerate(parts):
        full = f"{where}.{name}" if where else name
        fields = model.model_fields
        if name not in fields:
            raise InputError(f"{full}: unknown setting (expected one of: {', '.join(fields)})")
        sub = _section_type(fields[name].annotation)
        last = i == len(parts) - 1
        if last:
            if sub is not None and not isinstance(value, Mapping):
                raise InputError(f"{full}: is a section (set one of its fields: "
                                 f"{', '.join(f'{full}.{n}' for n in sub.model_fields)})")
            node[name] = value
        else:
            if sub is None:
                raise InputError(f"{full}: is a value, not a section: cannot set {path!r}")
            node, model = node.setdefault(name, {}), sub
        where = full


def _section_type(annotation: Any) -> type[Section] | None:
    return annotation if isinstance(annotation, type) and issubclass(annotation, Section) else None


def parse_assignment(text: str) -> tuple[str, Any]:
    """``"a.b.c=value"`` → ``("a.b.c", value)``, the value read as YAML (numbers, true/false,
    lists, ``null``); the command line's ``--set``.

    >>> parse_assignment("particle.motion.noise_m=0.05")
    ('particle.motion.noise_m', 0.05)
    >>> parse_assignment("ellipsoid.height.range_m=[1.2, 2.0]")
    ('ellipsoid.height.range_m', [1.2, 2.0])
    """
    if "=" not in text:
        raise InputError(f"--set {_quote(text)}: expected NAME=VALUE, e.g. particle.motion.noise_m=0.05")
    path, raw = text.split("=", 1)
    path = path.strip()
    if not path or any(not part.isidentifier() for part in path.split(".")):
        raise InputError(f"--set {_quote(text)}: {_quote(path)} is not a setting name (dotted, e.g. "
                         "ellipsoid.match.step_m)")
    try:
        value = yaml.safe_load(raw) if raw.strip() else None
    except yaml.YAMLError:
        value = raw.strip()
    return path, value


def load_yaml(path: str | Path) -> dict[str, Any]:
    """A YAML file's top-level mapping (empty for an empty file), errors naming the file."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError(f"{p}: no such file") from None
    except UnicodeDecodeError:
        raise InputError(f"{p}: not a UTF-8 text file") from None
    except OSError as e:
        raise InputError(f"{p}: cannot read ({e.strerror})") from None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark is not None else ""
        raise InputError(f"{p}: not valid YAML{where}") from None
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise InputError(f"{p}: expected a mapping of settings at the top, got {type(data).__name__}")
    return data


def dump_yaml(section: Section, described: bool = True) -> str:
    """The section as YAML, each field with its description as a comment (``described``)."""
    lines: list[str] = []
    _dump(section, 0, lines, described)
    return "\n".join(lines) + "\n"


def _dump(section: Section, indent: int, lines: list[str], described: bool) -> None:
    pad = "  " * indent
    for name, info in type(section).model_fields.items():
        value = getattr(section, name)
        if isinstance(value, Section):
            note = f"  # {info.description}" if described and info.description else ""
            lines.append(f"{pad}{name}:{note}")
            _dump(value, indent + 1, lines, described)
            continue
        text = yaml.safe_dump(_plain(value), default_flow_style=True, width=10_000).strip()
        if text.endswith("\n..."):
            text = text[:-4].strip()
        text = text.removesuffix("...").strip()
        note = f"  # {info.description}" if described and info.description else ""
        lines.append(f"{pad}{name}: {text}{note}")


def _plain(value: Any) -> Any:
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    if isinstance(value, float) and math.isinf(value):
        return value
    return value


# ---------------------------------------------------------------------------- error messages

def _message(error: ValidationError, root: str | None) -> str:
    """One line for the first problem of a pydantic ValidationError: ``path: expected …, got …``."""
    e = error.errors(include_url=False)[0]
    loc = [str(p) for p in e.get("loc", ())]
    path = ".".join(([root] if root else []) + loc) or (root or "config")
    kind = e.get("type", "")
    ctx = e.get("ctx", {}) or {}
    given = e.get("input")
    if kind == "extra_forbidden":
        return f"{path}: unknown setting"
    if kind == "missing":
        return f"{path}: required"
    expected = _EXPECTED.get(kind)
    if expected is not None:
        expected = expected.format(**{k: _fmt(v) for k, v in ctx.items()})
    elif kind == "value_error":
        text = str(ctx.get("error", e.get("msg", "")))
        # A cross-field rule: "field: expected …" names its own field.
        if ":" in text:
            field, rest = text.split(":", 1)
            return f"{path}.{field.strip()}:{rest}" if loc or root else f"{field.strip()}:{rest}"
        return f"{path}: {text}"
    else:
        expected = e.get("msg", "a valid value")
    return f"{path}: expected {expected}, got {_quote(given)}"


_EXPECTED = {
    "greater_than": "a number > {gt}",
    "greater_than_equal": "a number ≥ {ge}",
    "less_than": "a number < {lt}",
    "less_than_equal": "a number ≤ {le}",
    "finite_number": "a finite number",
    "float_type": "a number",
    "float_parsing": "a number",
    "int_type": "a whole number",
    "int_parsing": "a whole number",
    "int_from_float": "a whole number",
    "bool_type": "true or false",
    "bool_parsing": "true or false",
    "string_type": "text",
    "literal_error": "one of {expected}",
    "tuple_type": "a list",
    "list_type": "a list",
    "too_short": "at least {min_length} values",
    "too_long": "at most {max_length} values",
    "model_type": "a mapping of settings",
    "model_attributes_type": "a mapping of settings",
    "dict_type": "a mapping of settings",
}


def _fmt(v: Any) -> str:
    if isinstance(v, float) and v.is_integer():
        return str(int(v))
    return str(v)


def _quote(value: Any) -> str:
    """A short printable excerpt of a value (never the whole of a huge input)."""
    text = repr(value)
    return text if len(text) <= _MAX_QUOTE else text[:_MAX_QUOTE - 3] + "..."


__all__ = ["Section", "dump_yaml", "from_mapping", "load_yaml", "parse_assignment", "to_mapping",
           "with_overrides"]
