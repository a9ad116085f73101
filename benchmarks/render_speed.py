"""How fast does the synthetic world render? One 640×480 camera, 1, 10 and 50 people.

Question: can tests, the demo and the papers' experiments make their sequences on the fly? The
issue's target is "a 640×480 frame with 10 people well under 0.1 s on one core".

For each crowd size the ``crowd`` scenario (one corner camera of the 10 × 8 m hall) renders 25
frames; the first 3 (JIT compilation, static-scene cache) are dropped and the median per-frame
time is reported — everything a frame costs: posing the bodies, ray casting people, shadows,
shading, white balance, blur, noise and the ground truth. The people ray casting alone (the Numba
kernel) is timed separately on the same frames. The reference, measured in the same run, is one
``cv2.GaussianBlur`` (5×5) and one MOG2 ``apply`` on a 640×480 frame.

Run: ``.venv/bin/python benchmarks/render_speed.py`` (writes benchmarks/results/render_speed.md).
"""

from __future__ import annotations

import statistics
import time

import cv2
import numpy as np

from common import markdown_table, median_time, mog2_apply_time, write_result
from worldtrack.synth import make_scenario
from worldtrack.synth.people_pass import people_pass

W, H = 640, 480
FRAMES, WARMUP = 25, 3


def frame_times(people: int) -> tuple[float, float, float]:
    """Median seconds per frame: whole frame (wall clock and CPU), and the people ray casting alone."""
    sc = make_scenario("crowd", people=people, cameras=1, size=(W, H), frames=FRAMES, seed=0)
    cam = sc.scene.cameras["c1"]
    times, cpu = [], []
    it = sc.frames()
    for _ in range(FRAMES):
        t0, c0 = time.perf_counter(), time.process_time()
        next(it)
        times.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    r = sc._renderer
    static = r.static_layer(cam).depth
    rays = r.rays(cam)
    kernel = []
    for k in range(WARMUP, FRAMES):
        present, parts = sc.pose_people(k)
        ids = np.array([p.id for p in present])
        t0 = time.perf_counter()
        people_pass(cam, rays, parts, len(ids), ids, static)
        kernel.append(time.perf_counter() - t0)
    return statistics.median(times[WARMUP:]), statistics.median(cpu[WARMUP:]), statistics.median(kernel)


def main() -> None:
    frame = np.random.default_rng(0).integers(0, 255, (H, W, 3), dtype=np.uint8)
    blur = median_time(lambda: cv2.GaussianBlur(frame, (5, 5), 0), repeats=50)
    mog2 = mog2_apply_time(W, H)
    rows = []
    for n in (1, 10, 50):
        total, cpu, kernel = frame_times(n)
        rows.append([n, total * 1000, cpu * 1000, kernel * 1000, total / blur, total / mog2])
        print(f"{n:3d} people: {total * 1000:6.1f} ms/frame wall, {cpu * 1000:6.1f} ms CPU (people ray casting "
              f"{kernel * 1000:5.1f} ms), {total / blur:6.1f}× GaussianBlur, {total / mog2:5.2f}× MOG2.apply")
    table = markdown_table(["people", "ms / frame (wall)", "ms / frame (CPU)", "people ray casting ms",
                            "× GaussianBlur 5×5", "× MOG2 apply"], rows)
    body = (f"One 640×480 camera of the `crowd` scenario, median over {FRAMES - WARMUP} frames after "
            f"{WARMUP} warm-up frames; the whole frame (posing, ray casting, shadows, shading, white "
            "balance, blur, noise, ground truth). Wall-clock time depends on what else the machine runs; "
            "the CPU time of this process less so. Ratios use wall-clock time against references measured "
            "the same way.\n\n"
            f"{table}\n\nReference in the same run: `cv2.GaussianBlur` 5×5 on a 640×480 BGR frame "
            f"{blur * 1000:.2f} ms; MOG2 `apply` {mog2 * 1000:.2f} ms.")
    path = write_result("render_speed", "Synthetic rendering speed", body)
    print(table)
    print(f"GaussianBlur {blur * 1000:.2f} ms, MOG2 {mog2 * 1000:.2f} ms — written to {path}")


if __name__ == "__main__":
    main()
