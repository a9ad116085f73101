"""Shared helpers for the benchmark scripts: timing, the in-run reference, tables.

Machines here are noisy, so every speed figure is printed beside a reference measured in the same
run: one ``cv2.createBackgroundSubtractorMOG2().apply`` on a frame of the same size (the work any
video tracker must do per frame), and decoding a frame.
"""

from __future__ import annotations

import os
import shlex
import statistics
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Sequence

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
DATA = ROOT.parent / "shared" / "data"

cv2.setNumThreads(1)  # one core, as the targets say


def median_time(fn: Callable[[], object], repeats: int = 20, warmup: int = 2,
                clock: Callable[[], float] = time.perf_counter) -> float:
    """Median wall time (s) of ``fn()`` over ``repeats`` calls after ``warmup`` calls (or of ``clock``,
    e.g. ``time.thread_time`` for the CPU time of this thread on a crowded machine)."""
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(repeats):
        t0 = clock()
        fn()
        times.append(clock() - t0)
    return statistics.median(times)


def mog2_apply_time(width: int, height: int, repeats: int = 30, seed: int = 0,
                    clock: Callable[[], float] = time.perf_counter) -> float:
    """Median time (s) of one MOG2 ``apply`` on a textured ``width × height`` frame with motion."""
    rng = np.random.default_rng(seed)
    base = rng.integers(60, 200, (height, width, 3), dtype=np.uint8)
    model = cv2.createBackgroundSubtractorMOG2()
    for _ in range(20):
        model.apply(base)
    frames = []
    for k in range(repeats + 2):
        f = base.copy()
        x = (k * 7) % max(1, width - 40)
        cv2.rectangle(f, (x, height // 4), (x + width // 12, height // 4 + height // 3), (20, 30, 220), -1)
        frames.append(f)
    it = iter(frames)
    return median_time(lambda: model.apply(next(it)), repeats=repeats, warmup=2, clock=clock)


@dataclass
class ImageView:
    """What trackers read of a rendered view: the image only."""

    image: np.ndarray


@dataclass
class LightBundle:
    """A rendered frame without depth, instance and shadow images (a quarter of the memory);
    accepted by ``worldtrack.experiment.run_scenario(bundles=...)`` like a ``SynthBundle``."""

    frame: int
    time: float
    views: dict
    gt: list


def render_images(scenario) -> list[LightBundle]:
    """Render every frame of a synthetic scenario, keeping images and ground truth only."""
    return [LightBundle(b.frame, b.time, {c: ImageView(v.image) for c, v in b.views.items()}, b.gt)
            for b in scenario.frames()]


def markdown_table(headers: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    """A GitHub-markdown table with numbers formatted compactly."""
    def fmt(v: object) -> str:
        if isinstance(v, float):
            return f"{v:.3g}" if abs(v) < 1000 else f"{v:.0f}"
        return str(v)
    lines = ["| " + " | ".join(headers) + " |", "|" + "---|" * len(headers)]
    lines += ["| " + " | ".join(fmt(v) for v in r) + " |" for r in rows]
    return "\n".join(lines)


def source_version() -> str:
    """The commit the measured code is at, and whether ``src/`` had uncommitted changes (read-only git)."""
    import subprocess

    def git(*args: str) -> str:
        try:
            return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True, timeout=10).stdout.strip()
        except (OSError, subprocess.SubprocessError):
            return ""

    head = git("rev-parse", "--short", "HEAD")
    if not head:
        return "an unknown commit"
    dirty = git("status", "--porcelain", "--", "src")
    return f"commit {head}" + (" with uncommitted changes in src/" if dirty else "")


#: Taken when a script starts, i.e. about when it imports worldtrack (others may commit while it runs).
SOURCE_VERSION = source_version()


def write_result(name: str, title: str, body: str) -> Path:
    """Write ``benchmarks/results/<name>.md`` with a header naming the machine, date and commit."""
    RESULTS.mkdir(parents=True, exist_ok=True)
    path = RESULTS / f"{name}.md"
    stamp = time.strftime("%Y-%m-%d %H:%M")
    path.write_text(f"# {title}\n\nMeasured {stamp} on {os.cpu_count()} cores "
                    f"(Python {sys.version.split()[0]}, OpenCV {cv2.__version__}), one thread, "
                    f"{SOURCE_VERSION}.\n\n{body}\n")
    return path


def setting_value(text: str):
    """A ``--set KEY=VALUE`` value: an int, a float, true/false, or the text."""
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return {"true": True, "false": False}.get(text.lower(), text)


def save_result(name: str, title: str, text: str, quick: bool, seconds: float, script: str | None = None) -> None:
    """Write ``results/<name>.md`` for the script ``benchmarks/<script or name>.py``; ``--quick`` runs only print."""
    if quick:
        print(f"{name}: --quick smoke run in {seconds:.0f} s; results/{name}.md not written", file=sys.stderr)
        return
    args = "".join(f" {shlex.quote(a)}" for a in sys.argv[1:])  # the arguments this run was given
    command = f"`.venv/bin/python benchmarks/{script or name}.py{args}`"
    path = write_result(name, title, f"Command: {command} ({seconds:.0f} s)\n\n{text}")
    print(f"wrote {path} in {seconds:.0f} s", file=sys.stderr)
