"""Generated track files (``tracks.csv`` as worldtrack writes it, ``gt.csv``, MOTChallenge text).

Each case is evaluated against itself (``worldtrack eval FILE FILE --json``). Valid mutations
(``\\r`` or ``\\r\\n`` line endings, a byte-order mark, blank lines, spaces, quoted cells, columns
in another order, unknown columns) must read to the same table as the file they came from;
invalid ones (frames of 1e30 or 2⁶³, ids of 0 or 1e19, positions of ±1e308, NaN or text where a
number belongs, missing columns, wrong field counts, duplicate rows, NUL or non-UTF-8 bytes, more
people in a frame than can be evaluated) must be refused.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Callable

import numpy as np

from fuzz_runner import Case

HEADER = ["frame", "time", "id", "x", "y", "height", "width", "score", "mode", "flags", "vx", "vy", "speed", "sigma"]


def base_rows(rng: np.random.Generator) -> list[list[str]]:
    """Rows of a tracks.csv: 5-60 frames, 1-6 people, positions in metres."""
    rows = []
    people = int(rng.integers(1, 7))
    start = rng.uniform(-5, 5, (people, 2))
    for f in range(int(rng.integers(5, 61))):
        for i in range(people):
            if rng.random() < 0.1:
                continue
            x, y = start[i] + 0.05 * f
            rows.append([str(f), repr(round(f / 7.0, 6)), str(i + 1), f"{x:.4f}", f"{y:.4f}", "1.7", "0.4",
                         f"{rng.uniform(0.5, 1):.4f}", "tracking", "", "0.35", "0.35", "0.495", "0.1"])
    return rows


def csv_text(header: list[str], rows: list[list[str]], end: str = "\n") -> str:
    return end.join([",".join(header), *(",".join(r) for r in rows)]) + end


def _cell(column: str, value: str) -> Callable[[list[list[str]], np.random.Generator], str]:
    def mutate(rows: list[list[str]], rng: np.random.Generator) -> str:
        rows[int(rng.integers(len(rows)))][HEADER.index(column)] = value
        return csv_text(HEADER, rows)
    return mutate


def _drop_column(column: str) -> Callable:
    def mutate(rows: list[list[str]], rng: np.random.Generator) -> str:
        k = HEADER.index(column)
        return csv_text(HEADER[:k] + HEADER[k + 1:], [r[:k] + r[k + 1:] for r in rows])
    return mutate


def _fields(delta: int) -> Callable:
    def mutate(rows: list[list[str]], rng: np.random.Generator) -> str:
        r = rows[int(rng.integers(len(rows)))]
        if delta > 0:
            r.append("1")
        else:
            r.pop()
        return csv_text(HEADER, rows)
    return mutate


def _duplicate(rows: list[list[str]], rng: np.random.Generator) -> str:
    return csv_text(HEADER, rows + [list(rows[int(rng.integers(len(rows)))])])


def _crowded_frame(rows: list[list[str]], rng: np.random.Generator) -> str:
    extra = [["0", "0.0", str(i), f"{i * 0.001:.4f}", "0.0", "1.7", "0.4", "1", "tracking", "", "0", "0", "0", "0.1"]
             for i in range(100, 2200)]
    return csv_text(HEADER, [r for r in rows if r[0] != "0"] + extra)


def _reorder(rows: list[list[str]], rng: np.random.Generator) -> str:
    order = rng.permutation(len(HEADER))
    return csv_text([HEADER[k] for k in order], [[r[k] for k in order] for r in rows])


def _quoted(rows: list[list[str]], rng: np.random.Generator) -> str:
    return csv_text([f'"{h}"' for h in HEADER], [[f'"{c}"' for c in r] for r in rows])


def _spaces(rows: list[list[str]], rng: np.random.Generator) -> str:
    return csv_text(HEADER, [[f" {c} " if c else c for c in r] for r in rows])


def _blank_lines(rows: list[list[str]], rng: np.random.Generator) -> str:
    return csv_text(HEADER, rows).replace("\n", "\n\n  \n", 3)


def _mot(rows: list[list[str]], rng: np.random.Generator) -> str:
    return "".join(f"{int(r[0]) + 1},{r[2]},-1,-1,-1,-1,1,{r[3]},{r[4]},0\n" for r in rows)


def _truncate(rows: list[list[str]], rng: np.random.Generator) -> str:
    text = csv_text(HEADER, rows)
    return text[: int(rng.integers(len(text)))]


def _flips(rows: list[list[str]], rng: np.random.Generator) -> str:
    data = bytearray(csv_text(HEADER, rows).encode())
    for k in rng.integers(len(data), size=int(rng.integers(1, 6))):
        data[k] = int(rng.choice(list(b"0123456789.,-e\n\r\"x ")))
    return data.decode("latin-1")


VALID: dict[str, Callable] = {
    "as-is": lambda rows, rng: csv_text(HEADER, rows),
    "cr-line-endings": lambda rows, rng: csv_text(HEADER, rows, "\r"),
    "crlf-line-endings": lambda rows, rng: csv_text(HEADER, rows, "\r\n"),
    "byte-order-mark": lambda rows, rng: "\ufeff" + csv_text(HEADER, rows),
    "blank-lines": _blank_lines, "spaces-around-cells": _spaces, "quoted-cells": _quoted,
    "columns-reordered": _reorder, "mot-text": _mot,
    "unknown-column": lambda rows, rng: csv_text(HEADER + ["note"], [r + ["hello"] for r in rows]),
}
INVALID: dict[str, Callable] = {
    "frame-1e30": _cell("frame", "1e30"), "frame-2^63": _cell("frame", str(2 ** 63)), "frame-negative": _cell("frame", "-1"),
    "frame-fraction": _cell("frame", "2.5"), "id-zero": _cell("id", "0"), "id-1e19": _cell("id", "1e19"),
    "x-1e308": _cell("x", "1e308"), "y--1e308": _cell("y", "-1e308"), "x-nan": _cell("x", "nan"),
    "x-inf": _cell("x", "inf"), "x-text": _cell("x", "abc"), "x-empty": _cell("x", ""),
    "score-text": _cell("score", "high"),
    "missing-x": _drop_column("x"), "missing-frame": _drop_column("frame"),
    "extra-field": _fields(+1), "missing-field": _fields(-1), "duplicate-row": _duplicate,
    "nul-byte": lambda rows, rng: csv_text(HEADER, rows).replace("\n", "\x00\n", 1),
    "semicolons": lambda rows, rng: csv_text(HEADER, rows).replace(",", ";"),
    "2100-people-in-a-frame": _crowded_frame,
    "empty": lambda rows, rng: "",
}
EITHER: dict[str, Callable] = {"truncate": _truncate, "character-flips": _flips}


def _same_table(base: str) -> Callable[[Path], str | None]:
    def check(path: Path, outcome=None) -> str | None:
        from worldtrack.io.track_reader import read_tracks_text
        from worldtrack.io.tracks import read_tracks

        a, b = read_tracks_text(base, "base"), read_tracks(path)
        if not (np.array_equal(a.frame, b.frame) and np.array_equal(a.id, b.id)
                and np.allclose(a.xy, b.xy, atol=1e-9)):
            return "rows differ from the file it came from"
        return None
    return check


def tracks_case(mutation: str, seed: int, inserted: bytes = b"") -> Case:
    """The track-file case ``mutation`` of the tracks made from ``seed``."""
    rng = np.random.default_rng(seed)
    rows = base_rows(rng)
    base = csv_text(HEADER, rows)
    check = None
    for kind, table in (("valid", VALID), ("invalid", INVALID), ("either", EITHER)):
        if mutation in table:
            text = table[mutation]([list(r) for r in rows], rng)
            data = text.encode("utf-8") if kind != "either" else text.encode("latin-1", "replace")
            check = _same_table(base) if kind == "valid" else None
            break
    else:
        kind, data = "either", base.encode()
        k = int(rng.integers(len(data) + 1))
        data = data[:k] + inserted + data[k:]
    return Case("tracks", mutation, kind, data, lambda p: ["eval", str(p), str(p), "--json"], check, suffix=".csv")


def mota_of(stdout: str) -> float | None:
    """MOTA from ``eval --json`` output."""
    try:
        return json.loads(stdout.strip().splitlines()[-1])["mota"]
    except (ValueError, IndexError, KeyError):
        return None


MUTATIONS = [*VALID, *INVALID, *EITHER, "inserted-bytes"]
