"""Signals at random moments of a real ``worldtrack track`` process, and what it must leave behind.

:func:`long_sequence` makes a folder of frames that takes a few seconds to track (the test
sequence's frames repeated); :func:`signalled_run` starts the command line in a subprocess, sends
SIGINT or SIGTERM after a delay and judges the end: exit status 128 + signal (130 or 143), the
last line ``interrupted``/``terminated``, no traceback, and every output that exists whole:
``tracks.csv`` readable with complete rows, the floor plan drawn if tracking had started, the
annotated video readable with as many frames as ``tracks.csv`` has frames.

Used by ``tests/cli/test_faults.py`` (a few moments) and ``benchmarks/faults.py`` (20 each).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

COMMAND = [sys.executable, "-c", "from worldtrack.entry import run; run()"]     # as the installed `worldtrack`


def long_sequence(sequence: Path, folder: Path, frames: int = 200) -> Path:
    """``folder/cam1`` with ``frames`` frames (the sequence's cam1 frames, repeated by symlinks)."""
    src = sorted((sequence / "cam1").glob("*.png"))
    cam = folder / "cam1"
    cam.mkdir(parents=True, exist_ok=True)
    for k in range(frames):
        link = cam / f"{k:06d}.png"
        if not link.exists():
            link.symlink_to(src[k % len(src)])
    background = folder / "cam1_background.png"
    if not background.exists():
        background.symlink_to(sequence / "cam1_background.png")
    return cam


def moments(seed: int, count: int, signals: tuple[int, ...]) -> list[tuple[float, int, bool]]:
    """``count`` (delay s, signal, while tracking) moments, seeded: half during start-up (0.3-6 s
    after the start: imports, scene, background, kernels), half 0-3 s into tracking."""
    import random

    rng = random.Random(seed)
    out = []
    for k in range(count):
        tracking = k % 2 == 1
        out.append((round(rng.uniform(0.0, 3.0) if tracking else rng.uniform(0.3, 6.0), 3),
                    signals[k % len(signals)], tracking))
    return out


def track_command(sequence: Path, frames_dir: Path, out: Path) -> list[str]:
    return [*COMMAND, "track", str(sequence / "scene.yaml"), "--video", f"cam1={frames_dir}", "--out", str(out),
            "--quiet"]


@dataclass
class Run:
    delay: float                    # seconds after the start, or after tracking began
    signum: int
    code: int | None = None
    stderr: str = ""
    phase: str = ""                 # "starting" (before tracks.csv existed) or "tracking"
    problems: list[str] = field(default_factory=list)

    def describe(self) -> str:
        tail = self.stderr.strip().splitlines()[-3:]
        return (f"{signal.Signals(self.signum).name} after {self.delay:.2f} s ({self.phase}): {', '.join(self.problems)}; "
                f"exit {self.code}; stderr tail {tail}")


def signalled_run(command: list[str], out: Path, delay: float, signum: int, while_tracking: bool = False,
                  timeout: float = 180.0) -> Run:
    """Run ``command``, send ``signum`` ``delay`` seconds after its start (or, ``while_tracking``,
    after ``tracks.csv`` appears: inside the tracking loop and its compiled kernels), and judge
    what it left in ``out``."""
    run = Run(delay, signum)
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=env)
    t0 = time.perf_counter()
    while while_tracking and not (out / "tracks.csv").exists() and proc.poll() is None \
            and time.perf_counter() - t0 < timeout:
        time.sleep(0.02)
    time.sleep(delay)
    run.phase = "tracking" if (out / "tracks.csv").exists() else "starting"
    if proc.poll() is None:
        proc.send_signal(signum)
    try:
        _, run.stderr = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        _, run.stderr = proc.communicate()
        run.problems.append("did not stop")
    run.code = proc.returncode
    _judge(run, out)
    return run


def _judge(run: Run, out: Path) -> None:
    if run.code == 0:
        run.phase = "finished before the signal"
        return
    want = 128 + run.signum
    word = "terminated" if run.signum == signal.SIGTERM else "interrupted"
    if run.code != want:
        run.problems.append(f"exit {run.code}, expected {want}")
    lines = run.stderr.strip().splitlines()
    if not lines or lines[-1] != word:
        run.problems.append(f"last line not {word!r}")
    if "Traceback" in run.stderr or "Error" in run.stderr.replace("error:", ""):
        run.problems.append("traceback or exception text")
    csv_path = out / "tracks.csv"
    if not csv_path.exists():
        return
    from worldtrack.errors import InputError
    from worldtrack.io.tracks import read_tracks
    text = csv_path.read_text()
    if not text.endswith("\n"):
        run.problems.append("tracks.csv ends mid-line")
    try:
        table = read_tracks(csv_path) if text.count("\n") > 1 else None
    except InputError as e:
        run.problems.append(f"tracks.csv unreadable: {e}")
        return
    if not (out / "floorplan.png").exists():
        run.problems.append("no floor plan")
    video = out / "cam1_annotated.mp4"
    if table is not None and len(table):
        import cv2
        cap = cv2.VideoCapture(str(video))
        n = int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) if cap.isOpened() else -1
        cap.release()
        if n < len(table.frames()):
            run.problems.append(f"video has {n} frames, tracks.csv {len(table.frames())}")
