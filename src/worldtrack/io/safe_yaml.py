"""Reading YAML that users write, safely and as they mean it.

PyYAML's ``safe_load`` is safe against code execution but not against everything a hand-edited
or hostile file can hold:

* **size**: a file over ``max_bytes`` (default :data:`MAX_BYTES`) is refused before parsing (the
  pure-Python parser, needed for the nesting limit, reads about 100 kB a second on a busy machine);
* **nesting**: :data:`MAX_DEPTH` levels at most (deeper ones reach Python's recursion limit);
* **aliases**: ``&a``/``*a`` are kept, but the document they expand to may hold at most
  :data:`MAX_NODES` values (an "alias bomb" of nine nested aliases expands to 10⁹);
* **YAML 1.1 surprises**: numbers are read as YAML 1.2 reads them (``0640`` is 640, not the octal
  416; ``1:30`` is the text "1:30", not 90; ``yes``/``no``/``on``/``off`` are text, not booleans);
* **duplicate keys** are an error (PyYAML keeps the last one silently).

Every problem is one :class:`~worldtrack.errors.InputError` line naming the file and line, and
quoting at most a short excerpt of the input.

>>> load_yaml_text("size: [0640, 0480]\\nwhen: 1:30\\nflag: yes\\n", "f.yaml")
{'size': [640, 480], 'when': '1:30', 'flag': 'yes'}
>>> load_yaml_text("a: 1\\na: 2\\n", "f.yaml")
Traceback (most recent call last):
...
worldtrack.errors.InputError: f.yaml: line 2: key 'a' given twice (first at line 1)
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import yaml

from worldtrack.errors import InputError

#: Largest file read by default (bytes).
MAX_BYTES = 1_000_000
#: Deepest nesting of lists and mappings.
MAX_DEPTH = 50
#: Most values (scalars, list items, mapping entries) a document may hold once aliases are expanded.
MAX_NODES = 200_000
#: Longest excerpt of the input quoted in a message.
MAX_QUOTE = 60

# YAML 1.2 core schema scalars (https://yaml.org/spec/1.2.2/#1032-tag-resolution).
_INT = re.compile(r"[-+]?[0-9]+|0o[0-7]+|0x[0-9a-fA-F]+")
_FLOAT = re.compile(r"[-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?|[-+]?\.(inf|Inf|INF)|\.(nan|NaN|NAN)")
_BOOL = re.compile(r"true|True|TRUE|false|False|FALSE")
_NULL = re.compile(r"~|null|Null|NULL|")


def short(value: Any, limit: int = MAX_QUOTE) -> str:
    """``repr(value)`` cut to ``limit`` characters (with ``…``), for messages.

    >>> short("x" * 100, 10)
    "'xx...xxx'"
    >>> short(list(range(100)))
    '[0, 1, 2, 3, 4, 5, ...]'
    """
    import reprlib

    r = reprlib.Repr()
    r.maxstring, r.maxother, r.maxlist, r.maxdict, r.maxlevel = limit, limit, 6, 6, 3
    text = r.repr(value)
    return text if len(text) <= limit else text[: limit - 1] + "…"


def clip(text: str, limit: int = MAX_QUOTE) -> str:
    """``text`` cut to ``limit`` characters (ending in ``…``), unquoted.

    >>> clip("frame,id,x,y", 8)
    'frame,i…'
    """
    return text if len(text) <= limit else text[: limit - 1] + "…"


class _Loader(yaml.SafeLoader):
    """SafeLoader with YAML 1.2 scalars, a depth limit and duplicate-key detection."""

    def __init__(self, stream: str, label: str):
        super().__init__(stream)
        self.label = label
        self._depth = 0

    def compose_node(self, parent: Any, index: Any) -> Any:
        self._depth += 1
        try:
            if self._depth > MAX_DEPTH:
                mark = self.peek_event().start_mark
                raise InputError(f"{self.label}: line {mark.line + 1}: nested deeper than {MAX_DEPTH} levels")
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1

    def construct_mapping(self, node: Any, deep: bool = False) -> dict:
        seen: dict[Any, int] = {}
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=True)
            try:
                first = seen.get(key)
            except TypeError:        # an unhashable key: PyYAML's own error follows
                continue
            if first is not None:
                raise InputError(f"{self.label}: line {key_node.start_mark.line + 1}: key {short(key)} given "
                                 f"twice (first at line {first})")
            seen[key] = key_node.start_mark.line + 1
        return super().construct_mapping(node, deep=deep)


# Replace YAML 1.1's implicit resolvers by the 1.2 core schema's.
_Loader.yaml_implicit_resolvers = {}
for _tag, _pattern, _first in (("tag:yaml.org,2002:bool", _BOOL, "tTfF"),
                               ("tag:yaml.org,2002:int", _INT, "-+0123456789"),
                               ("tag:yaml.org,2002:float", _FLOAT, "-+.0123456789"),
                               ("tag:yaml.org,2002:null", _NULL, ["~", "n", "N", ""])):
    _Loader.add_implicit_resolver(_tag, re.compile(rf"^(?:{_pattern.pattern})$"), list(_first))


def _int12(loader: _Loader, node: Any) -> int:
    text = loader.construct_scalar(node)
    if text.startswith("0o"):
        return int(text[2:], 8)
    if text.startswith("0x"):
        return int(text[2:], 16)
    return int(text)                    # decimal, leading zeros allowed (0640 is 640)


def _float12(loader: _Loader, node: Any) -> float:
    text = str(loader.construct_scalar(node)).lower()
    if text.endswith(".inf"):
        return float("-inf") if text.startswith("-") else float("inf")
    if text.endswith(".nan"):
        return float("nan")
    return float(text)


_Loader.add_constructor("tag:yaml.org,2002:int", _int12)
_Loader.add_constructor("tag:yaml.org,2002:float", _float12)


def _count_nodes(node: Any, budget: int, label: str) -> int:
    """Values in the document ``node`` roots, aliases expanded; raises past ``budget``."""
    count, stack = 0, [node]
    while stack:
        n = stack.pop()
        count += 1
        if count > budget:
            raise InputError(f"{label}: holds more than {budget:,} values once its aliases (*name) are "
                             "expanded; write the values out or shorten the file")
        if isinstance(n, yaml.SequenceNode):
            stack.extend(n.value)
        elif isinstance(n, yaml.MappingNode):
            for k, v in n.value:
                stack.append(k)
                stack.append(v)
    return count


def load_yaml_text(text: str, label: str) -> Any:
    """Parse one YAML document (see the module docstring for what is refused)."""
    loader = None
    try:
        loader = _Loader(text, label)       # its reader refuses control characters here already
        node = loader.get_single_node()
        if node is None:
            return None
        _count_nodes(node, MAX_NODES, label)
        return loader.construct_document(node)
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        where = f"line {mark.line + 1}: " if mark is not None else ""
        if isinstance(e, yaml.reader.ReaderError):          # a control character: no mark, a position
            where = f"line {text.count(chr(10), 0, e.position) + 1}: "
        problem = str(getattr(e, "problem", None) or str(e).splitlines()[0])
        problem = clip(problem, 80)
        raise InputError(f"{label}: {where}not valid YAML ({problem})") from None
    except RecursionError:
        raise InputError(f"{label}: nested too deeply") from None
    finally:
        if loader is not None:
            loader.dispose()


def read_yaml(path: str | Path, what: str = "YAML", label: str | None = None, max_bytes: int = MAX_BYTES) -> Any:
    """Read and parse a YAML file: at most :data:`MAX_BYTES`, UTF-8 (a byte-order mark dropped).

    ``label`` names the file in messages about its content (default: the path).

    Raises
    ------
    InputError
        No such file, a directory, too large, not UTF-8 text, or not valid YAML.
    """
    p = Path(path)
    name = str(p) if label is None else label
    try:
        size = p.stat().st_size
    except FileNotFoundError:
        raise InputError(f"{p}: no such file") from None
    except OSError as e:
        raise InputError(f"{p}: cannot read ({e.strerror})") from None
    if p.is_dir():
        raise InputError(f"{name}: is a directory, expected a {what} file")
    if size > max_bytes:
        raise InputError(f"{name}: {size:,} bytes; a {what} file may have at most {max_bytes:,}")
    try:
        data = p.read_bytes()
    except OSError as e:
        raise InputError(f"{p}: cannot read ({e.strerror})") from None
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        raise InputError(f"{name}: not UTF-8 text (byte {e.start}); expected a {what} file") from None
    if "\x00" in text:
        raise InputError(f"{name}: holds NUL bytes; expected a {what} text file")
    return load_yaml_text(text, name)


__all__ = ["MAX_BYTES", "MAX_DEPTH", "MAX_NODES", "clip", "load_yaml_text", "read_yaml", "short"]
