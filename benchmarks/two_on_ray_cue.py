"""One tall person or two on one line of sight: how well the head's size tells them apart (issue 37).

On the ``line-of-sight`` scenario (one camera 2.5–3 m high, people 5–10 m away), every 4th frame,
each person whose head and feet are both in view is read as a height measurement would read them
(the region of the tallest plausible person at their *true* place, the ellipsoid tracker's
foreground with the evidence shadow test). The renderer's instance image says whose feet end the
silhouette and whose head tops it. Readings whose feet are not the person's own are left out. The
rest fall in two groups:

- **own top**: the silhouette's top is the person's own head (one person);
- **other's top**: it is somebody else's head, usually somebody farther on the same line of sight,
  and the height a single camera reads from it is wrong (the issue's 2.05 m for 1.69 m).

For each group it prints the ratio :func:`worldtrack.trackers.ellipsoid.two_on_ray.head_scale` (the
head band's width over a head's width at the feet's depth) and the share below the threshold
(0.8, chosen on development seeds 20–24). The group "other's top, ≥ 5 cm wrong" is the one a
height must not be taken from. The default seeds 140–144 had never been used.

Usage::

    .venv/bin/python benchmarks/two_on_ray_cue.py                 # seeds 140-144
    .venv/bin/python benchmarks/two_on_ray_cue.py --seeds 20-24 --quick

Writes ``benchmarks/results/two_on_ray_cue.md`` (not with ``--quick``).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import markdown_table, save_result  # noqa: E402
from crowd_seeds import _seed_list  # noqa: E402

from worldtrack.experiment import synthetic_threshold  # noqa: E402
from worldtrack.foreground import make_foregrounds  # noqa: E402
from worldtrack.synth import make_scenario  # noqa: E402
from worldtrack.trackers import make_tracker  # noqa: E402
from worldtrack.trackers.ellipsoid.births import head_height  # noqa: E402
from worldtrack.trackers.ellipsoid.forms import ellipse_crop  # noqa: E402
from worldtrack.trackers.ellipsoid.two_on_ray import silhouette_ratio  # noqa: E402

THRESHOLD = 0.8
WRONG_M = 0.05
EVERY = 4


def _owner(instance: np.ndarray, px: np.ndarray) -> int:
    """The person (instance id) most present in the 5x5 pixels around ``px``, 0 for none."""
    u, v = int(round(px[0])), int(round(px[1]))
    w = instance[max(v - 2, 0):v + 3, max(u - 2, 0):u + 3]
    w = w[w > 0]
    return int(np.bincount(w).argmax()) if len(w) else 0


def readings(seed: int, size, frames: int) -> list[tuple[bool, float, float]]:
    """(own top?, ratio, height read − true height m) of every clear-view reading of one seed."""
    sc = make_scenario("line-of-sight", size=size, frames=frames, seed=seed)
    fgs = make_foregrounds(sc.scene, {c: sc.background(c) for c in sc.camera_ids}, "colour",
                           synthetic_threshold("ellipsoid", "colour"), shadow_test="evidence")
    view = make_tracker("ellipsoid", sc.scene, fgs).views["cam"]
    cam = view.camera
    out = []
    for i, bundle in enumerate(sc.frames()):
        if i % EVERY:
            continue
        image = bundle.views["cam"]
        labels = fgs["cam"].labels(image.image)
        clear = [g for g in bundle.gt if g["head_cam"] > 0 and g["feet_cam"] > 0]
        if not clear:
            continue
        xy = np.array([[g["x"], g["y"]] for g in clear])
        _, ring, box, valid, _ = view.forms(xy, np.full(len(clear), 2.1), 1.25 * np.array([g["width"] for g in clear]))
        for k, g in enumerate(clear):
            b = tuple(int(x) for x in box[k])
            if not valid[k] or b[0] >= b[1] or b[2] >= b[3]:
                continue
            down = view.down_direction(np.array([(b[0] + b[1]) / 2, (b[2] + b[3]) / 2]))
            if down is None:
                continue
            ratio, top, feet = silhouette_ratio(view, labels, ellipse_crop(ring[k], box[k], view.grid,
                                                                          cam.has_distortion), b, down)
            if not np.isfinite(ratio):
                continue
            bottom = cam.project(feet[None])[0]
            if _owner(image.instance, bottom - 2 * down) != g["id"]:
                continue  # the silhouette ends at somebody else's feet
            h = head_height(cam, top, feet)
            if h is not None:
                out.append((_owner(image.instance, top + 2 * down) == g["id"], ratio, h - g["height"]))
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--seeds", type=_seed_list, nargs="+", default=None, help="default 140-144 (never used)")
    p.add_argument("--quick", action="store_true", help="320x240, 40 frames; prints only")
    args = p.parse_args(argv)
    seeds = list(range(140, 145)) if args.seeds is None else sum(args.seeds, [])
    size, frames = ((320, 240), 40) if args.quick else ((640, 480), 120)
    t0 = time.perf_counter()
    rows = [r for s in seeds for r in readings(s, size, frames)]
    own = np.array([r[0] for r in rows], bool)
    ratio = np.array([r[1] for r in rows])
    err = np.array([r[2] for r in rows])
    groups = [("own top", own), ("other's top", ~own), (f"other's top, ≥ {WRONG_M * 100:.0f} cm wrong",
                                                          ~own & (np.abs(err) >= WRONG_M))]
    table = []
    for name, sel in groups:
        r = ratio[sel]
        pct = np.percentile(r, [5, 25, 50, 75, 95]) if len(r) else [float("nan")] * 5
        table.append([name, int(sel.sum()), float(np.median(err[sel])) if sel.any() else float("nan")] + list(pct)
                     + [float((r < THRESHOLD).mean()) if len(r) else float("nan")])
    headers = ["readings", "n", "median height error m", "ratio p5", "p25", "p50", "p75", "p95",
               f"share below {THRESHOLD}"]
    text = (f"`line-of-sight`, {size[0]}x{size[1]}, {frames} frames, every {EVERY}th frame, seeds "
            f"{seeds[0]}–{seeds[-1]}; each person in clear view read at their true place (tallest plausible "
            f"region, evidence shadow test).\n\n{markdown_table(headers, table)}\n")
    print(text)
    save_result("two_on_ray_cue", "One tall person or two on one line of sight: the head's size (issue 37)", text,
                args.quick, time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
