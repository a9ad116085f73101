"""Speed of the particle tracker (seed 004): cost per object per frame, against one MOG2 apply.

A 640×480 camera 3 m up looks over a 10 × 10 m floor with K ellipsoid people (1.7 m) standing on a
grid; the tracker starts one tracking filter on each (no detection filters, so the cost is the
tracking filters'; no track is ended, so K stays K even where people hide each other), and is
stepped over frames in which everybody shifts by a few centimetres.
Measured, with the median over frames after a warm-up:

* the per-frame cost that does not depend on the objects — turning the frame into what the
  likelihood reads (F > γ, with or without shadow removal);
* ms per frame for K = 1, 2, 5, 10, 20 objects, and the per-object cost
  ``(time(K) − time(0)) / K``, as a ratio to one ``cv2.createBackgroundSubtractorMOG2().apply`` on a
  640×480 frame measured in the same run (target ≤ 0.2);
* the likelihood kernel alone for 500 particles × 20 heights, against the NumPy reference.

Configurations: ``paper`` (500 particles, a line column of 20 heights, weights ∝ count) and
``default`` (500 particles, a 3-line column of 22 heights, ratio weights, explaining away, split
and merge checks).

Usage: ``.venv/bin/python benchmarks/particle_speed.py`` — writes ``benchmarks/results/particle_speed.md``.
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table, median_time, mog2_apply_time, write_result  # noqa: E402

from worldtrack.foreground.background import StaticBackground  # noqa: E402
from worldtrack.geometry.quadric import ellipse_mask, ellipsoid_conics, person_ellipsoid  # noqa: E402
from worldtrack.scene import scene_from_dict  # noqa: E402
from worldtrack.trackers.particle import ParticleConfig, ParticleTracker  # noqa: E402
from worldtrack.trackers.particle_likelihood import (CameraLikelihood, column_counts_reference,  # noqa: E402
                                                     hit_image, hit_labels, hit_labels_reference)

W, H = 640, 480
SCENE = {"name": "speed", "cameras": [{"id": "cam", "image_size": [W, H], "position": [0, -2, 3.5],
                                       "look_at": [0, 4, 0.5], "hfov_deg": 80}],
         "floor": {"walkable": [{"outer": [[-5, 0], [5, 0], [5, 10], [-5, 10]]}]},
         "people": {"height": 1.7, "width": 0.45}}
COUNTS = (1, 2, 5, 10, 20)
FRAMES = 25


def people_at(k: int, frame: int) -> np.ndarray:
    """K positions on a grid in view, shifted a little every frame (m)."""
    cols = 5
    i = np.arange(k)
    xy = np.column_stack([-2.4 + 1.2 * (i % cols), 2.0 + 1.0 * (i // cols)])
    return xy + 0.03 * frame * np.array([1.0, 0.5])


def render(cam, bg, xy, rng) -> np.ndarray:
    img = bg.astype(np.float32)
    order = np.argsort(-np.hypot(xy[:, 0] - cam.centre[0], xy[:, 1] - cam.centre[1]))
    for j in order:
        c, r = person_ellipsoid(xy[j:j + 1], 1.7, 0.45)
        img[ellipse_mask(ellipsoid_conics(cam.P, c, r)[0], (H, W))] = (40 + 7 * j % 200, 30, 200 - 5 * j)
    img += rng.normal(0, 2.0, img.shape)
    return np.clip(img, 0, 255).astype(np.uint8)


def step_time(config: ParticleConfig, k: int, scene, bg, frames) -> float:
    """Median seconds per ``step`` with k tracking filters."""
    tracker = ParticleTracker(scene, {"cam": StaticBackground(bg, 30.0, "colour")}, config)
    for x, y in people_at(k, 0):
        tracker.init_track(x, y)
    times = []
    for f, img in enumerate(frames):
        t0 = time.perf_counter()
        tracker.step({"cam": img}, (f + 1) / 10.0)
        times.append(time.perf_counter() - t0)
    if len(tracker.filters) != k:
        print(f"warning: {len(tracker.filters)} of {k} tracks left", file=sys.stderr)
    return statistics.median(times[3:])


def main() -> int:
    cv2.setNumThreads(1)
    scene = scene_from_dict(SCENE)
    cam = scene.cameras["cam"]
    rng = np.random.default_rng(0)
    bg = np.clip(cv2.GaussianBlur(rng.uniform(60, 200, (H, W, 3)).astype(np.float32), (0, 0), 3), 0, 255).astype(np.uint8)
    configs = {"paper": ParticleConfig.paper(births="none", end_after_s=1e9),
               "default": ParticleConfig(births="none", end_after_s=1e9)}
    mog2 = mog2_apply_time(W, H)
    print(f"MOG2 apply {W}x{H}: {1000 * mog2:.2f} ms", file=sys.stderr)

    # Per-frame image preparation.
    img = render(cam, bg, people_at(10, 0), rng)
    fg = StaticBackground(bg, 30.0, "colour")
    prep = {"F = colour distance, F > γ (paper)": median_time(lambda: hit_image(fg.difference(img), 30.0)),
            "shadow-free F > γ (Numba, default)": median_time(lambda: hit_labels(img, bg, 25.0)),
            "shadow-free F > γ (NumPy reference)": median_time(lambda: hit_labels_reference(img, bg, 25.0),
                                                               repeats=5)}
    prep_rows = [[k, 1000 * v, v / mog2] for k, v in prep.items()]

    # Tracking cost against the number of objects.
    rows = []
    per_object = {}
    for name, cfg in configs.items():
        frames_by_k = {}
        base = None
        for k in (0,) + COUNTS:
            frames = [render(cam, bg, people_at(k, f + 1), np.random.default_rng(f)) for f in range(FRAMES)]
            frames_by_k[k] = frames
            t = step_time(cfg, k, scene, bg, frames)
            if k == 0:
                base = t
                continue
            po = (t - base) / k
            per_object.setdefault(name, []).append(po)
            rows.append([name, k, 1000 * t, 1000 * po, po / mog2])
            print(f"{name:8s} K={k:2d}: {1000 * t:7.2f} ms/frame, {1000 * po:.3f} ms/object "
                  f"= {po / mog2:.3f} MOG2", file=sys.stderr)

    # The likelihood kernel alone: 500 particles x 20 heights.
    cl = CameraLikelihood(cam)
    hit = hit_image(fg.difference(render(cam, bg, people_at(1, 0), rng)), 30.0)
    xy = people_at(1, 0) + rng.normal(0, 0.2, (500, 2))
    heights = np.arange(20) * 0.1
    k_line = median_time(lambda: cl.column(hit, xy, heights), repeats=200)
    k_cyl = median_time(lambda: cl.column(hit, xy, np.concatenate([[-0.2, -0.1], heights]), radius=0.1,
                                          n_below=2), repeats=200)
    k_ref = median_time(lambda: column_counts_reference(cam, hit, xy, heights), repeats=20)
    kernel_rows = [["Numba, line column (paper)", 1000 * k_line, k_line / mog2],
                   ["Numba, 3-line column + 2 below the floor (default)", 1000 * k_cyl, k_cyl / mog2],
                   ["NumPy reference, line column", 1000 * k_ref, k_ref / mog2]]

    t1 = markdown_table(["per-frame step", "ms", "× MOG2"], prep_rows)
    t2 = markdown_table(["config", "objects", "ms/frame", "ms/object", "per object × MOG2"], rows)
    t3 = markdown_table(["500 particles × 20 heights", "ms", "× MOG2"], kernel_rows)
    summary = ", ".join(f"{n}: median {np.median(v) / mog2:.3f} × MOG2 per object" for n, v in per_object.items())
    text = (f"One MOG2 apply on {W}x{H}: {1000 * mog2:.2f} ms (the reference). {summary}.\n\n"
            f"Per frame, independent of the objects:\n\n{t1}\n\nTracking (median over {FRAMES - 3} frames; "
            f"per object = (ms/frame(K) − ms/frame(0)) / K):\n\n{t2}\n\nThe column likelihood alone:\n\n{t3}\n")
    print(text)
    path = write_result("particle_speed", "Particle tracker (seed 004): speed",
                        "Command: `.venv/bin/python benchmarks/particle_speed.py`\n\n" + text)
    print(f"wrote {path}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
