"""Reading track files — ``tracks.csv``, ``gt.csv``, MOTChallenge text — into a :class:`TrackTable`.

Two readers give the same table: a column-wise one (pandas' C parser, then NumPy checks) for
plain files, which reads a million rows in seconds, and a cell-by-cell one (the ``csv`` module)
for quoted CSV and to name the first bad cell's line and column when the fast one meets a
problem. Whatever the file holds, the result is a table or one :class:`InputError` line:

* frames are whole numbers from 0 to :data:`MAX_FRAME` and ids from 1 to :data:`MAX_ID` (larger
  ones lose precision as floats and wrap as integers), positions finite metres within
  ±:data:`MAX_COORDINATE_M`;
* ``\\r``, ``\\r\\n`` and ``\\n`` line endings are all read; a file over :data:`MAX_BYTES` is refused.

>>> from worldtrack.io.track_reader import read_tracks_text
>>> read_tracks_text("frame,id,x,y\\r0,1,2.5,3\\r", "t.csv").xy
array([[2.5, 3. ]])
>>> read_tracks_text("frame,id,x,y\\n1e30,1,0,0\\n", "t.csv")
Traceback (most recent call last):
...
worldtrack.errors.InputError: t.csv: line 2, column frame: expected a whole number from 0 to 1000000000, got '1e30'
"""

from __future__ import annotations

import csv
import io
import re
from pathlib import Path

import numpy as np

from worldtrack.errors import InputError
from worldtrack.io.safe_yaml import clip, short
from worldtrack.io.text import is_number
from worldtrack.io.tracks import _CORE, MOT_COLUMNS, TrackTable

#: Largest frame number and track id read.
MAX_FRAME = 1_000_000_000
MAX_ID = 1_000_000_000
#: Positions beyond ± this many metres are refused (their squares overflow long before 1e308).
MAX_COORDINATE_M = 1e6
#: Largest track file read (bytes): about 30 million rows of tracks.csv.
MAX_BYTES = 2_000_000_000

_REQUIRED = ("frame", "id", "x", "y")
# Extra columns that must be numbers (empty cells read as NaN) and ones that are always text.
_FLOAT_COLUMNS = frozenset({"height", "width", "score", "z_head", "speed", "vx", "vy", "sigma", "sx", "sy",
                            "sz", "bb_left", "bb_top", "bb_width", "bb_height", "conf", "z"})
_FLOAT_PREFIXES = ("vis_", "head_", "feet_")
_TEXT_COLUMNS = frozenset({"mode", "flags"})
_SPLIT_MOT = re.compile(r"[,\s]+")
# Files up to this size are re-read cell by cell after an error, to quote the bad cell as written.
_CELLS_UP_TO = 50_000_000
_BLANK_LINES = re.compile(r"^[ \t\f\v]+$", re.MULTILINE)


class _Fallback(Exception):
    """The fast reader met something only the cell-by-cell reader can name precisely."""


def read_tracks(path: str | Path) -> TrackTable:
    """Read ``tracks.csv``, ``gt.csv`` or MOTChallenge text into a :class:`TrackTable`.

    A headered CSV needs at least ``frame, id, x, y``; ``time`` is optional (NaN if absent) and
    every other column is kept in ``extra``. A file without a header whose first line has at
    least ten numbers is read as MOTChallenge (frames made 0-based; world ``x, y`` from columns
    8–9, ``z`` and the box kept as extras).

    Returns
    -------
    TrackTable
        Sorted by frame, then id.

    Raises
    ------
    InputError
        One line naming the file and, where it applies, the line and column: a missing file, an
        empty or too large file, missing columns, a cell that is not a number or out of range, a
        row with the wrong number of fields, or two rows for the same (frame, id).
    """
    name = str(path)
    try:
        if Path(path).stat().st_size > MAX_BYTES:
            raise InputError(f"{name}: larger than {MAX_BYTES:,} bytes; split it by frames")
        with open(path, encoding="utf-8-sig", newline="") as f:
            text = f.read()
    except FileNotFoundError:
        raise InputError(f"{name}: no such file") from None
    except IsADirectoryError:
        raise InputError(f"{name}: is a directory, expected a track file") from None
    except UnicodeDecodeError:
        raise InputError(f"{name}: not a text file (expected UTF-8 CSV)") from None
    except OSError as e:
        raise InputError(f"{name}: cannot read: {e.strerror or e}") from None
    return read_tracks_text(text, name)


def read_tracks_text(text: str, name: str) -> TrackTable:
    """:func:`read_tracks` of a file's text (``name`` for the messages)."""
    if "\x00" in text:
        raise InputError(f"{name}: holds NUL bytes; expected a CSV text file")
    text = _BLANK_LINES.sub("", text.replace("\r\n", "\n").replace("\r", "\n"))
    first = next((line for line in text.split("\n", 50) if line.strip()), None)
    if first is None:
        raise InputError(f"{name}: empty file")
    tokens = [t for t in _SPLIT_MOT.split(first.strip()) if t]
    if all(is_number(t) for t in tokens):
        if len(tokens) < len(MOT_COLUMNS):
            raise InputError(f"{name}: line 1: no header and only {len(tokens)} numeric columns; "
                             f"expected a CSV header (frame,id,x,y,…) or MOTChallenge text with "
                             f"{len(MOT_COLUMNS)} columns")
        return _read_mot(text, name)
    return _read_csv(text, name)


# --------------------------------------------------------------------------------------------
# Headered CSV
# --------------------------------------------------------------------------------------------

def _header(record: list[str], line: int, name: str) -> list[str]:
    header = [c.strip() for c in record]
    if "" in header:
        raise InputError(f"{name}: line {line}: empty column name in header")
    dup = sorted({c for c in header if header.count(c) > 1})
    if dup:
        raise InputError(f"{name}: line {line}: repeated columns: {clip(', '.join(dup))}")
    missing = [c for c in _REQUIRED if c not in header]
    if missing:
        hint = ""
        if len(header) == 1 and any(sep in header[0] for sep in ";\t"):
            hint = " (the header is one column: columns must be separated by commas)"
        raise InputError(f"{name}: missing columns: {', '.join(missing)}{hint}")
    return header


def _read_csv(text: str, name: str) -> TrackTable:
    if '"' not in text:
        try:
            return _read_csv_fast(text, name)
        except _Fallback:
            pass
        except InputError:
            if len(text) > _CELLS_UP_TO:
                raise                       # the fast reader's message (numbers as read, not as written)
    return _read_csv_cells(text, name)


def _line_starts(text: str) -> tuple[np.ndarray, np.ndarray]:
    """Line numbers (from 1) and comma counts of the non-empty lines of ``text`` (``\\n`` endings)."""
    b = np.frombuffer(text.encode("utf-8"), dtype=np.uint8)
    ends = np.flatnonzero(b == 10)
    if b.size and b[-1] != 10:
        ends = np.append(ends, b.size)
    starts = np.concatenate([[0], ends[:-1] + 1])
    commas = np.flatnonzero(b == 44)
    per_line = np.searchsorted(commas, ends) - np.searchsorted(commas, starts)
    filled = ends > starts
    return np.flatnonzero(filled) + 1, per_line[filled]


def _read_csv_fast(text: str, name: str) -> TrackTable:
    """Column-wise reading (pandas' C parser); :class:`_Fallback` on anything it cannot name."""
    import pandas as pd

    lines, commas = _line_starts(text)
    header_line = int(lines[0])
    header = _header(next(csv.reader([text.split("\n", header_line)[header_line - 1]])), header_line, name)
    if np.any(commas[1:] != len(header) - 1):
        raise _Fallback
    numeric = {h for h in header if h in _CORE or h in _FLOAT_COLUMNS or h.startswith(_FLOAT_PREFIXES)}
    dtypes = {h: (np.float64 if h in numeric else object) for h in header}
    try:
        df = pd.read_csv(io.StringIO(text), header=None, names=header, skiprows=header_line, dtype=dtypes,
                         keep_default_na=False, na_values={h: [""] for h in numeric}, skip_blank_lines=True,
                         skipinitialspace=True, engine="c")
    except (ValueError, pd.errors.ParserError):
        raise _Fallback from None
    line_no = lines[1:]
    if len(df) != len(line_no):
        raise _Fallback
    col = {h: df[h].to_numpy() for h in header}
    for h in header:
        if h not in numeric:
            col[h] = np.asarray([str(v).strip() for v in col[h]], dtype=str) if len(df) else np.zeros(0, str)
    return _table(col, header, line_no, name)


def _read_csv_cells(text: str, name: str) -> TrackTable:
    """Cell-by-cell reading with the ``csv`` module: quoted fields, and precise messages."""
    reader = csv.reader(io.StringIO(text))
    header: list[str] | None = None
    cells: list[list[str]] = []
    lines: list[int] = []
    try:
        for record in reader:
            if not any(c.strip() for c in record):
                continue
            if header is None:
                header = _header(record, reader.line_num, name)
                continue
            if len(record) != len(header):
                raise InputError(f"{name}: line {reader.line_num}: expected {len(header)} fields "
                                 f"({clip(','.join(header))}), got {len(record)}")
            cells.append([c.strip() for c in record])
            lines.append(reader.line_num)
    except csv.Error as e:
        raise InputError(f"{name}: line {reader.line_num}: not valid CSV ({e})") from None
    assert header is not None  # the caller saw a non-blank first line
    line_no = np.asarray(lines, dtype=np.int64)
    cols = list(zip(*cells)) if cells else [() for _ in header]
    raw = {h: np.asarray(c, dtype=str) for h, c in zip(header, cols)}
    return _table(raw, header, line_no, name)


def _table(col: dict[str, np.ndarray], header: list[str], line_no: np.ndarray, name: str) -> TrackTable:
    """Check and convert the columns (strings or floats) into a sorted table."""
    frame = _integers(col["frame"], "frame", line_no, name, minimum=0, maximum=MAX_FRAME)
    ids = _integers(col["id"], "id", line_no, name, minimum=1, maximum=MAX_ID)
    x = _floats(col["x"], "x", line_no, name, allow_empty=False, limit=MAX_COORDINATE_M)
    y = _floats(col["y"], "y", line_no, name, allow_empty=False, limit=MAX_COORDINATE_M)
    if "time" in col:
        time = _floats(col["time"], "time", line_no, name, allow_empty=True, finite=False)
    else:
        time = np.full(len(line_no), np.nan)
    extra: dict[str, np.ndarray] = {}
    for h in header:
        if h in _CORE:
            continue
        if h in _TEXT_COLUMNS:
            extra[h] = col[h]
        elif h in _FLOAT_COLUMNS or h.startswith(_FLOAT_PREFIXES):
            extra[h] = _floats(col[h], h, line_no, name, allow_empty=True, finite=False)
        else:
            extra[h] = _guess(col[h])
    return _finish(TrackTable(frame=frame, time=time, id=ids, x=x, y=y, extra=extra, source=name), line_no)


# --------------------------------------------------------------------------------------------
# MOTChallenge text
# --------------------------------------------------------------------------------------------

def _read_mot(text: str, name: str) -> TrackTable:
    rows: list[list[str]] = []
    lines: list[int] = []
    width = None
    for i, line in enumerate(text.split("\n"), start=1):
        if not line.strip():
            continue
        tokens = [t for t in _SPLIT_MOT.split(line.strip()) if t]
        if width is None:
            width = len(tokens)
        elif len(tokens) != width:
            raise InputError(f"{name}: line {i}: expected {width} fields (MOTChallenge), got {len(tokens)}")
        rows.append(tokens)
        lines.append(i)
    assert width is not None
    line_no = np.asarray(lines, dtype=np.int64)
    names = list(MOT_COLUMNS) + [f"col_{k + 1}" for k in range(len(MOT_COLUMNS), width)]
    raw = np.asarray(rows, dtype=str)
    col = {n: raw[:, k] for k, n in enumerate(names)}

    frame = _integers(col["frame"], "frame", line_no, name, minimum=1, maximum=MAX_FRAME + 1) - 1
    ids = _integers(col["id"], "id", line_no, name, minimum=1, maximum=MAX_ID)
    x = _floats(col["x"], "x", line_no, name, allow_empty=False, limit=MAX_COORDINATE_M)
    y = _floats(col["y"], "y", line_no, name, allow_empty=False, limit=MAX_COORDINATE_M)
    extra = {n: _floats(col[n], n, line_no, name, allow_empty=False, finite=False)
             for n in names if n not in ("frame", "id", "x", "y")}
    if np.all(x == -1) and np.all(y == -1) and np.all(extra["z"] == -1):
        raise InputError(f"{name}: MOTChallenge file without world coordinates (columns 8-10, "
                         f"x,y,z, are all -1); worldtrack evaluates positions in metres")
    return _finish(TrackTable(frame=frame, time=np.full(len(rows), np.nan), id=ids, x=x, y=y,
                              extra=extra, source=name), line_no)


# --------------------------------------------------------------------------------------------
# Cells
# --------------------------------------------------------------------------------------------

def _finish(table: TrackTable, line_no: np.ndarray) -> TrackTable:
    """Sort by (frame, id) and reject duplicate rows, naming both lines."""
    order = np.lexsort((table.id, table.frame))
    table = table.select(order)
    line_no = line_no[order]
    same = (np.diff(table.frame) == 0) & (np.diff(table.id) == 0)
    if np.any(same):
        k = int(np.flatnonzero(same)[0])
        a, b = sorted((int(line_no[k]), int(line_no[k + 1])))
        raise InputError(f"{table.source}: line {b}: duplicate row for frame {table.frame[k]}, "
                         f"id {table.id[k]} (first at line {a})")
    return table


def _floats(values: np.ndarray, column: str, line_no: np.ndarray, name: str, *,
            allow_empty: bool, finite: bool = True, limit: float | None = None) -> np.ndarray:
    """A column of strings (or floats, empty = NaN) as float64; the first bad cell raises with its line.

    A cell is bad when it is not a number (or empty, unless ``allow_empty``), not finite (with
    ``finite``), or beyond ± ``limit``."""
    reason = np.zeros(values.shape, dtype=np.int8)          # 0 fine, 1 not a number, 2 not finite, 3 too large
    if values.dtype.kind == "f":
        out = values.astype(np.float64)
        if not allow_empty:
            reason[np.isnan(out)] = 1
    else:
        vals = np.where(values == "", "nan", values) if allow_empty else values
        try:
            out = vals.astype(float) if vals.size else np.zeros(0)
        except (ValueError, OverflowError):
            number = np.array([is_number(v) for v in vals], dtype=bool)
            reason[~number] = 1
            out = np.array([float(v) if ok else np.nan for v, ok in zip(vals, number)], dtype=float)
    with np.errstate(invalid="ignore"):
        if finite:
            reason[(reason == 0) & ~np.isfinite(out)] = 2
        if limit is not None:
            reason[(reason == 0) & (np.abs(out) > limit)] = 3
    if np.any(reason):
        k = int(np.flatnonzero(reason)[0])
        what = ("a number", "a finite number", f"metres within ±{limit or 0:g}")[int(reason[k]) - 1]
        raise InputError(f"{name}: line {line_no[k]}, column {column}: expected {what}, got {_cell(values[k])}")
    return out


def _cell(value: object) -> str:
    """A cell as quoted in messages: its text, or the number read; an empty cell as ''."""
    if isinstance(value, (float, np.floating)):
        return "''" if np.isnan(value) else short(repr(float(value)))
    return short(str(value))


def _integers(values: np.ndarray, column: str, line_no: np.ndarray, name: str, *,
              minimum: int, maximum: int) -> np.ndarray:
    out = _floats(values, column, line_no, name, allow_empty=False)
    bad = (out != np.round(out)) | (out < minimum) | (out > maximum)
    if np.any(bad):
        k = int(np.flatnonzero(bad)[0])
        raise InputError(f"{name}: line {line_no[k]}, column {column}: expected a whole number from "
                         f"{minimum} to {maximum}, got {_cell(values[k])}")
    return out.astype(np.int64)


def _guess(values: np.ndarray) -> np.ndarray:
    """An unknown extra column: float64 if every non-empty cell is a number, else text."""
    filled = values != ""
    if not np.any(filled):
        return values
    try:
        return np.where(filled, values, "nan").astype(float)
    except ValueError:
        return values


__all__ = ["MAX_BYTES", "MAX_COORDINATE_M", "MAX_FRAME", "MAX_ID", "read_tracks", "read_tracks_text"]
