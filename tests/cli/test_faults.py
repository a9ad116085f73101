"""Ctrl-C and SIGTERM at random moments of a real ``worldtrack track`` process (see fault_harness):
always exit 130/143 with one line, no traceback, and every output that exists whole — including
when the signal lands inside the compiled tracking kernels. ``benchmarks/faults.py`` does 20 of
each; here a few seeded moments, run three at a time."""

import os
import signal
from concurrent.futures import ThreadPoolExecutor

import pytest

from fault_harness import long_sequence, moments, signalled_run, track_command


@pytest.mark.slow
def test_signals_at_random_moments_end_cleanly_with_outputs_whole(sequence, tmp_path):
    # Every run ends at its signal, so the sequence only has to outlast the latest moment (6 s of
    # start-up + 3 s of tracking) on a fast, warm machine: 400 frames did not always.
    frames = long_sequence(sequence, tmp_path / "frames", 4000)
    plan = moments(38, 4, (signal.SIGINT, signal.SIGINT, signal.SIGTERM, signal.SIGTERM))
    with ThreadPoolExecutor(max_workers=3) as pool:
        runs = list(pool.map(lambda a: signalled_run(track_command(sequence, frames, tmp_path / f"o{a[0]}"),
                                                     tmp_path / f"o{a[0]}", a[1][0], a[1][1], a[1][2]),
                             enumerate(plan)))
    problems = [r.describe() for r in runs if r.problems]
    assert not problems, problems
    stopped = [r for r in runs if r.phase != "finished before the signal"]
    assert len(stopped) == len(runs)                           # the moments fell inside the runs
    assert any(r.phase == "tracking" for r in stopped)         # some inside the tracking loop
    assert {r.code for r in stopped} <= {130, 143}


def _damaged_video(sequence, path, broken_from):
    """cam1's frames as an MP4 whose sample table is broken from frame ``broken_from`` on: FFmpeg
    complains and OpenCV cannot read those frames."""
    import cv2

    frames = sorted((sequence / "cam1").glob("*.png"))
    first = cv2.imread(str(frames[0]))
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), 10, (first.shape[1], first.shape[0]))
    for f in frames:
        writer.write(cv2.imread(str(f)))
    writer.release()
    data = bytearray(path.read_bytes())
    sizes = data.find(b"stsz") + 16                    # after size, tag, version/flags, sample size, count
    for k in range(broken_from, broken_from + 2):
        data[sizes + 4 * k:sizes + 4 * k + 4] = (10_000_000).to_bytes(4, "big")
    path.write_bytes(bytes(data))


@pytest.mark.slow
def test_damaged_video_stops_after_n_bad_frames_with_ffmpeg_quiet_unless_verbose(sequence, tmp_path):
    import subprocess

    from fault_harness import COMMAND

    video = tmp_path / "cam1.mp4"
    _damaged_video(sequence, video, broken_from=12)
    (tmp_path / "cam1_background.png").symlink_to(sequence / "cam1_background.png")
    # An in-process run earlier in the session may have set FFmpeg's log level in os.environ.
    env = {k: v for k, v in os.environ.items() if k != "OPENCV_FFMPEG_LOGLEVEL"}
    results = {}
    for verbose in (False, True):
        out = tmp_path / f"o{verbose}"
        cmd = [*COMMAND, "track", str(sequence / "scene.yaml"), "--video", f"cam1={video}", "--out", str(out),
               "--quiet", "--max-bad-frames", "4", "--no-video", *(["--verbose"] if verbose else [])]
        results[verbose] = subprocess.run(cmd, capture_output=True, text=True, timeout=300, env=env)
    quiet, loud = results[False], results[True]
    assert quiet.returncode == 2 and "Traceback" not in quiet.stderr
    last = quiet.stderr.strip().splitlines()[-1]
    assert last.startswith(f"error: cam1: {video}: 4 frames in a row cannot be decoded") and "outputs up to frame" in last
    assert "@ 0x" not in quiet.stderr                                 # FFmpeg's own lines: only with --verbose
    assert "@ 0x" in loud.stderr and loud.returncode == 2
    written = (tmp_path / "oFalse" / "tracks.csv").read_text().splitlines()
    assert len(written) > 1 and written[0].startswith("frame,time,id")


@pytest.mark.slow
@pytest.mark.skipif(__import__("shutil").which("ffmpeg") is None, reason="ffmpeg is not on PATH (OpenCV writes the video)")
def test_sigkill_leaves_the_annotated_video_playable(sequence, tmp_path):
    import subprocess
    import time

    import cv2

    frames = long_sequence(sequence, tmp_path / "frames", 400)
    out = tmp_path / "o"
    proc = subprocess.Popen(track_command(sequence, frames, out), stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    csv_path, t0 = out / "tracks.csv", time.perf_counter()
    while proc.poll() is None and time.perf_counter() - t0 < 240:
        if csv_path.exists() and len({ln.split(",")[0] for ln in csv_path.read_text().splitlines()[1:]}) >= 15:
            break
        time.sleep(0.05)
    assert proc.poll() is None, "the run ended before it could be killed"
    proc.kill()                                          # SIGKILL: nothing of worldtrack's runs after it
    proc.wait()
    tracked = len({ln.split(",")[0] for ln in csv_path.read_text().splitlines()[1:] if ln.count(",") > 5})

    def readable() -> int:
        cap = cv2.VideoCapture(str(out / "cam1_annotated.mp4"))
        n = 0
        while cap.isOpened() and cap.read()[0]:
            n += 1
        cap.release()
        return n
    counts = [readable()]
    while time.perf_counter() - t0 < 300 and not (counts[-1] > 0 and len(counts) > 1 and counts[-1] == counts[-2]):
        time.sleep(0.5)                                  # FFmpeg finishes the file once its input ends
        counts.append(readable())
    assert counts[-1] >= max(10, tracked - 2), (counts, tracked)
