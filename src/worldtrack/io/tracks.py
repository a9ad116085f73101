"""Track files: what trackers write and what evaluation reads.

Two headered CSV formats that open in a spreadsheet, plus MOTChallenge text for other tools.

``tracks.csv`` (tracker output), one row per person per frame::

    frame,time,id,x,y,height,width,score,mode,flags,vx,vy,speed[,extra…]

``frame`` counts from 0, ``time`` is seconds (to the microsecond), ``id`` is an integer from 1,
``x, y, height, width`` are metres, ``vx, vy, speed`` metres per second, ``mode`` is a word
(``capture``, ``tracking``…) and ``flags`` is a ``;``-separated list of words
(``unmeasurable``), possibly empty. Trackers may append columns (``sigma``, the 1-σ position
uncertainty in metres; ``sx,sy,sz`` box sizes…); readers keep them.

``gt.csv`` (ground truth from the synthetic-world renderer)::

    frame,time,id,x,y,z_head,height,width,speed,vis_<cam>,head_<cam>,feet_<cam>,…

MOTChallenge text (``frame,id,bb_left,bb_top,bb_width,bb_height,conf,x,y,z``, no header,
frames and ids from 1, ``-1`` for unknown) is read when the file has no header and at least ten
numeric columns; ``x, y, z`` (columns 8–10) are world coordinates in metres. Frames become
0-based on reading and 1-based again on writing; ids are 1-based in both.

>>> with TracksWriter("tracks.csv") as out:                         # doctest: +SKIP
...     out.write(0, 0.0, [{"id": 1, "x": 1.2, "y": 0.4, "mode": "capture"}])
>>> table = read_tracks("tracks.csv")                                # doctest: +SKIP
>>> table.xy                                                         # doctest: +SKIP
array([[1.2, 0.4]])
"""

from __future__ import annotations

import csv
import enum
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO

import numpy as np
from numpy.typing import ArrayLike

from worldtrack.errors import InputError

#: Columns of ``tracks.csv``, in order; trackers may append more.
TRACK_COLUMNS: tuple[str, ...] = ("frame", "time", "id", "x", "y", "height", "width", "score",
                                  "mode", "flags", "vx", "vy", "speed")
#: Columns of a MOTChallenge text file (1-based frames and ids, ``-1`` = unknown).
MOT_COLUMNS: tuple[str, ...] = ("frame", "id", "bb_left", "bb_top", "bb_width", "bb_height",
                                "conf", "x", "y", "z")

_CORE = ("frame", "time", "id", "x", "y")


# --------------------------------------------------------------------------------------------
# The table
# --------------------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class TrackTable:
    """Rows of (frame, id) → position, as NumPy columns; one row per person per frame.

    Parameters
    ----------
    frame : (N,) int64
        Frame index from 0.
    time : (N,) float64, seconds
        Time stamp; NaN where the file had none.
    id : (N,) int64
        Track id from 1.
    x, y : (N,) float64, metres
        Position on the floor.
    extra : dict of str → (N,) ndarray
        Every other column, in file order: float64 for numbers, ``str`` arrays for text.
    source : str
        Where the rows came from (a file name), for error messages.
    """

    frame: np.ndarray
    time: np.ndarray
    id: np.ndarray
    x: np.ndarray
    y: np.ndarray
    extra: dict[str, np.ndarray] = field(default_factory=dict)
    source: str = ""

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "frame", np.asarray(self.frame, dtype=np.int64).reshape(-1))
        set_(self, "id", np.asarray(self.id, dtype=np.int64).reshape(-1))
        for name in ("time", "x", "y"):
            set_(self, name, np.asarray(getattr(self, name), dtype=float).reshape(-1))
        extra = {str(k): np.asarray(v).reshape(-1) for k, v in dict(self.extra).items()}
        set_(self, "extra", extra)
        n = self.frame.shape[0]
        for name in (*_CORE, *extra):
            if self.column(name).shape[0] != n:
                raise ValueError(f"TrackTable: column {name!r} has {self.column(name).shape[0]} "
                                 f"rows, frame has {n}")
        clash = set(extra) & set(_CORE)
        if clash:
            raise ValueError(f"TrackTable: extra columns repeat core columns: {sorted(clash)}")

    @classmethod
    def from_arrays(cls, frame: ArrayLike, id: ArrayLike, x: ArrayLike, y: ArrayLike,
                    time: ArrayLike | None = None, extra: Mapping[str, ArrayLike] | None = None,
                    source: str = "") -> "TrackTable":
        """Build a table from columns; ``time`` defaults to NaN."""
        frame = np.asarray(frame)
        if time is None:
            time = np.full(frame.shape, np.nan)
        return cls(frame=frame, time=np.asarray(time), id=np.asarray(id), x=np.asarray(x),
                   y=np.asarray(y), extra={k: np.asarray(v) for k, v in (extra or {}).items()},
                   source=source)

    def __len__(self) -> int:
        return int(self.frame.shape[0])

    @property
    def xy(self) -> np.ndarray:
        """(N, 2) float64, metres: ``x, y`` side by side."""
        return np.column_stack([self.x, self.y])

    @property
    def columns(self) -> list[str]:
        """All column names: ``frame, time, id, x, y`` then the extra columns in file order."""
        return [*_CORE, *self.extra]

    def column(self, name: str) -> np.ndarray:
        """One column by name (core or extra); ``KeyError`` if there is none."""
        if name in _CORE:
            return getattr(self, name)
        return self.extra[name]

    def frames(self) -> np.ndarray:
        """Sorted distinct frame indices."""
        return np.unique(self.frame)

    def ids(self) -> np.ndarray:
        """Sorted distinct track ids."""
        return np.unique(self.id)

    def select(self, rows: ArrayLike) -> "TrackTable":
        """Rows by boolean mask (N,) or integer index, as a new table."""
        rows = np.asarray(rows)
        return TrackTable(frame=self.frame[rows], time=self.time[rows], id=self.id[rows],
                          x=self.x[rows], y=self.y[rows],
                          extra={k: v[rows] for k, v in self.extra.items()}, source=self.source)

    def sorted(self) -> "TrackTable":
        """Rows ordered by frame, then id (stable)."""
        order = np.lexsort((self.id, self.frame))
        return self.select(order)


# --------------------------------------------------------------------------------------------
# Writing
# --------------------------------------------------------------------------------------------

def _fmt_float(v: Any) -> str:
    """Shortest text that reads back to the same float; NaN and None as an empty cell."""
    if v is None:
        return ""
    f = float(v)
    return "" if math.isnan(f) else repr(f)


def _fmt_cell(v: Any) -> str:
    if v is None:
        return ""
    if isinstance(v, enum.Enum):
        v = v.value
    if isinstance(v, str):
        return v
    if isinstance(v, (bool, np.bool_)):
        return str(int(v))
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        return _fmt_float(v)
    if isinstance(v, Iterable):
        return ";".join(_fmt_cell(w) for w in v)
    return str(v)


def _get(track: Any, key: str, default: Any = None) -> Any:
    if isinstance(track, Mapping):
        return track.get(key, default)
    return getattr(track, key, default)


def _open_for_writing(path: str | Path) -> TextIO:
    try:
        return open(path, "w", encoding="utf-8", newline="")
    except OSError as e:
        raise InputError(f"{path}: cannot write: {e.strerror or e}") from None


class TracksWriter:
    """Stream ``tracks.csv`` as a tracker runs; every :meth:`write` is flushed to disk.

    The header is written when the writer is created, so an interrupted run (Ctrl-C, a crash)
    leaves a valid file with every frame written so far.

    Parameters
    ----------
    path : str or Path
        Output file; replaced if it exists.
    extra_columns : sequence of str
        Columns after :data:`TRACK_COLUMNS` (e.g. ``("sx", "sy", "sz")``), read from each track
        by attribute or key; missing values are left empty.

    Examples
    --------
    >>> with TracksWriter("tracks.csv", extra_columns=("sx",)) as out:   # doctest: +SKIP
    ...     for frame, t, tracks in run():
    ...         out.write(frame, t, tracks)
    """

    def __init__(self, path: str | Path, extra_columns: Sequence[str] = ()):
        self.path = Path(path)
        self.extra_columns = tuple(str(c) for c in extra_columns)
        clash = [c for c in self.extra_columns if c in TRACK_COLUMNS]
        if clash or len(set(self.extra_columns)) != len(self.extra_columns):
            raise ValueError(f"TracksWriter: extra_columns must be new, distinct names, got "
                             f"{list(self.extra_columns)}")
        self.columns = TRACK_COLUMNS + self.extra_columns
        self.rows_written = 0
        self._file: TextIO | None = _open_for_writing(self.path)
        self._csv = csv.writer(self._file, lineterminator="\n")
        self._csv.writerow(self.columns)
        self._file.flush()

    def write(self, frame: int, time: float, tracks: Iterable[Any]) -> None:
        """Append one row per track for this frame and flush.

        Parameters
        ----------
        frame : int
            Frame index from 0.
        time : float, seconds (written rounded to the microsecond)
        tracks : iterable of objects or mappings
            Each has ``id`` (int ≥ 1) and ``x, y`` (metres) — or ``xy``/``position`` (2+,) —
            and optionally ``height, width`` (metres), ``score``, ``mode`` (str or Enum),
            ``flags`` (str or iterable of str), ``vx, vy, speed`` (m/s) and the extra columns.
        """
        if self._file is None:
            raise ValueError(f"TracksWriter({self.path}): write after close")
        frame = int(frame)
        if frame < 0:
            raise ValueError(f"TracksWriter: frame must be >= 0, got {frame}")
        rows = []
        for t in tracks:
            tid = int(_get(t, "id"))
            if tid < 1:
                raise ValueError(f"TracksWriter: track ids start at 1, got {tid}")
            x, y = _get(t, "x"), _get(t, "y")
            if x is None or y is None:
                xy = _get(t, "xy")
                if xy is None:
                    xy = _get(t, "position")
                x, y = xy[0], xy[1]
            flags = _get(t, "flags", "")
            row = [str(frame), _fmt_float(round(float(time), 6)), str(tid), _fmt_float(x), _fmt_float(y),
                   _fmt_float(_get(t, "height")), _fmt_float(_get(t, "width")),
                   _fmt_float(_get(t, "score")), _fmt_cell(_get(t, "mode", "")),
                   flags if isinstance(flags, str) else ";".join(map(str, flags)),
                   _fmt_float(_get(t, "vx")), _fmt_float(_get(t, "vy")), _fmt_float(_get(t, "speed"))]
            row += [_fmt_cell(_get(t, c)) for c in self.extra_columns]
            rows.append(row)
        self._csv.writerows(rows)
        self._file.flush()
        self.rows_written += len(rows)

    def close(self) -> None:
        """Close the file; further writes raise."""
        if self._file is not None:
            self._file.close()
            self._file = None

    def __enter__(self) -> "TracksWriter":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def write_tracks(path: str | Path, table: TrackTable) -> None:
    """Write a whole table as a headered CSV: ``frame,time,id,x,y`` then its extra columns.

    A table read from ``tracks.csv`` or ``gt.csv`` is written back with the same columns.
    """
    with _open_for_writing(path) as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(table.columns)
        cols = [table.column(c) for c in table.columns]
        for k in range(len(table)):
            w.writerow([_fmt_cell(c[k]) for c in cols])


def write_mot(path: str | Path, table: TrackTable) -> None:
    """Export MOTChallenge text: ``frame,id,bb_left,bb_top,bb_width,bb_height,conf,x,y,z``.

    Frames are written 1-based (``frame + 1``), ids as they are (already from 1). The box and
    ``z`` come from extra columns of those names when present, else ``-1`` (box) and ``0`` (a
    floor position has z = 0); ``conf`` from an extra ``conf`` or ``score`` column, else 1.
    Rows are ordered by frame, then id.
    """
    t = table.sorted()
    n = len(t)

    def extra(name: str, default: float) -> np.ndarray:
        v = t.extra.get(name)
        if v is None or v.dtype.kind not in "fiub":
            return np.full(n, default)
        return np.where(np.isnan(v.astype(float)), -1.0, v.astype(float))

    conf = extra("conf", np.nan) if "conf" in t.extra else extra("score", 1.0)
    cols = [extra("bb_left", -1.0), extra("bb_top", -1.0), extra("bb_width", -1.0),
            extra("bb_height", -1.0), conf, t.x, t.y, extra("z", 0.0)]
    with _open_for_writing(path) as f:
        for k in range(n):
            f.write(",".join([str(int(t.frame[k]) + 1), str(int(t.id[k]))]
                             + [_fmt_float(c[k]) for c in cols]) + "\n")


class MotWriter:
    """Stream MOTChallenge rows as a tracker runs: ``frame,id,bb_left,bb_top,bb_width,bb_height,conf,x,y,z``.

    Frames are written 1-based, the box in pixels with the MOTChallenge convention of 1-based
    pixel coordinates (``bb_left = u_min + 1``), ``-1`` when the person is not in front of the
    camera; ``x, y, z`` are world metres. Every :meth:`write` is flushed.

    Examples
    --------
    >>> with MotWriter("tracks_mot.txt") as out:                     # doctest: +SKIP
    ...     out.write(0, [(1, (100.0, 50.0, 40.0, 120.0), 0.9, 1.2, 0.4, 0.0)])
    """

    def __init__(self, path: str | Path):
        self.path = Path(path)
        self._file: TextIO | None = _open_for_writing(self.path)

    def write(self, frame: int, rows: Iterable[tuple[int, Sequence[float] | None, float, float, float, float]]) -> None:
        """Append this frame's rows: ``(id, box, conf, x, y, z)`` with ``box = (u_min, v_min, width,
        height)`` in 0-based pixels or None."""
        if self._file is None:
            raise ValueError(f"MotWriter({self.path}): write after close")
        lines = []
        for tid, box, conf, x, y, z in rows:
            b = ["-1"] * 4 if box is None else [_fmt_float(round(box[0] + 1, 2)), _fmt_float(round(box[1] + 1, 2)),
                                                _fmt_float(round(box[2], 2)), _fmt_float(round(box[3], 2))]
            lines.append(",".join([str(int(frame) + 1), str(int(tid)), *b, _fmt_float(round(float(conf), 4)),
                                   _fmt_float(round(x, 4)), _fmt_float(round(y, 4)), _fmt_float(round(z, 4))]))
        self._file.write("".join(line + "\n" for line in lines))
        self._file.flush()

    def close(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None

    def __enter__(self) -> "MotWriter":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


# Reading lives in worldtrack.io.track_reader (imported here, after TrackTable, for the old name).
from worldtrack.io.track_reader import read_tracks  # noqa: E402
