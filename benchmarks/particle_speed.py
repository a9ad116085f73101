"""Speed of the particle tracker (seed 004): cost per object per frame, against one MOG2 apply.

A 640×480 camera 3 m up looks over a 10 × 10 m floor with K ellipsoid people (1.7 m) standing on a
grid; the tracker starts one tracking filter on each (no detection filters, so the cost is the
tracking filters'; no track is ended, so K stays K even where people hide each other), and is
stepped over frames in which everybody shifts by a few centimetres.
Measured, with the median over frames after a warm-up:

* the per-frame cost that does not depend on the objects — turning the frame into what the
  likelihood reads (F > γ, with or without shadow removal, the latter on the floor pixels as the
  tracker does);
* ms per frame for K = 1, 2, 5, 10, 20 objects, and the per-object cost
  ``(time(K) − time(0)) / K``, as a ratio to one ``cv2.createBackgroundSubtractorMOG2().apply`` on a
  640×480 frame measured in the same run (target ≤ 0.2);
* the likelihood alone for one tracking filter of 500 particles (``ParticleTracker.likelihood``, the
  configured component; ``step`` makes one such call for all its tracking filters together, of which
  this is the case of one filter) for each configuration, and the bare line-column kernel against its NumPy reference.

Configurations: ``paper`` (500 particles, a line column of 20 heights, weights ∝ count, shadows
count as object) and ``default`` (500 particles, a 3-line column of 20 heights with 4 samples below
the floor and 3 above the top — ``column.foot_samples``, ``column.head_samples`` — the column ratio
with the height prior, shadows removed, explaining away, split and merge checks, the colour model of
``trackers/particle/appearance.py``) and ``no-appearance`` (the default without the colour model, to show what it
costs).

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
from worldtrack.config import with_overrides  # noqa: E402
from worldtrack.foreground.shadows import floor_pixels, read_shadows, read_shadows_reference  # noqa: E402
from worldtrack.trackers.particle import ParticleConfig, ParticleTracker, image_box  # noqa: E402
from worldtrack.trackers.particle.likelihood import (CameraLikelihood, column_counts_reference,  # noqa: E402
                                                     column_heights, column_spec, edge_spec, owner_image,
                                                     top_edge_offsets)
from worldtrack.trackers.particle.likelihood.models import FrameView, Readers  # noqa: E402

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
    tracker = ParticleTracker(scene, {"cam": StaticBackground(bg, 25.0, "colour", shadows=True)}, config)   # its own γ
    for x, y in people_at(k, 0):
        tracker.init_track(x, y)
    times = []
    for f, img in enumerate(frames):
        t0 = time.perf_counter()
        tracker.step({"cam": img}, (f + 1) / 10.0)
        times.append(time.perf_counter() - t0)
    if len(tracker.clouds) != k:
        print(f"warning: {len(tracker.clouds)} of {k} tracks left", file=sys.stderr)
    return statistics.median(times[3:])


def main() -> int:
    cv2.setNumThreads(1)
    scene = scene_from_dict(SCENE)
    cam = scene.cameras["cam"]
    rng = np.random.default_rng(0)
    bg = np.clip(cv2.GaussianBlur(rng.uniform(60, 200, (H, W, 3)).astype(np.float32), (0, 0), 3), 0, 255).astype(np.uint8)
    held = {"detection.births": "none", "tracking.end_after_s": 1e9}     # K stays K
    configs = {"paper": with_overrides(ParticleConfig.paper(), held),
               "default": with_overrides(ParticleConfig(), held),
               "no-appearance": with_overrides(ParticleConfig(), {**held, "appearance.weight": 0.0})}
    mog2 = mog2_apply_time(W, H)
    print(f"MOG2 apply {W}x{H}: {1000 * mog2:.2f} ms", file=sys.stderr)

    # Per-frame image preparation, as ParticleTracker._images does it (shadows only on the floor).
    img = render(cam, bg, people_at(10, 0), rng)
    fg = StaticBackground(bg, 25.0, "colour", shadows=True)   # the particle tracker's own γ
    floor = floor_pixels(cam, scene.walkable.raster(0.01))
    labels = fg.labels(img)
    prep = {"foreground labels, F > γ with shadow-like changes apart": median_time(lambda: fg.labels(img)),
            "shadows judged on the floor (Numba, default)": median_time(lambda: read_shadows(labels, img, bg, floor, 0)),
            "shadows judged (box-filter reference)": median_time(lambda: read_shadows_reference(labels, img, bg, floor, 0),
                                                                 repeats=5)}
    prep_rows = [[k, 1000 * v, v / mog2] for k, v in prep.items()]

    # Tracking cost against the number of objects.
    rows = []
    per_object = {}
    for name, cfg in configs.items():
        base = None
        for k in (0,) + COUNTS:
            frames = [render(cam, bg, people_at(k, f + 1), np.random.default_rng(f)) for f in range(FRAMES)]
            t = step_time(cfg, k, scene, bg, frames)
            if k == 0:
                base = t
                continue
            po = (t - base) / k
            per_object.setdefault(name, []).append(po)
            rows.append([name, k, 1000 * t, 1000 * po, po / mog2])
            print(f"{name:8s} K={k:2d}: {1000 * t:7.2f} ms/frame, {1000 * po:.3f} ms/object "
                  f"= {po / mog2:.3f} MOG2", file=sys.stderr)

    # The likelihood alone: one tracking filter of 500 particles about one person, read as step()
    # reads its tracking filters with the tracker's likelihood (the image it reads, the filter's
    # own box among the track boxes when explaining away, the particles' heights).
    person = people_at(1, 0)
    img = render(cam, bg, person, rng)
    xy = person + rng.normal(0, 0.2, (500, 2))
    xyz = np.column_stack([xy, rng.uniform(0, 1.7, 500)])
    h = 1.7 + 0.1 * rng.standard_normal(500)
    kernel_rows = []
    for name, cfg in configs.items():
        tracker = ParticleTracker(scene, {"cam": fg}, cfg)
        lk = cfg.likelihood
        seen = tracker.labels.read({"cam": img}).images["cam"]
        view = FrameView({"cam": seen})
        if cfg.explain.filters == "all":
            box = image_box(cam, person[0, 0], person[0, 1], scene.people.width, scene.people.height,
                            cfg.explain.box_margin_m)
            view = FrameView({"cam": seen}, {"cam": owner_image(seen.shape, [box])}, {"cam": [box]})
        readers = Readers.one(len(xyz))
        tk = median_time(lambda: tracker.likelihood(xyz, h, view, readers, top_edge=True), repeats=200)
        kernel_rows.append([f"likelihood ({lk.model}), {name} config", 1000 * tk, tk / mog2])
        he = cfg.height
        if he.edge_weight > 0 and he.prior_sigma_m > 0:
            edge = edge_spec(top_edge_offsets(he.edge_step_m, he.edge_samples), he.edge_weight,
                             tracker.likelihood.on, tracker.likelihood.off)
            out, cl_edge = np.zeros(len(xyz)), CameraLikelihood(cam)
            # The route step takes with edge_explain off (every config here): the labels as they are.
            reading = cl_edge.reading(seen, len(xyz))
            te = median_time(lambda: cl_edge.top_edge(reading, xyz, h, edge, out), repeats=200)
            kernel_rows.append([f"of which the top edge ({len(edge.offsets)} samples), {name} config", 1000 * te,
                                te / mog2])
    # The bare kernel: a line column of the paper's 20 heights, against the NumPy reference.
    cl = CameraLikelihood(cam)
    hit = (labels != 0).astype(np.uint8)
    line = column_spec(column_heights(configs["paper"].column.max_height_m, configs["paper"].column.dz_m))
    k_line = median_time(lambda: cl.column(hit, xy, line), repeats=200)
    k_ref = median_time(lambda: column_counts_reference(cam, hit, xy, line), repeats=20)
    kernel_rows += [["column kernel alone (Numba), line column of 20 heights", 1000 * k_line, k_line / mog2],
                    ["NumPy reference, line column of 20 heights", 1000 * k_ref, k_ref / mog2]]

    t1 = markdown_table(["per-frame step", "ms", "× MOG2"], prep_rows)
    t2 = markdown_table(["config", "objects", "ms/frame", "ms/object", "per object × MOG2"], rows)
    t3 = markdown_table(["500 particles", "ms", "× MOG2"], kernel_rows)
    summary = ", ".join(f"{n}: median {np.median(v) / mog2:.3f} × MOG2 per object" for n, v in per_object.items())
    text = (f"One MOG2 apply on {W}x{H}: {1000 * mog2:.2f} ms (the reference). {summary}.\n\n"
            f"Per frame, independent of the objects:\n\n{t1}\n\nTracking (median over {FRAMES - 3} frames; "
            f"per object = (ms/frame(K) − ms/frame(0)) / K):\n\n{t2}\n\nThe likelihood alone (one filter's "
            f"500 particles, as step reads them; default: 20 heights + {configs['default'].column.foot_samples} below + "
            f"{configs['default'].column.head_samples} above, 3 lines, and the top edge of tracking filters):\n\n{t3}\n")
    print(text)
    path = write_result("particle_speed", "Particle tracker (seed 004): speed",
                        "Command: `.venv/bin/python benchmarks/particle_speed.py`\n\n" + text)
    print(f"wrote {path}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
