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
from worldtrack.foreground.background import AdaptiveBackground, StaticBackground, estimate_background
from worldtrack.scene.model import Scene
from worldtrack.trackers.base import warm_started

FOREGROUNDS = ("grey", "colour", "mog2", "knn")
#: Difference thresholds for the static foregrounds: grey levels, and RGB distance. 30 suits
#: compressed surveillance video (PETS 2009: MOTA 0.85 at 30, 0.67 at 20); clean cameras and the
#: synthetic world (noise σ ≈ 3) separate people better at 20 — pass ``threshold`` then.
DEFAULT_THRESHOLDS = {"grey": 25.0, "colour": 30.0}
#: The threshold the synthetic world's experiments use (see DEFAULT_THRESHOLDS).
SYNTHETIC_COLOUR_THRESHOLD = 20.0
#: The texture test of shadow-like pixels (:mod:`worldtrack.foreground.texture`) is off by default:
#: it finds dark-clothed people the brightness/chroma test calls shadow on the synthetic wooden
#: floor (10-person crowd, ``benchmarks/crowd_seeds.py``: mean MOTA 0.881 -> 0.898 over seeds 0-9,
#: 0.832 -> 0.860 over seeds 10-19 at NCC <= 0), but on PETS 2009 (real, compressed, sunlit) it
#: cost the ellipsoid tracker 0.04-0.05 MOTA at NCC <= 0, -0.2 and -0.4. Pass
#: ``shadow_texture_ncc`` to :func:`make_foregrounds` to use it.
SHADOW_TEXTURE_NCC: float | None = None


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


def make_foregrounds(scene: Scene, backgrounds: Mapping[str, np.ndarray], kind: str = "colour",
                     threshold: float | None = None, shadows: bool | None = None,
                     shadow_texture_ncc: float | None = SHADOW_TEXTURE_NCC) -> dict:
    """One foreground model per camera from background images.

    Parameters
    ----------
    backgrounds : {camera_id: (H, W, 3) uint8}
    kind : "grey" (the paper), "colour", "mog2" or "knn"
    threshold : grey levels / RGB distance for the static kinds; default :data:`DEFAULT_THRESHOLDS`
    shadows : treat cast shadows as background; default: on except for "grey" (the paper's)
    shadow_texture_ncc : for the static kinds with shadows, tell dark garments from shadows by
        texture (see :class:`StaticBackground`); default off (:data:`SHADOW_TEXTURE_NCC`)
    """
    if kind not in FOREGROUNDS:
        raise InputError(f"--foreground: expected one of {', '.join(FOREGROUNDS)}, got {kind!r}")
    out = {}
    for cid, bg in backgrounds.items():
        cam = scene.camera(cid)
        if (bg.shape[1], bg.shape[0]) != (cam.width, cam.height):
            raise InputError(f"background for {cid}: image is {bg.shape[1]}x{bg.shape[0]} but the camera is "
                             f"{cam.width}x{cam.height}")
        shade = (kind != "grey") if shadows is None else shadows
        if kind in ("grey", "colour"):
            out[cid] = StaticBackground(bg, threshold if threshold is not None else DEFAULT_THRESHOLDS[kind], kind,
                                        shadows=shade, shadow_texture_ncc=shadow_texture_ncc)
        else:
            out[cid] = AdaptiveBackground(kind, background=bg, shadows=shade)
    return out


def background_from_video(path: str | Path, samples: int = 50) -> np.ndarray:
    """Temporal median of ``samples`` frames spread over a video (people must keep moving)."""
    import cv2
    cap = cv2.VideoCapture(str(path))
    if not cap.isOpened():
        raise InputError(f"{path}: cannot open as a video")
    n = int(cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
    frames = []
    if n > 0:
        for idx in np.linspace(0, n - 1, min(samples, n)).astype(int):
            cap.set(cv2.CAP_PROP_POS_FRAMES, int(idx))
            ok, img = cap.read()
            if ok:
                frames.append(img)
    cap.release()
    if not frames:
        raise InputError(f"{path}: no frames could be read to estimate a background")
    return estimate_background(frames)


def run_tracking(scene: Scene, source, tracker, out_dir: str | Path, write_video: bool = True,
                 json_stream: IO[str] | None = None, progress: bool = True, show_ring: bool = False,
                 gt_paths: Mapping[int, np.ndarray] | None = None) -> RunResult:
    """Run ``tracker`` over ``source`` and write the outputs into ``out_dir``.

    Parameters
    ----------
    source : iterable of ``(index, t, {camera_id: Frame})`` (e.g. :class:`VideoSource`)
    tracker : object with ``step(frames, t) -> list[Track]`` (and a warm start on the first frames,
        if it has one: :func:`worldtrack.trackers.base.warm_started`)
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
    extra = getattr(tracker, "extra_columns", ("sigma",))
    writer = TracksWriter(result.tracks_csv, extra_columns=extra)
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
                masks = getattr(tracker, "last_masks", {})
                for cid, frame in frames.items():
                    cam = scene.cameras.get(cid)
                    if cam is None:
                        continue
                    ring = getattr(tracker, "cams", {}).get(cid)
                    img = draw_tracks(frame.image, cam, tracks,
                                      ring_px=(ring.ring_px if (show_ring and ring is not None) else None),
                                      mask=masks.get(cid) if show_ring else None,
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


def _row(tr) -> dict:
    row = {"id": tr.id, "x": round(tr.x, 4), "y": round(tr.y, 4), "height": round(tr.height, 3),
           "width": round(tr.width, 3), "score": round(float(tr.score), 4), "mode": tr.mode,
           "flags": ";".join(sorted(tr.flags)), "sigma": round(float(getattr(tr, "sigma", 0.0)), 3)}
    row.update({k: (round(float(v), 4) if isinstance(v, float) else v) for k, v in tr.extra.items()})
    return row
