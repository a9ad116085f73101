"""A finished run for the page: ``tracks.csv``, ``run.yaml`` and the scene they name, as one timeline.

The page gets the whole run at once (``/api/run``) and scrubs and plays it by itself: per row
the frame, id, position (m), velocity (m/s, central differences over about half a second of the
same person's rows), σ (m, the tracker's ``sigma`` column, NaN when it has none), height, whether
the tracker marked the person ``unmeasurable``, and the cameras that show them (geometry:
:func:`~worldtrack.serve.plan.cameras_seeing`).

The scene is the one ``run.yaml`` names (``inputs.scene``: as written, else relative to the run's
folder or a folder above it), or ``--scene``; a scene file whose SHA-256 differs from the one the run recorded is used
with a warning.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from worldtrack.errors import InputError
from worldtrack.io.tracks import TrackTable, read_tracks
from worldtrack.scene.model import Scene

#: Frame rate assumed for a ``tracks.csv`` without times and a ``run.yaml`` without ``fps``.
DEFAULT_FPS = 10.0
#: Velocities are central differences over about this long (s).
VELOCITY_WINDOW_S = 0.5


@dataclass
class FinishedRun:
    """A run folder read for the page."""

    folder: Path
    scene: Scene
    scene_path: Path
    table: TrackTable
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def cameras(self) -> list[str]:
        return list(self.scene.cameras)


def _read_info(folder: Path) -> dict[str, Any]:
    path = folder / "run.yaml"
    if not path.is_file():
        return {}
    try:
        info = yaml.safe_load(path.read_text(encoding="utf-8")) or {}
    except (OSError, yaml.YAMLError) as e:
        raise InputError(f"{path}: cannot read ({type(e).__name__})") from None
    if not isinstance(info, dict):
        raise InputError(f"{path}: expected a mapping (the run.yaml that worldtrack track writes)")
    return info


def _scene_path(folder: Path, info: dict[str, Any], scene: str | Path | None) -> Path:
    if scene is not None:
        return Path(scene)
    named = (info.get("inputs") or {}).get("scene")
    # As written (relative to where the run was started: here, or a folder above the run's).
    candidates = [] if not named else [Path(named), *(p / named for p in (folder, *folder.resolve().parents)),
                                       folder / Path(named).name]
    candidates.append(folder / "scene.yaml")
    for c in candidates:
        if c.is_file():
            return c
    if named:
        raise InputError(f"{folder}: cannot find the scene {named} that run.yaml names: give it with --scene")
    raise InputError(f"{folder}: no run.yaml naming a scene and no scene.yaml: give the scene with --scene")


def load_run(folder: str | Path, scene: str | Path | None = None) -> FinishedRun:
    """Read a finished run's folder (``worldtrack track --out FOLDER``).

    Raises :class:`InputError` (one line) for a missing folder, a missing ``tracks.csv``, a scene
    that cannot be found or read.
    """
    from worldtrack.io.runinfo import file_digest
    from worldtrack.scene import load_scene

    folder = Path(folder)
    if not folder.exists():
        raise InputError(f"{folder}: no such folder (give the output folder of a run: worldtrack serve out/)")
    if not folder.is_dir():
        raise InputError(f"{folder}: not a folder (give the output folder of a run: worldtrack serve out/)")
    if not (folder / "tracks.csv").is_file():
        raise InputError(f"{folder}: no tracks.csv in it (is it the output folder of worldtrack track?)")
    info = _read_info(folder)
    path = _scene_path(folder, info, scene)
    recorded = (info.get("inputs") or {}).get("scene_sha256")
    if scene is None and recorded and file_digest(path) != recorded:
        print(f"warning: {path} has changed since the run (its SHA-256 differs from run.yaml's)", file=sys.stderr)
    return FinishedRun(folder, load_scene(path), path, read_tracks(folder / "tracks.csv"), info)


def _times(run: FinishedRun) -> np.ndarray:
    t = run.table.time.copy()
    if np.isnan(t).any():
        fps = (run.info.get("inputs") or {}).get("fps") or DEFAULT_FPS
        t = np.where(np.isnan(t), run.table.frame / float(fps), t)
    return t


def velocities(ids: np.ndarray, t: np.ndarray, xy: np.ndarray, window_s: float = VELOCITY_WINDOW_S) -> np.ndarray:
    """(N, 2) m/s: per row, the central difference of the same id's positions about ``window_s``
    apart (one-sided at a track's ends; 0 for a track of one row). Rows in any order.

    >>> ids = np.array([1, 1, 1, 2]); t = np.array([0.0, 0.5, 1.0, 0.0])
    >>> velocities(ids, t, np.array([[0, 0], [1, 0], [2, 0], [5, 5.0]]), window_s=0.5).tolist()
    [[2.0, 0.0], [2.0, 0.0], [2.0, 0.0], [0.0, 0.0]]
    """
    v = np.zeros_like(xy, dtype=float)
    order = np.lexsort((t, ids))
    sid, st, sxy = ids[order], t[order], xy[order]
    starts = np.flatnonzero(np.r_[True, sid[1:] != sid[:-1]])
    ends = np.r_[starts[1:], len(sid)]
    for a, b in zip(starts, ends):                      # one vectorised pass per person
        tt, pp, n = st[a:b], sxy[a:b], b - a
        if n < 2:
            continue
        i = np.arange(n)
        lo = np.searchsorted(tt, tt - window_s / 2, side="left")
        hi = np.searchsorted(tt, tt + window_s / 2, side="right") - 1
        alone = hi == lo                                # no other row within the window: the neighbours
        lo = np.where(alone, np.maximum(i - 1, 0), lo)
        hi = np.where(alone, np.minimum(i + 1, n - 1), hi)
        dt = tt[hi] - tt[lo]
        with np.errstate(invalid="ignore", divide="ignore"):
            v[order[a:b]] = np.where(dt[:, None] > 0, (pp[hi] - pp[lo]) / dt[:, None], 0.0)
    return v


def all_frames(frame: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every frame number from 0 (or the first, if negative) to the last row's, and its time (s):
    frames where nobody was tracked are on the timeline too (times interpolated, or extrapolated
    at the median frame interval).

    >>> f, t = all_frames(np.array([2, 2, 5]), np.array([0.2, 0.2, 0.5]))
    >>> f.tolist(), np.round(t, 3).tolist()
    ([0, 1, 2, 3, 4, 5], [0.0, 0.1, 0.2, 0.3, 0.4, 0.5])
    """
    if len(frame) == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0)
    known, first = np.unique(frame, return_index=True)
    kt = t[first]
    frames = np.arange(min(0, int(known[0])), int(known[-1]) + 1)
    step = float(np.median(np.diff(kt) / np.diff(known))) if len(known) > 1 else 1.0 / DEFAULT_FPS
    times = np.interp(frames, known, kt)
    times = np.where(frames < known[0], kt[0] + (frames - known[0]) * step, times)
    return frames, times


def _column(table: TrackTable, name: str, default: float) -> np.ndarray:
    if name not in table.extra:
        return np.full(len(table), default)
    try:
        return table.extra[name].astype(float)
    except ValueError:
        return np.full(len(table), default)


def timeline_json(run: FinishedRun) -> dict[str, Any]:
    """The run as columns for the page (see the module docstring).

    Returns
    -------
    dict with ``frames`` (sorted frame numbers), ``times`` (s, one per frame), ``cameras`` (ids),
    and ``rows``: ``frame`` (index into ``frames``), ``id``, ``x``, ``y``, ``vx``, ``vy``, ``sigma``,
    ``height`` (m), ``unmeasurable`` (0/1), ``mode`` (text), ``cams`` (indices into ``cameras``).
    Numbers are rounded to mm; NaN becomes null.
    """
    from worldtrack.serve.plan import cameras_seeing

    table = run.table
    t = _times(run)
    frames, times = all_frames(table.frame, t)
    xy = table.xy
    v = velocities(table.id, t, xy)
    height = _column(table, "height", run.scene.people.height)
    flags = table.extra.get("flags", np.full(len(table), "", dtype=object)).astype(str)
    mode = table.extra.get("mode", np.full(len(table), "", dtype=object)).astype(str)
    unmeasurable = np.char.find(flags, "unmeasurable") >= 0
    cams = run.cameras
    index = {c: k for k, c in enumerate(cams)}
    seen = [[index[c] for c in row] for row in cameras_seeing(run.scene, xy, height)]

    def rounded(a: np.ndarray, digits: int = 3) -> list:
        a = np.round(np.asarray(a, dtype=float), digits)
        return [None if not np.isfinite(x) else float(x) for x in a]

    return {"frames": frames.tolist(), "times": rounded(times, 4), "cameras": cams,
            "rows": {"frame": (table.frame - frames[0]).tolist() if len(frames) else [], "id": table.id.tolist(),
                     "x": rounded(table.x), "y": rounded(table.y), "vx": rounded(v[:, 0]), "vy": rounded(v[:, 1]),
                     "sigma": rounded(_column(table, "sigma", np.nan)), "height": rounded(height, 2),
                     "unmeasurable": unmeasurable.astype(int).tolist(), "mode": mode.tolist(), "cams": seen}}


__all__ = ["DEFAULT_FPS", "FinishedRun", "all_frames", "load_run", "timeline_json", "velocities"]
