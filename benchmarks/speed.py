"""Where a frame's time goes (decode, foreground, tracking) and how it scales from 1 to 50 people.

Question (issue 5's speed targets): per person, does the ellipsoid tracker cost at most 0.2 of one
MOG2 ``apply`` on a frame of the same size, and does it run at ≥ 30 frames/s with 50 people at
640×480 on one core? How close is each tracker to the limit of any video tracker — decoding the
frame plus one MOG2 apply?

For each size (160×120, 640×480) and crowd size (1, 2, 5, 10, 20, 50 people) the ``crowd``
scenario with one corner camera (seed 0, 40 frames) is written as an MP4 by
``worldtrack.synth.write_sequence`` and decoded back with ``cv2.VideoCapture.read`` (timed per
frame); the trackers run on the *decoded* frames, as they would on a recording. Each method
(default preset, colour foreground against the scenario's background plate; the blobs baseline its
own MOG2) starts the people at their true positions on frame 0 where it can (ellipsoid, particle;
the blobs baseline finds them itself), and births stay on. Medians over the frames after
``WARMUP`` = 10, per frame:

* decode — ``VideoCapture.read``;
* foreground — the method's own per-frame image stage alone, on the same frames: the colour
  difference's labels and the ternary image with its −1 ring (ellipsoid), the shadow-free hit
  image ``F > γ`` (particle; without its restriction to floor pixels), one MOG2 ``apply`` with
  the opening (blobs);
* tracking — ``tracker.step`` minus foreground; step — the whole ``tracker.step``;
* empty — ``tracker.step`` on 40 frames of the empty scene (background plate plus noise): the
  per-frame cost that does not depend on people.

Reported: frames/s of ``step`` and of decode + step; "÷ limit" = (decode + step) / (decode + one
MOG2 apply), both measured in this run (1 = as fast as the cheapest video tracker); per person =
(step(K) − empty) / K, also as a multiple of one MOG2 apply on a frame of that size (target
≤ 0.2 for the ellipsoid). The MOG2 reference is the median of one measurement per crowd size
(``common.mog2_apply_time``), since a single one can coincide with another process's burst. "tracks" is the mean number of tracks reported per frame: at 160×120
people in the 10 × 8 m hall are a few pixels tall, and in a crowd seen by one corner camera many
are hidden, so trackers may hold fewer tracks than people.

Run: ``.venv/bin/python benchmarks/speed.py [--quick]``. Writes ``benchmarks/results/speed.md``.
About 1 minute; 40 frames per run (instead of the scenario's 100) keeps the rendering of the
50-person sequences short. ``--quick`` (a smoke run, prints only): 1 and 10 people, 20 frames.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table, median_time, mog2_apply_time, save_result  # noqa: E402

from worldtrack.foreground.background import AdaptiveBackground  # noqa: E402
from worldtrack.trackers.base import Frame  # noqa: E402
from worldtrack.errors import InputError  # noqa: E402
from worldtrack.io.tracks import read_tracks  # noqa: E402
from worldtrack.experiment import synthetic_threshold  # noqa: E402
from worldtrack.foreground import make_foregrounds  # noqa: E402
from worldtrack.synth import make_scenario, write_sequence  # noqa: E402
from worldtrack.trackers import METHODS, make_tracker, method_shadow_test  # noqa: E402
from worldtrack.trackers.ellipsoid.real import ternary_real  # noqa: E402

SEED = 0
SIZES = ((160, 120), (640, 480))
COUNTS = (1, 2, 5, 10, 20, 50)
FRAMES, WARMUP = 40, 10
FOREGROUND = "colour"


@dataclass
class Clip:
    """Decoded frames of one crowd sequence, and what a tracker needs besides them."""

    size: tuple[int, int]
    people: int
    scene: object
    camera: str
    fps: float
    background: np.ndarray
    frames: list[np.ndarray]
    decode_s: float                   # median seconds per VideoCapture.read
    start: list[tuple[int, float, float]]   # (id, x, y) on frame 0


def decode(path: Path) -> tuple[list[np.ndarray], float]:
    """All frames of a video and the median seconds per ``read``."""
    cap = cv2.VideoCapture(str(path))
    frames, times = [], []
    while True:
        t0 = time.perf_counter()
        ok, img = cap.read()
        if not ok:
            break
        times.append(time.perf_counter() - t0)
        frames.append(img)
    cap.release()
    return frames, statistics.median(times[2:] or times)


def make_clip(size: tuple[int, int], people: int, frames: int, tmp: Path) -> Clip:
    sc = make_scenario("crowd", size=size, frames=frames, seed=SEED, people=people, cameras=1)
    cam = sc.camera_ids[0]
    out = write_sequence(sc, tmp / f"{size[0]}x{size[1]}_{people}", progress=False)
    images, decode_s = decode(out / f"{cam}.mp4")
    gt = read_tracks(out / "gt.csv")
    first = gt.frame == gt.frame.min()
    start = list(zip(gt.id[first].tolist(), gt.x[first].tolist(), gt.y[first].tolist()))
    return Clip(size, people, sc.scene, cam, sc.fps, sc.background(cam), images, decode_s, start)


def empty_clip(clip: Clip, frames: int) -> Clip:
    """The same scene with nobody in it: the background plate plus sensor-like noise."""
    rng = np.random.default_rng(SEED)
    bg = clip.background.astype(np.float32)
    images = [np.clip(bg + rng.normal(0, 1.8, bg.shape), 0, 255).astype(np.uint8) for _ in range(frames)]
    return Clip(clip.size, 0, clip.scene, clip.camera, clip.fps, clip.background, images, clip.decode_s, [])


def step_times(method: str, clip: Clip) -> tuple[float, float, object]:
    """Median seconds per ``tracker.step`` after the warm-up, the mean number of tracks, the tracker."""
    fgs = make_foregrounds(clip.scene, {clip.camera: clip.background}, FOREGROUND,
                           synthetic_threshold(method, FOREGROUND), shadow_test=method_shadow_test(method))
    tracker = make_tracker(method, clip.scene, fgs)
    try:
        for tid, x, y in clip.start:
            tracker.init_track(x, y, track_id=tid)
    except InputError:
        pass  # a tracker that starts its tracks by itself (blobs)
    times, counts = [], []
    for k, img in enumerate(clip.frames):
        t = k / clip.fps
        t0 = time.perf_counter()
        tracks = tracker.step({clip.camera: Frame(img, t, k)}, t)
        times.append(time.perf_counter() - t0)
        counts.append(len(tracks))
    return statistics.median(times[WARMUP:]), float(np.mean(counts[WARMUP:])), tracker


def foreground_stage(method: str, tracker, clip: Clip):
    """``image -> what the method's likelihood reads``, done as its ``step`` does it (public parts)."""
    if method == "ellipsoid":
        cs = tracker.views[clip.camera]
        return lambda img: ternary_real(cs.foreground.labels(img), cs.ring_px)
    if method == "particle":
        # The foreground's labels and the shadows judged, as the particle tracker reads a frame.
        return lambda img: tracker.labels.read({clip.camera: img})
    model = AdaptiveBackground("mog2", background=clip.background)
    return model.labels


def foreground_time(method: str, tracker, clip: Clip) -> float:
    """Median seconds of the method's foreground stage alone, over the clip's frames."""
    stage = foreground_stage(method, tracker, clip)
    it = iter(clip.frames * 2)
    return median_time(lambda: stage(next(it)), repeats=min(30, len(clip.frames)), warmup=2)


def measure_size(size: tuple[int, int], counts, frames: int, tmp: Path) -> tuple[list[list], dict, float]:
    """Rows of the table for one image size; per-person ratios by method; the MOG2 reference (s).

    The MOG2 reference is measured once per crowd size, between the trackers' runs, and the median
    of those is used: one measurement can land on a moment when another process holds the core.
    """
    measured, mog2_refs, empty = [], [], {}
    for people in counts:
        t0 = time.perf_counter()
        clip = make_clip(size, people, frames, tmp)
        print(f"{size[0]}x{size[1]}, {people} people: written and decoded in {time.perf_counter() - t0:.1f} s "
              f"(decode {1000 * clip.decode_s:.2f} ms/frame)", file=sys.stderr)
        if not empty:
            e = empty_clip(clip, frames)
            empty = {m: step_times(m, e)[0] for m in METHODS}   # also compiles / loads the Numba kernels
        mog2_refs.append(mog2_apply_time(*size))
        for method in METHODS:
            step, tracks, tracker = step_times(method, clip)
            measured.append((people, method, tracks, clip.decode_s, foreground_time(method, tracker, clip), step))
    mog2 = statistics.median(mog2_refs)
    rows, per_person = [], {m: [] for m in METHODS}
    for people, method, tracks, decode_s, fg, step in measured:
        person = (step - empty[method]) / people
        per_person[method].append((people, person / mog2))
        rows.append([f"{size[0]}x{size[1]}", method, people, tracks, 1000 * decode_s, 1000 * fg,
                     1000 * max(step - fg, 0.0), 1000 * step, 1000 * empty[method], 1 / step,
                     1 / (decode_s + step), (decode_s + step) / (decode_s + mog2), 1000 * person, person / mog2])
        print(f"  {method:9s} {people:2d} people: step {1000 * step:7.2f} ms ({tracks:.1f} tracks), "
              f"{1 / (decode_s + step):6.1f} frames/s with decode, per person {person / mog2:.3f} MOG2",
              file=sys.stderr)
    print(f"{size[0]}x{size[1]}: MOG2 apply {', '.join(f'{1000 * m:.2f}' for m in mog2_refs)} ms -> median "
          f"{1000 * mog2:.2f} ms", file=sys.stderr)
    return rows, per_person, mog2


HEADERS = ["size", "method", "people", "tracks", "decode ms", "foreground ms", "tracking ms", "step ms",
           "empty step ms", "frames/s (step)", "frames/s (decode + step)", "÷ limit", "per person ms",
           "per person ÷ MOG2"]


def summary(results: dict, rows: list[list]) -> str:
    lines = []
    for size, (per_person, mog2) in results.items():
        for method, values in per_person.items():
            many = [v for k, v in values if k >= 5] or [v for _, v in values]
            target = ", target ≤ 0.2" if method == "ellipsoid" else ""
            lines.append(f"- {size}, {method}: per person {np.median(many):.3f} × MOG2 apply (median over ≥ 5 "
                         f"people; MOG2 apply {1000 * mog2:.3f} ms){target}")
    for r in rows:
        if r[0] == "640x480" and r[2] == max(COUNTS):
            lines.append(f"- 640x480, {r[1]}, {r[2]} people: {r[9]:.1f} frames/s (step), {r[10]:.1f} frames/s "
                         "(decode + step)" + (", target ≥ 30" if r[1] == "ellipsoid" else ""))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="1 and 10 people, 20 frames")
    args = ap.parse_args(argv)
    counts = (1, 10) if args.quick else COUNTS
    frames = 20 if args.quick else FRAMES
    t_start = time.perf_counter()
    rows, results = [], {}
    with tempfile.TemporaryDirectory(prefix="worldtrack_speed_") as tmp:
        for size in SIZES:
            r, per_person, mog2 = measure_size(size, counts, frames, Path(tmp))
            rows += r
            results[f"{size[0]}x{size[1]}"] = (per_person, mog2)
    elapsed = time.perf_counter() - t_start
    table = markdown_table(HEADERS, rows)
    text = (f"`crowd`, one camera, seed {SEED}, {frames} frames written as MP4 and decoded; medians over frames "
            f"{WARMUP}–{frames - 1}; default presets, foreground `{FOREGROUND}` (blobs: MOG2). Limit = decode + one "
            f"MOG2 apply per frame, measured in this run.\n\n{table}\n\n{summary(results, rows)}\n")
    print(text)
    save_result("speed", "Per-frame cost and scaling with people", text, args.quick, elapsed)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
