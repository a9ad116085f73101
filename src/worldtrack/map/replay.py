"""Replay: rebuild ``tracks.csv``, the floor plan and a plan-view video from the map stream.

``worldtrack replay redis://… --from T --to T --out DIR`` reads the map states between two capture
times (``XRANGE`` over entry ids, which are the buckets' start times in ms) and writes what a run
would have written: one ``tracks.csv`` row per person present in each state, ``floorplan.png``
with every trajectory, and ``plan.mp4`` (the floor plan with the people as they move) when the
scene is given.

Times are Unix seconds, ISO 8601 (``2025-01-31T14:05:00``, local time unless it says otherwise),
or relative to now (``-90s``, ``-15m``, ``-2h``).

>>> parse_time("1700000000.5"), parse_time("-90s", now=1000.0), parse_time("-2m", now=1000.0)
(1700000000.5, 910.0, 880.0)
"""

from __future__ import annotations

import datetime as _dt
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator

import numpy as np

from worldtrack.errors import InputError
from worldtrack.map.connection import MapKeys
from worldtrack.map.messages import MapState, bucket_index, decode_map_state, stream_id_ms

_RELATIVE = re.compile(r"^-(\d+(?:\.\d+)?)([smh])$")


def parse_time(text: str, now: float | None = None) -> float:
    """A time given on the command line, as Unix seconds (see the module docstring)."""
    import time
    text = str(text).strip()
    m = _RELATIVE.match(text)
    if m:
        return (time.time() if now is None else now) - float(m.group(1)) * {"s": 1, "m": 60, "h": 3600}[m.group(2)]
    try:
        return float(text)
    except ValueError:
        pass
    try:
        return _dt.datetime.fromisoformat(text).timestamp()
    except ValueError:
        raise InputError(f"{text!r}: expected a time as Unix seconds, ISO 8601 (2025-01-31T14:05:00) or "
                         f"relative to now (-90s, -15m, -2h)") from None


def read_states(client: Any, keys: MapKeys, t_from: float | None = None, t_to: float | None = None,
                batch: int = 500) -> Iterator[MapState]:
    """The map states with bucket start in ``[t_from, t_to]`` (s), in order; malformed entries are
    skipped."""
    lo = f"{stream_id_ms(t_from)}-0" if t_from is not None else "-"
    hi = f"{stream_id_ms(t_to)}-18446744073709551615" if t_to is not None else "+"
    while True:
        entries = client.xrange(keys.map_stream, min=lo, max=hi, count=batch)
        for _, fields in entries:
            try:
                yield decode_map_state(fields)
            except ValueError:
                continue
        if len(entries) < batch:
            return
        last_ms, last_seq = entries[-1][0].split("-")
        lo = f"{last_ms}-{int(last_seq) + 1}"


@dataclass
class ReplayResult:
    """What a replay wrote."""

    states: int = 0
    rows: int = 0
    tracks_csv: Path | None = None
    floorplan: Path | None = None
    video: Path | None = None
    ids: set[int] = field(default_factory=set)
    first_t: float | None = None
    last_t: float | None = None


def replay(client: Any, keys: MapKeys, out_dir: str | Path, t_from: float | None = None, t_to: float | None = None,
           scene=None, bucket_s: float = 0.1, origin: float | None = None, video: bool = True) -> ReplayResult:
    """Write ``tracks.csv`` (and with ``scene`` the floor plan and plan video) from the map stream.

    Parameters
    ----------
    out_dir : output folder (created)
    t_from, t_to : capture-time range (Unix s), None for the stream's start / end
    scene : Scene, optional — for ``floorplan.png`` and ``plan.mp4``
    bucket_s : the map's bucket length (frame numbers are buckets since ``origin``'s)
    origin : a time (s) in the bucket of frame 0 (``time`` 0) in the CSV (default: the map's epoch
        if it has one, else the first state's time)
    """
    from worldtrack.io.tracks import TracksWriter
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    result = ReplayResult(tracks_csv=out / "tracks.csv")
    if origin is None:
        epoch = client.get(keys.epoch)
        origin = float(epoch) if epoch is not None else None
    paths: dict[int, list[tuple[float, float]]] = {}
    plan = None
    writer = TracksWriter(result.tracks_csv, extra_columns=("support", "workers"))
    try:
        for state in read_states(client, keys, t_from, t_to):
            origin = state.t if origin is None else origin
            frame = bucket_index(state.t, bucket_s) - bucket_index(origin, bucket_s)
            if frame < 0:
                continue
            people = state.present()
            writer.write(frame, round(frame * bucket_s, 6), [p._asdict() for p in people])
            result.rows += len(people)
            result.states += 1
            result.first_t = state.t if result.first_t is None else result.first_t
            result.last_t = state.t
            for p in people:
                paths.setdefault(p.id, []).append((p.x, p.y))
            if scene is not None and video:
                if plan is None:
                    plan = PlanVideo(scene, out / "plan.mp4", fps=1.0 / bucket_s)
                plan.write(people, f"t={state.t - origin:.1f}s  {len(people)} people")
    finally:
        writer.close()
        if plan is not None:
            result.video = plan.close()
    result.ids = set(paths)
    if scene is not None:
        from worldtrack.viz.floorplan import save_floorplan
        result.floorplan = save_floorplan(scene, out / "floorplan.png",
                                          paths={k: np.array(v) for k, v in paths.items()},
                                          title=f"{scene.name}: {len(paths)} people replayed from the map")
    return result


def record_digest(client: Any, keys: MapKeys, buckets: int | None = None) -> str:
    """A digest (hex, 16 digits) of the map record: per bucket its people and merges, as stored, with
    times counted in ms from the first bucket and each lead's worker name (``host:pid:random``) replaced
    by the cameras it published — equal for two batch runs of the same videos that wrote the same
    map. ``buckets``: only the first so many."""
    import hashlib
    import json
    workers: dict[str, list[str]] = {}
    for cam, info in sorted(client.hgetall(keys.cameras).items()):
        workers.setdefault(json.loads(info).get("worker", ""), []).append(cam)
    h, t0 = hashlib.sha256(), None
    for k, state in enumerate(read_states(client, keys)):
        if buckets is not None and k >= buckets:
            break
        t0 = state.t if t0 is None else t0
        ms = lambda t: round((t - t0) * 1000)     # noqa: E731
        people = [p._replace(last_seen=ms(p.last_seen), born=ms(p.born), lead="+".join(workers.get(p.lead, [p.lead])))
                  for p in state.people]
        h.update(f"{ms(state.t)} {people!r} {sorted(state.aliases.items())}\n".encode())
    return h.hexdigest()[:16]


class PlanVideo:
    """A floor-plan video: the scene drawn once (matplotlib), the people drawn on it per state."""

    def __init__(self, scene, path: Path, fps: float):
        import matplotlib.pyplot as plt

        from worldtrack.viz.floorplan import draw_scene
        x0, x1, y0, y1 = scene.walkable.bounds
        w, h = x1 - x0 + 2, y1 - y0 + 2
        scale = 8.0 / max(w, h)
        # Even pixel sizes (video codecs want them).
        fig, ax = plt.subplots(figsize=(max(4.0, round(w * scale, 1)), max(3.0, round(h * scale, 1) + 0.4)), dpi=100)
        draw_scene(ax, scene, show_coverage=True)
        fig.tight_layout()
        fig.canvas.draw()
        self.base = np.ascontiguousarray(np.asarray(fig.canvas.buffer_rgba())[:, :, 2::-1])
        self._to_px = ax.transData.transform
        self._height = self.base.shape[0]
        plt.close(fig)
        from worldtrack.io.video import VideoWriter
        self.writer = VideoWriter(path, fps)
        self.path = path

    def write(self, people, label: str) -> None:
        import cv2
        img = self.base.copy()
        for p in people:
            u, v = self._to_px([p.x, p.y])
            centre = (int(round(u)), int(round(self._height - v)))
            colour = tuple(int(c) for c in np.array(_colour(p.id)) * 255)
            cv2.circle(img, centre, 7, colour, -1, cv2.LINE_AA)
            cv2.putText(img, str(p.id), (centre[0] + 8, centre[1] - 6), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (0, 0, 0), 1,
                        cv2.LINE_AA)
        cv2.putText(img, label, (10, 20), cv2.FONT_HERSHEY_SIMPLEX, 0.55, (0, 0, 0), 1, cv2.LINE_AA)
        self.writer.write(img)

    def close(self) -> Path:
        self.writer.close()
        return self.path


def _colour(pid: int) -> tuple[float, float, float]:
    import matplotlib.pyplot as plt
    r, g, b, _ = plt.get_cmap("tab20")((int(pid) - 1) % 20)
    return b, g, r


__all__ = ["PlanVideo", "ReplayResult", "parse_time", "read_states", "record_digest", "replay"]
