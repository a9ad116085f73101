"""Head observations in, trajectories out: the files of ``worldtrack smooth`` (seed 002).

``observations.csv``, one row per head seen by one camera at one time::

    t,camera,u,v[,sigma_px][,id][,height][,u_feet,v_feet[,sigma_feet_px]]
    t,camera,left,top,right,bottom[,…]          (a box: its top centre and bottom centre)

``t`` is seconds, ``camera`` a camera id of the scene, ``u, v`` the head's pixel in that camera's
real (distorted) image — the head's top, or the top centre of a person's box — ``sigma_px`` its
standard deviation in pixels (default 2), ``id`` the person (default 1), ``height`` the person's
head height in metres (used for e_v when given). ``u_feet, v_feet`` (optional, both or neither
in a row; empty cells: not seen) is the pixel of the floor point below the head — the bottom centre
of the box — with ``sigma_feet_px`` (default ``sigma_px``); with it the head height is observed. A
box (``left,top,right,bottom`` pixels instead of ``u,v``) gives both — for cameras that see people
upright (a camera looking straight down sees the head beside the feet: give ``u,v,u_feet,v_feet``). Rows are counted as a spreadsheet counts them
(the header is row 1); every row of one person must come in time order.

A worldtrack ``tracks.csv`` from one camera's run is read as observations of that camera: each
row's head point (x, y, height) is projected into it (rows outside its image are left out).

``trajectory.csv`` (what comes out), one row per person per grid step::

    id,t,x,y,z,vx,vy,vz,sigma_x,sigma_y,sigma_z,rho_xy,observed,barrier
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping

import numpy as np

from worldtrack.errors import InputError
from worldtrack.geometry.camera import Camera
from worldtrack.io.text import read_text
from worldtrack.io.tracks import read_tracks

REQUIRED = ("t", "camera", "u", "v")
OPTIONAL = ("sigma_px", "id", "height", "u_feet", "v_feet", "sigma_feet_px")
BOX = ("left", "top", "right", "bottom")
TRAJECTORY_COLUMNS = ("id", "t", "x", "y", "z", "vx", "vy", "vz", "sigma_x", "sigma_y", "sigma_z", "rho_xy",
                      "observed", "barrier")


@dataclass(frozen=True, eq=False)
class ObservationTable:
    """Rows of head observations: time (N,) s, camera (N,) str, uv (N, 2) px, sigma (N,) px,
    id (N,) int, height (N,) m (NaN: not given), row (N,) int — the row in the file — and source;
    feet_uv (N, 2) px and feet_sigma (N,) px (NaN rows: no feet pixel; None: no feet column)."""

    time: np.ndarray
    camera: np.ndarray
    uv: np.ndarray
    sigma: np.ndarray
    id: np.ndarray
    height: np.ndarray
    row: np.ndarray
    source: str = ""
    feet_uv: np.ndarray | None = None
    feet_sigma: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.time)

    def people(self) -> list[int]:
        return sorted(int(i) for i in np.unique(self.id))

    def select(self, keep: np.ndarray) -> "ObservationTable":
        pick = lambda a: None if a is None else a[keep]  # noqa: E731
        return ObservationTable(self.time[keep], self.camera[keep], self.uv[keep], self.sigma[keep], self.id[keep],
                                self.height[keep], self.row[keep], self.source, pick(self.feet_uv),
                                pick(self.feet_sigma))

    def of(self, person_id: int) -> "ObservationTable":
        """One person's rows, in time order (stable: rows at one time keep the file's order)."""
        sel = self.select(self.id == person_id)
        return sel.select(np.argsort(sel.time, kind="stable"))

    @staticmethod
    def concatenate(tables: list["ObservationTable"]) -> "ObservationTable":
        if len(tables) == 1:
            return tables[0]
        cat = lambda name: np.concatenate([getattr(t, name) for t in tables])  # noqa: E731
        feet = feet_sigma = None
        if any(t.feet_uv is not None for t in tables):
            feet = np.concatenate([np.full((len(t), 2), np.nan) if t.feet_uv is None else t.feet_uv for t in tables])
            feet_sigma = np.concatenate([t.sigma if t.feet_sigma is None else t.feet_sigma for t in tables])
        return ObservationTable(cat("time"), cat("camera"), cat("uv"), cat("sigma"), cat("id"), cat("height"),
                                cat("row"), ", ".join(t.source for t in tables), feet, feet_sigma)


def read_observations(path: str | Path, cameras: Mapping[str, Camera], sigma_px: float = 2.0) -> ObservationTable:
    """Read and check ``observations.csv`` against the scene's cameras.

    Raises
    ------
    InputError
        One line naming the file and the first bad row: a missing column, a cell that is not a
        number, an unknown camera, a pixel that is NaN or outside the camera's image, sigma ≤ 0,
        an id below 1, a time earlier than the person's previous row, a feet pixel half given.
    """
    name = str(path)
    records = list(csv.reader(io.StringIO(read_text(path, "a CSV of observations"))))
    lines = [k + 1 for k, rec in enumerate(records) if any(c.strip() for c in rec)]
    if not lines:
        raise InputError(f"{name}: empty file")
    header = [c.strip().lower() for c in records[lines[0] - 1]]
    header = ["t" if h == "time" else h for h in header]
    boxes = all(c in header for c in BOX) and not ("u" in header or "v" in header)
    missing = [c for c in (REQUIRED[:2] + BOX if boxes else REQUIRED) if c not in header]
    if missing:
        raise InputError(f"{name}: missing columns: {', '.join(missing)} (expected t,camera,u,v[,sigma_px][,id]"
                         f"[,height][,u_feet,v_feet], or t,camera,left,top,right,bottom[,…])")
    if ("u_feet" in header) != ("v_feet" in header):
        raise InputError(f"{name}: u_feet and v_feet come together (only {'u_feet' if 'u_feet' in header else 'v_feet'} "
                         f"is given)")
    rows = np.array(lines[1:], dtype=np.int64)
    cells = []
    for line in rows:
        rec = records[line - 1]
        if len(rec) != len(header):
            raise InputError(f"{name}: row {line}: expected {len(header)} fields ({','.join(header)}), got {len(rec)}")
        cells.append([c.strip() for c in rec])
    col = {h: np.array([c[k] for c in cells], dtype=object) for k, h in enumerate(header)}
    n = len(rows)
    t = _numbers(col["t"], "t", rows, name)
    sigma = _numbers(col["sigma_px"], "sigma_px", rows, name) if "sigma_px" in col else np.full(n, float(sigma_px))
    uv, feet = _pixels(col, rows, name, boxes)
    feet_sigma = (_numbers(col["sigma_feet_px"], "sigma_feet_px", rows, name) if "sigma_feet_px" in col
                  else sigma.copy()) if feet is not None else None
    ids = _numbers(col["id"], "id", rows, name) if "id" in col else np.ones(n)
    height = _numbers(col["height"], "height", rows, name, empty_ok=True) if "height" in col else np.full(n, np.nan)
    camera = np.array([str(c) for c in col["camera"]], dtype=object)
    table = ObservationTable(t, camera, uv, sigma, ids.astype(np.int64), height, rows, name, feet, feet_sigma)
    check_observations(table, cameras, ids)
    return table


def _pixels(col: dict, rows: np.ndarray, name: str, boxes: bool) -> tuple[np.ndarray, np.ndarray | None]:
    """The head pixels (N, 2) and the feet pixels (N, 2) or None, from u,v[,u_feet,v_feet] or a box."""
    if boxes:
        left, top, right, bottom = (_numbers(col[c], c, rows, name) for c in BOX)
        centre = (left + right) / 2
        return np.column_stack([centre, top]).reshape(-1, 2), np.column_stack([centre, bottom]).reshape(-1, 2)
    uv = np.column_stack([_numbers(col["u"], "u", rows, name), _numbers(col["v"], "v", rows, name)]).reshape(-1, 2)
    if "u_feet" not in col:
        return uv, None
    feet = np.column_stack([_numbers(col[c], c, rows, name, empty_ok=True) for c in ("u_feet", "v_feet")])
    empty = np.column_stack([col[c] == "" for c in ("u_feet", "v_feet")]).reshape(-1, 2)
    for k in np.flatnonzero(~empty.any(axis=1) & ~np.all(np.isfinite(feet), axis=1))[:1]:
        raise InputError(f"{name}: row {rows[k]}: feet pixel ({feet[k, 0]}, {feet[k, 1]}) is not a finite number; "
                         f"leave both cells empty where the feet are not seen")
    half = np.flatnonzero(empty[:, 0] != empty[:, 1])
    if len(half):
        k = half[0]
        raise InputError(f"{name}: row {rows[k]}: u_feet and v_feet come together (one is empty); leave both empty "
                         f"where the feet are not seen")
    return uv, feet.reshape(-1, 2)


def _numbers(values: np.ndarray, column: str, rows: np.ndarray, name: str, empty_ok: bool = False) -> np.ndarray:
    out = np.empty(len(values))
    for k, text in enumerate(values):
        try:
            out[k] = float(text) if (text or not empty_ok) else np.nan
        except ValueError:
            raise InputError(f"{name}: row {rows[k]}: {column} is not a number ({text!r})") from None
    return out


def check_observations(table: ObservationTable, cameras: Mapping[str, Camera], raw_ids: np.ndarray | None = None) -> None:
    """Raise :class:`InputError` for the first (in file order) row that cannot be used."""
    n = len(table)
    known = np.array([c in cameras for c in table.camera], dtype=bool)
    inside = np.ones(n, dtype=bool)
    for cid, cam in cameras.items():
        sel = np.flatnonzero(table.camera == cid)
        if len(sel):
            inside[sel] = cam.in_image(np.nan_to_num(table.uv[sel], nan=-1e9))
    ids = table.id if raw_ids is None else raw_ids
    finite_uv = np.all(np.isfinite(table.uv), axis=1)
    feet_bad = _bad_feet(table, cameras, known)
    early = _time_goes_back(table)
    checks = [
        (~np.isfinite(table.time), lambda k: f"t is not a finite time in seconds ({table.time[k]})"),
        (~known, lambda k: f"unknown camera {table.camera[k]!r} (cameras: {', '.join(cameras)})"),
        (~finite_uv, lambda k: f"pixel ({table.uv[k, 0]}, {table.uv[k, 1]}) is not a finite number"),
        (known & finite_uv & ~inside, lambda k: f"pixel ({table.uv[k, 0]:.1f}, {table.uv[k, 1]:.1f}) is outside camera "
                                                f"{table.camera[k]}'s {cameras[table.camera[k]].width}x"
                                                f"{cameras[table.camera[k]].height} image"),
        (~(table.sigma > 0) | ~np.isfinite(table.sigma), lambda k: f"sigma_px must be a positive number of pixels, "
                                                                  f"got {table.sigma[k]}"),
        ((ids < 1) | (ids != np.round(ids)), lambda k: f"id must be an integer from 1, got {ids[k]:g}"),
        (~(np.isnan(table.height) | ((table.height > 0.3) & (table.height < 2.6))),
         lambda k: f"height must be a head height in metres (0.3–2.6), got {table.height[k]}"),
        (feet_bad != "", lambda k: feet_bad[k]),
        (early >= 0, lambda k: f"time {table.time[k]:g} s is before the previous row of person {table.id[k]} "
                               f"(row {table.row[early[k]]}, {table.time[early[k]]:g} s); expected rows in time order"),
    ]
    first = None
    for bad, message in checks:
        idx = np.flatnonzero(bad)
        if len(idx) and (first is None or table.row[idx[0]] < table.row[first[0]]):
            first = (idx[0], message)
    if first is not None:
        k, message = first
        raise InputError(f"{table.source}: row {table.row[k]}: {message(k)}")
    if n == 0:
        raise InputError(f"{table.source}: no observations (only a header)")


def _bad_feet(table: ObservationTable, cameras: Mapping[str, Camera], known: np.ndarray) -> np.ndarray:
    """(N,) str: what is wrong with each row's feet pixel ('' where nothing is or there is none)."""
    out = np.full(len(table), "", dtype=object)
    if table.feet_uv is None:
        return out
    feet = table.feet_uv
    given = ~np.all(np.isnan(feet), axis=1)   # empty cells are NaN: not seen
    for k in np.flatnonzero(given & ~np.all(np.isfinite(feet), axis=1)):
        out[k] = f"feet pixel ({feet[k, 0]}, {feet[k, 1]}) is not a finite number (leave both cells empty if unseen)"
    for k in np.flatnonzero(given & ~(table.feet_sigma > 0)):
        out[k] = f"sigma_feet_px must be a positive number of pixels, got {table.feet_sigma[k]}"
    for cid, cam in cameras.items():
        sel = np.flatnonzero((table.camera == cid) & given & known & np.all(np.isfinite(feet), axis=1))
        outside = sel[~cam.in_image(feet[sel])] if len(sel) else sel
        for k in outside:
            out[k] = f"feet pixel ({feet[k, 0]:.1f}, {feet[k, 1]:.1f}) is outside camera {cid}'s {cam.width}x{cam.height} image"
    return out


def _time_goes_back(table: ObservationTable) -> np.ndarray:
    """(N,) index of the person's previous row where a row's time is earlier than it, else −1."""
    out = np.full(len(table), -1, dtype=np.int64)
    order = np.lexsort((np.arange(len(table)), table.id))          # by person, file order kept
    same = table.id[order][1:] == table.id[order][:-1]
    back = same & (table.time[order][1:] < table.time[order][:-1])
    out[order[1:][back]] = order[:-1][back]
    return out


def observations_from_tracks(path: str | Path, camera: Camera, sigma_px: float = 2.0) -> ObservationTable:
    """A worldtrack ``tracks.csv`` of one camera as head observations of that camera.

    Each row's head point (x, y, height) is projected through ``camera``; rows flagged
    ``unmeasurable`` and heads outside the image are left out.
    """
    table = read_tracks(path)
    name = str(path)
    if np.any(np.isnan(table.time)):
        raise InputError(f"{name}: tracks need a time column (seconds) to be smoothed")
    if "height" not in table.extra:
        raise InputError(f"{name}: tracks need a height column (the head height, metres)")
    height = np.asarray(table.extra["height"], dtype=float)
    flags = np.asarray(table.extra.get("flags", np.full(len(table.x), "")), dtype=str)
    ok = np.isfinite(height) & (height > 0.3) & (np.char.find(flags, "unmeasurable") < 0)
    uv = camera.project(np.column_stack([table.x, table.y, np.nan_to_num(height)]))
    ok &= camera.in_image(uv)
    rows = np.arange(len(table.x)) + 2
    out = ObservationTable(table.time, np.full(len(table.x), camera.id, dtype=object), uv,
                           np.full(len(table.x), float(sigma_px)), table.id.astype(np.int64), height, rows, name)
    return out.select(np.flatnonzero(ok))


def write_trajectories(path: str | Path, columns: Mapping[int, Mapping[str, np.ndarray]]) -> Path:
    """Write ``trajectory.csv``: ``columns[id]`` holds the arrays of :data:`TRAJECTORY_COLUMNS` (but id)."""
    path = Path(path)
    with open(path, "w", newline="") as f:
        out = csv.writer(f)
        out.writerow(TRAJECTORY_COLUMNS)
        for pid in sorted(columns):
            c = columns[pid]
            n = len(c["t"])
            table = [np.full(n, pid)] + [c[k] for k in TRAJECTORY_COLUMNS[1:]]
            for row in zip(*table):
                out.writerow([int(row[0]), *(_fmt(x) for x in row[1:-2]), int(row[-2]), int(row[-1])])
    return path


def _fmt(x: float) -> str:
    return f"{x:.6f}".rstrip("0").rstrip(".") if np.isfinite(x) else "nan"


def write_observations(path: str | Path, table: ObservationTable) -> Path:
    """Write an ``observations.csv`` (t,camera,u,v,sigma_px,id[,height][,u_feet,v_feet,sigma_feet_px])."""
    path = Path(path)
    with_height = bool(np.any(np.isfinite(table.height)))
    with_feet = table.feet_uv is not None
    header = ["t", "camera", "u", "v", "sigma_px", "id"] + (["height"] if with_height else [])
    with open(path, "w", newline="") as f:
        out = csv.writer(f)
        out.writerow(header + (["u_feet", "v_feet", "sigma_feet_px"] if with_feet else []))
        for k in range(len(table)):
            row = [_fmt(table.time[k]), table.camera[k], f"{table.uv[k, 0]:.3f}", f"{table.uv[k, 1]:.3f}",
                   _fmt(table.sigma[k]), int(table.id[k])] + ([_fmt(table.height[k])] if with_height else [])
            if with_feet:
                seen = bool(np.all(np.isfinite(table.feet_uv[k])))
                row += ([f"{table.feet_uv[k, 0]:.3f}", f"{table.feet_uv[k, 1]:.3f}", _fmt(table.feet_sigma[k])]
                        if seen else ["", "", ""])
            out.writerow(row)
    return path
