"""Running a tracker over a source and writing every output: the loop behind ``worldtrack track``.

Outputs (all in one folder): ``tracks.csv`` (flushed every frame), ``<camera>_annotated.mp4`` per
camera, ``floorplan.png`` of every trajectory, optionally MOTChallenge rows (world x, y, z and
the box the person's ellipsoid projects to in one camera) and JSON lines on a stream. An
interrupted or failed run keeps everything written so far: the CSV is complete up to the last
frame, the videos are closed properly and the floor plan is drawn from what was tracked.

Ctrl-C and SIGTERM during the loop end it after the current frame (:class:`StopRequests`), so a
signal never lands inside a compiled kernel or half-way through a row; a second signal stops at
once. A closed pipe on the JSON stream (``worldtrack track … --json | head``) ends the run the
same way.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any, Callable, Mapping

import numpy as np

from worldtrack.errors import InputError
from worldtrack.interrupts import StopRequests, interrupt_in, signal_of
from worldtrack.scene.model import Scene
from worldtrack.trackers.base import Track, Tracker, warm_started


@dataclass
class RunResult:
    """What a tracking run produced.

    ``interrupted`` is set when a signal (``stop_signal``: SIGINT or SIGTERM) ended the run,
    ``broken_pipe`` when the JSON stream's reader went away, ``error`` on bad input met mid-run
    (e.g. too many undecodable frames in a row).
    """

    out_dir: Path
    frames: int = 0
    last_frame: int = -1
    seconds: float = 0.0
    tracks_csv: Path | None = None
    mot: Path | None = None
    videos: dict[str, Path] = field(default_factory=dict)
    floorplan: Path | None = None
    interrupted: bool = False
    stop_signal: int | None = None
    broken_pipe: bool = False
    error: str | None = None
    track_ids: set[int] = field(default_factory=set)

    @property
    def fps(self) -> float:
        return self.frames / self.seconds if self.seconds > 0 else 0.0


def run_tracking(scene: Scene, source, tracker: Tracker, out_dir: str | Path, write_video: bool = True,
                 json_stream: IO[str] | None = None, progress: bool = True, show_ring: bool = False,
                 gt_paths: Mapping[int, np.ndarray] | None = None, mot_path: str | Path | None = None,
                 mot_camera: str | None = None, area: np.ndarray | None = None) -> RunResult:
    """Run ``tracker`` over ``source`` and write the outputs into ``out_dir``.

    Parameters
    ----------
    source : iterable of ``(index, t, {camera_id: Frame})`` (e.g. :class:`VideoSource`)
    tracker : Tracker — stepped over the frames after its warm start
        (:func:`worldtrack.trackers.base.warm_started`)
    json_stream : write one JSON object per frame (``{"frame", "time", "tracks": [...]}``) here
    gt_paths : ground-truth paths to draw dashed on the floor plan
    mot_path : also write MOTChallenge rows here, with the boxes as seen by ``mot_camera``
        (default: the scene's first camera)
    area : (M, 2) metres — the tracking area, drawn on the floor plan

    Returns
    -------
    RunResult
        The caller decides the exit status. Outputs are complete up to the last frame.
    """
    from worldtrack.viz.floorplan import save_floorplan

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    result = RunResult(out)
    sinks = _Sinks(scene, tracker, out, result, write_video=write_video, json_stream=json_stream,
                   show_ring=show_ring, fps=getattr(source, "fps", 10.0), mot_path=mot_path, mot_camera=mot_camera)
    bar = _progress_bar(getattr(source, "length", None)) if progress else None
    t_start = time.perf_counter()
    try:
        with StopRequests() as stop:
            for index, t, frames in warm_started(tracker, source):
                tracks = tracker.step(frames, t)
                sinks.write(index, t, frames, tracks)
                result.frames += 1
                result.last_frame = index
                if bar is not None:
                    el = time.perf_counter() - t_start
                    bar.update(1)
                    bar.set_postfix(people=len(tracks), fps=f"{result.frames / el:.1f}" if el > 0 else "-")
                if stop.requested:
                    break
        if stop.requested:
            result.interrupted, result.stop_signal = True, stop.signal
    except InputError as e:
        result.error = str(e)
    except BrokenPipeError:
        result.broken_pipe = True
    except BaseException as e:          # a second Ctrl-C, or one inside a compiled kernel
        interrupt = interrupt_in(e)
        if interrupt is None:
            raise
        result.interrupted, result.stop_signal = True, signal_of(interrupt)
    finally:
        result.seconds = time.perf_counter() - t_start
        if bar is not None:
            bar.close()
        sinks.close()
        arr = {k: np.array(v) for k, v in sinks.paths.items()}
        result.track_ids = set(arr)
        result.floorplan = save_floorplan(scene, out / "floorplan.png", paths=arr, reference_paths=gt_paths,
                                          area=area, title=f"{scene.name}: {len(arr)} tracks, {result.frames} frames")
    return result


class _Sinks:
    """Every output of a run, written frame by frame: CSV, JSON lines, MOT rows, videos, paths."""

    def __init__(self, scene: Scene, tracker: Tracker, out: Path, result: RunResult, *, write_video: bool,
                 json_stream: IO[str] | None, show_ring: bool, fps: float, mot_path: str | Path | None,
                 mot_camera: str | None):
        from worldtrack.io.tracks import MotWriter, TracksWriter

        self.scene, self.tracker, self.out, self.result = scene, tracker, out, result
        self.write_video, self.json_stream, self.show_ring, self.fps = write_video, json_stream, show_ring, fps
        result.tracks_csv = out / "tracks.csv"
        self.writer = TracksWriter(result.tracks_csv, extra_columns=tracker.extra_columns)
        self.mot = None
        if mot_path is not None:
            cid = mot_camera or next(iter(scene.cameras))
            self.mot_camera = scene.camera(cid)
            self.mot = MotWriter(mot_path)
            result.mot = self.mot.path
        self.videos: dict[str, Any] = {}
        self.paths: dict[int, list[tuple[float, float]]] = {}

    def write(self, index: int, t: float, frames: Mapping[str, Any], tracks: list[Track]) -> None:
        rows = [track_row(tr) for tr in tracks]
        self.writer.write(index, t, rows)
        for tr in tracks:
            self.paths.setdefault(tr.id, []).append((tr.x, tr.y))
        if self.mot is not None:
            from worldtrack.viz.overlay import projected_box
            self.mot.write(index, [(tr.id, projected_box(self.mot_camera, tr), tr.score, tr.x, tr.y,
                                    float(tr.extra.get("z", 0.0))) for tr in tracks])
        if self.json_stream is not None:
            self.json_stream.write(json.dumps({"frame": index, "time": round(t, 6), "tracks": _json_rows(rows)},
                                              allow_nan=False) + "\n")
            self.json_stream.flush()
        if self.write_video:
            self._draw(index, t, frames, tracks)

    def _draw(self, index: int, t: float, frames: Mapping[str, Any], tracks: list[Track]) -> None:
        from worldtrack.io.video import VideoWriter
        from worldtrack.viz.overlay import draw_tracks

        for cid, frame in frames.items():
            cam = self.scene.cameras.get(cid)
            if cam is None:
                continue
            shown = self.tracker.overlay(cid) if self.show_ring else None
            img = draw_tracks(frame.image, cam, tracks, ring_px=shown.ring_px if shown else None,
                              mask=shown.mask if shown else None,
                              label=f"{cid}  frame {index}  t = {t:.1f} s  {len(tracks)} people")
            if cid not in self.videos:
                self.videos[cid] = VideoWriter(self.out / f"{cid}_annotated.mp4", self.fps)
                self.result.videos[cid] = self.videos[cid].path
            self.videos[cid].write(img)

    def close(self) -> None:
        self.writer.close()
        if self.mot is not None:
            self.mot.close()
        for v in self.videos.values():
            v.close()


def _progress_bar(total: int | None) -> Any:
    from tqdm import tqdm
    return tqdm(total=total, unit="frame", desc="tracking", leave=False, dynamic_ncols=True, mininterval=0.5)


def progress_writer(progress: bool) -> Callable[[str], None]:
    """A function that prints one line to standard error without breaking a progress bar."""
    import sys

    if not progress:
        return lambda line: print(line, file=sys.stderr)
    from tqdm import tqdm
    return lambda line: tqdm.write(line, file=sys.stderr)


def track_row(tr: Track) -> dict:
    """The output row of a track: position, velocity (m/s) and speed, size, score, mode, flags,
    σ and the tracker's extra columns, rounded to what they mean (0.1 mm, 1 mm/s)."""
    row = {"id": tr.id, "x": round(tr.x, 4), "y": round(tr.y, 4), "vx": round(float(tr.vx), 4),
           "vy": round(float(tr.vy), 4), "speed": round(tr.speed, 4), "height": round(tr.height, 3),
           "width": round(tr.width, 3), "score": round(float(tr.score), 4), "mode": tr.mode,
           "flags": ";".join(sorted(tr.flags)), "sigma": round(float(tr.sigma), 4)}
    row.update({k: (round(float(v), 4) if isinstance(v, float) else v) for k, v in tr.extra.items()})
    return row


def _json_rows(rows: list[dict]) -> list[dict]:
    """Rows with every non-finite number as ``null``, so each line is valid JSON."""
    return [{k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in r.items()} for r in rows]


# The former name of :func:`track_row`.
_row = track_row
