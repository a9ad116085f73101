"""Running a tracker over a source and writing every output: the loop behind ``worldtrack track``.

Outputs (all in one folder): ``tracks.csv`` (flushed every frame), ``<camera>_annotated.mp4`` per
camera, ``floorplan.png`` of every trajectory, and optionally JSON lines on a stream. An
interrupted or failed run keeps everything written so far: the CSV is complete up to the last
frame, the videos are closed properly and the floor plan is drawn from what was tracked.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Mapping

import numpy as np

from worldtrack.errors import InputError
# Kept for callers of the former home of these (until every import moves to worldtrack.foreground / io).
from worldtrack.foreground import FOREGROUND_KINDS as FOREGROUNDS  # noqa: F401
from worldtrack.foreground import SYNTHETIC_COLOUR_THRESHOLD, make_foregrounds  # noqa: F401
from worldtrack.io.sources import background_from_video  # noqa: F401
from worldtrack.scene.model import Scene
from worldtrack.trackers.base import Track, Tracker, warm_started

@dataclass
class RunResult:
    """What a tracking run produced."""

    out_dir: Path
    frames: int = 0
    seconds: float = 0.0
    tracks_csv: Path | None = None
    videos: dict[str, Path] = field(default_factory=dict)
    floorplan: Path | None = None
    interrupted: bool = False
    error: str | None = None
    track_ids: set[int] = field(default_factory=set)

    @property
    def fps(self) -> float:
        return self.frames / self.seconds if self.seconds > 0 else 0.0


def run_tracking(scene: Scene, source, tracker: Tracker, out_dir: str | Path, write_video: bool = True,
                 json_stream: IO[str] | None = None, progress: bool = True, show_ring: bool = False,
                 gt_paths: Mapping[int, np.ndarray] | None = None) -> RunResult:
    """Run ``tracker`` over ``source`` and write the outputs into ``out_dir``.

    Parameters
    ----------
    source : iterable of ``(index, t, {camera_id: Frame})`` (e.g. :class:`VideoSource`)
    tracker : Tracker — stepped over the frames after its warm start
        (:func:`worldtrack.trackers.base.warm_started`)
    json_stream : write one JSON object per frame (``{"frame", "time", "tracks": [...]}``) here
    gt_paths : ground-truth paths to draw dashed on the floor plan

    Returns
    -------
    RunResult
        ``interrupted`` is set on Ctrl-C and ``error`` on bad input met mid-run (e.g. a corrupt
        frame); the caller decides the exit status. Outputs are complete up to the last frame.
    """
    from worldtrack.io.tracks import TracksWriter
    from worldtrack.io.video import VideoWriter
    from worldtrack.viz.floorplan import save_floorplan
    from worldtrack.viz.overlay import draw_tracks

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    result = RunResult(out)
    result.tracks_csv = out / "tracks.csv"
    writer = TracksWriter(result.tracks_csv, extra_columns=tracker.extra_columns)
    videos: dict[str, VideoWriter] = {}
    paths: dict[int, list[tuple[float, float]]] = {}
    fps = getattr(source, "fps", 10.0)
    total = getattr(source, "length", None)
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=total, unit="frame", desc="tracking", leave=False, dynamic_ncols=True, mininterval=0.5)
    t_start = time.perf_counter()
    try:
        for index, t, frames in warm_started(tracker, source):
            tracks = tracker.step(frames, t)
            rows = [_row(tr) for tr in tracks]
            writer.write(index, t, rows)
            for tr in tracks:
                paths.setdefault(tr.id, []).append((tr.x, tr.y))
            if json_stream is not None:
                json_stream.write(json.dumps({"frame": index, "time": round(t, 6), "tracks": rows}) + "\n")
                json_stream.flush()
            if write_video:
                for cid, frame in frames.items():
                    cam = scene.cameras.get(cid)
                    if cam is None:
                        continue
                    shown = tracker.overlay(cid) if show_ring else None
                    img = draw_tracks(frame.image, cam, tracks, ring_px=shown.ring_px if shown else None,
                                      mask=shown.mask if shown else None,
                                      label=f"{cid}  frame {index}  t={t:.1f}s  {len(tracks)} people")
                    if cid not in videos:
                        videos[cid] = VideoWriter(out / f"{cid}_annotated.mp4", fps)
                        result.videos[cid] = videos[cid].path
                    videos[cid].write(img)
            result.frames += 1
            if bar is not None:
                bar.update(1)
                el = time.perf_counter() - t_start
                bar.set_postfix(people=len(tracks), fps=f"{result.frames / el:.1f}" if el > 0 else "-")
    except KeyboardInterrupt:
        result.interrupted = True
    except InputError as e:
        result.error = str(e)
    finally:
        result.seconds = time.perf_counter() - t_start
        if bar is not None:
            bar.close()
        writer.close()
        for v in videos.values():
            v.close()
        result.track_ids = set(paths)
        arr = {k: np.array(v) for k, v in paths.items()}
        result.floorplan = save_floorplan(scene, out / "floorplan.png", paths=arr, reference_paths=gt_paths,
                                          title=f"{scene.name}: {len(arr)} trajectories, {result.frames} frames")
    return result


def _row(tr: Track) -> dict:
    row = {"id": tr.id, "x": round(tr.x, 4), "y": round(tr.y, 4), "height": round(tr.height, 3),
           "width": round(tr.width, 3), "score": round(float(tr.score), 4), "mode": tr.mode,
           "flags": ";".join(sorted(tr.flags)), "sigma": round(float(tr.sigma), 3)}
    row.update({k: (round(float(v), 4) if isinstance(v, float) else v) for k, v in tr.extra.items()})
    return row
