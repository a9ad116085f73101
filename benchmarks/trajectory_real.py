"""Seed 002 on real pedestrian trajectories: ETH EWAP (seq_eth, seq_hotel) and UCY zara01.

Question: on people who really walked (not a simulator's walkers), seen by a few small cameras
that do not share views, is the MAP estimate between the views at least as good as a Kalman + RTS
smoother, and does it never cross a wall?

Data (``../shared/data``, or ``$WORLDTRACK_DATA``; read each folder's README): world positions in
metres at 2.5 Hz (``obsmat.txt``: columns 3 and 5), wall lines and pillars (``map.xml``, the same
frame). No video: the cameras are virtual.

Protocol, per sequence and camera seed (``--seeds``, default 0, 1, 2; nothing was tuned on any): 4 cameras (3 for seq_hotel, the smallest) 4 m above
the ground looking down with a random tilt of up to ~7°, 50° horizontal field of view, 640×480;
centres drawn from the annotated positions, at least 4.5 m apart, so their views do not overlap
even on the ground. Every person gets a head height drawn from U(1.6, 1.8) m; the true head point
is projected into every camera whose image holds it, with 2 px noise. Everybody seen by ≥ 2
cameras is estimated on the annotation grid (0.4 s) with the head height unknown (1.70 m, the
middle of the range, for the MAP's e_v and for the baseline's back-projection):

- MAP, walls: obstacles = the ``map.xml`` walls and pillars (the floor: the annotated area + 1 m);
- MAP, walls + free space: also barred, the cells farther than 0.5 m from every *other* person's
  annotated path (the person under test left out: a map learnt from the others);
- the MAP without the barrier, and Kalman + RTS on the back-projected head pixels.

(The MAPs run every start to convergence, to tell which start wins; the default race is run
too, whether its objective is within 1e-6 of every start's best is counted, and its CPU time beside
that of the estimate without the environment.)

Scores: horizontal RMSE between views and in view (the truth at the grid times, interpolated where
an annotation is missing), steps whose segment crosses a wall line (the truth's own crossings are
counted too), steps inside obstacles, which start won.

Run: ``.venv/bin/python benchmarks/trajectory_real.py [--seeds 0,1,2] [--quick]``. Writes
``benchmarks/results/trajectory_real.md`` and one ETH track's floor plan of the first seed
(``trajectory_real_eth.png``). About 3 minutes.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import RESULTS, ROOT, markdown_table, save_result  # noqa: E402
from trajectory_common import (Score, add_estimate_flags, baseline, estimate_options, estimate_tail,  # noqa: E402
                               score, winners)

from worldtrack.scene.load import scene_from_dict  # noqa: E402
from worldtrack.trajectory.environment import field_from_walkable, rasterise_segments  # noqa: E402
from worldtrack.trajectory.estimate import TrajectoryOptions, estimate_trajectory  # noqa: E402
from worldtrack.trajectory.observation import Observations  # noqa: E402

SEQUENCES = {"seq_eth": ("eth_ewap/seq_eth", 4), "seq_hotel": ("eth_ewap/seq_hotel", 3),
             "zara01": ("ucy_zara01", 4)}
CAMERA_HEIGHT, HFOV_DEG, MIN_SEPARATION = 4.0, 50.0, 4.5
RESOLUTION = 0.05
VARIANTS = ("MAP, walls", "MAP, walls + free space", "MAP without barrier", "Kalman+RTS")


def data_root() -> Path:
    env = os.environ.get("WORLDTRACK_DATA")
    return Path(env) if env else (ROOT / ".." / "shared" / "data").resolve()


def load(folder: Path) -> tuple[dict[int, tuple[np.ndarray, np.ndarray]], np.ndarray, np.ndarray]:
    """People {id: (times (n,) s, xy (n, 2) m)}, wall segments (K, 2, 2), pillars (M, 3) = x, y, radius."""
    a = np.loadtxt(folder / "obsmat.txt")
    frames = np.unique(a[:, 0])
    step = np.bincount(np.diff(frames).astype(int)).argmax()           # frames between annotations
    people = {}
    for pid in np.unique(a[:, 1]).astype(int):
        r = a[a[:, 1] == pid]
        r = r[np.argsort(r[:, 0])]
        people[pid] = ((r[:, 0] - frames[0]) / step * 0.4, r[:, [2, 4]])  # 2.5 Hz annotations
    xml = (folder / "map.xml").read_text()
    num = r"([-+\d.eE]+)"
    walls = np.array(re.findall(rf'<Line x1="{num}" y1="{num}" x2="{num}" y2="{num}"', xml), float).reshape(-1, 2, 2)
    pillars = np.array(re.findall(rf'<Circle x="{num}" y="{num}" radius="{num}"', xml), float).reshape(-1, 3)
    return people, walls, pillars


def place_cameras(people, count: int, rng: np.random.Generator) -> list[dict]:
    """Camera blocks for a scene file: centres among the annotated positions, ≥ MIN_SEPARATION apart."""
    pts = np.vstack([xy for _, xy in people.values()])
    centres = []
    for k in rng.permutation(len(pts)):
        c = pts[k]
        if all(np.hypot(*(c - o)) >= MIN_SEPARATION for o in centres):
            centres.append(c)
        if len(centres) == count:
            break
    out = []
    for k, c in enumerate(centres):
        tilt = rng.uniform(0.0, 0.5) * np.array([np.cos(a := rng.uniform(0, 2 * np.pi)), np.sin(a)])
        out.append({"id": f"v{k + 1}", "image_size": [640, 480], "position": [float(c[0]), float(c[1]), CAMERA_HEIGHT],
                    "look_at": [float(c[0] + tilt[0]), float(c[1] + tilt[1]), 0.0], "hfov_deg": HFOV_DEG})
    return out


def make_scene(name: str, people, walls, pillars, cameras: list[dict]):
    pts = np.vstack([xy for _, xy in people.values()] + [walls.reshape(-1, 2)] if len(walls) else
                    [xy for _, xy in people.values()])
    lo, hi = pts.min(axis=0) - 1.0, pts.max(axis=0) + 1.0
    obstacles = [{"name": f"wall{k + 1}", "type": "patch",
                  "corners": [[*a, 0.0], [*b, 0.0], [*b, 2.0], [*a, 2.0]]} for k, (a, b) in enumerate(walls)]
    obstacles += [{"name": f"pillar{k + 1}", "type": "box", "centre": [x, y, 1.0], "size": [2 * r, 2 * r, 2.0]}
                  for k, (x, y, r) in enumerate(pillars)]
    data = {"name": name, "cameras": cameras,
            "floor": {"walkable": [{"outer": [[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]]}]},
            "obstacles": obstacles, "people": {"height": 1.70, "width": 0.45}}
    return scene_from_dict(data, label=name)


class FreeSpace:
    """Cells near anybody's annotated path, counted per person so one can be left out."""

    def __init__(self, scene, people, radius: float = 0.5):
        field = scene.distance_field(RESOLUTION)
        self.origin, self.shape, self.radius = field.origin, field.values.shape, radius
        self.base = field.values > 0                       # walkable in the scene (walls, pillars, floor)
        self.visits = np.zeros(self.shape, dtype=np.int32)
        self.own = {}
        for pid, (_, xy) in people.items():
            cells = np.zeros(self.shape, dtype=bool)
            if len(xy) > 1:
                rasterise_segments(cells, np.stack([xy[:-1], xy[1:]], axis=1), self.origin, RESOLUTION)
            self.own[pid] = cells
            self.visits += cells

    def field_without(self, pid: int):
        """Signed distance to walls, pillars and the cells farther than ``radius`` from the others' paths."""
        from scipy import ndimage
        others = (self.visits - self.own[pid]) > 0
        near = ndimage.distance_transform_edt(~others) * RESOLUTION <= self.radius
        return field_from_walkable(self.base & near, self.origin, RESOLUTION)


def run_sequence(name: str, root: Path, seed: int, totals: dict, starts: Counter, quick: bool, keep: dict,
                 extra: dict | None = None) -> list:
    """``extra``: more ``TrajectoryOptions`` fields of every estimate with the environment (the opt-ins)."""
    extra = extra or {}
    folder, n_cams = SEQUENCES[name]
    people, walls, pillars = load(root / folder)
    rng = np.random.default_rng([seed, sum(map(ord, name))])
    scene = make_scene(name, people, walls, pillars, place_cameras(people, n_cams, rng))
    field = scene.distance_field(RESOLUTION)
    free = FreeSpace(scene, people)
    heights = {pid: rng.uniform(1.6, 1.8) for pid in people}
    cams = scene.cameras
    used = truth_crossings = 0
    for pid, (t, xy) in people.items():
        pts = np.column_stack([xy, np.full(len(t), heights[pid])])
        rows, ids, uvs = [], [], []
        for cid, cam in cams.items():
            uv = cam.project(pts) + rng.normal(0.0, 2.0, (len(t), 2))
            ok = cam.in_image(uv)
            rows += list(np.flatnonzero(ok))
            ids += [cid] * int(ok.sum())
            uvs.append(uv[ok])
        if len(set(ids)) < 2 or (quick and used >= 8):
            continue
        order = np.argsort(rows, kind="stable")
        obs = Observations.from_rows(t[np.array(rows)[order]], np.array(ids)[order], np.vstack(uvs)[order], cams, 2.0)
        opts = TrajectoryOptions(dt=0.4, height=1.70, race_iterations=None, **extra)  # every start
        est = estimate_trajectory(obs, field, opts)
        learnt = estimate_trajectory(obs, free.field_without(pid), opts)
        c0 = time.process_time()
        race = estimate_trajectory(obs, field, TrajectoryOptions(dt=0.4, height=1.70, **extra))
        c1 = time.process_time()
        estimate_trajectory(obs, None, TrajectoryOptions(dt=0.4, height=1.70, environment=False))
        starts[(name, "cpu", "walls")] += c1 - c0
        starts[(name, "cpu", "none")] += time.process_time() - c1
        truth = np.column_stack([np.interp(est.times, t, xy[:, k]) for k in range(2)] + [np.full(len(est.times), heights[pid])])
        seen = est.observed > 0
        kf = baseline(obs, est.times, opts.motion.q_horizontal, 1.70)
        for variant, path in zip(VARIANTS, (est.positions[:, :2], learnt.positions[:, :2],
                                            est.without_barrier[:, [0, 2]], kf.xy)):
            totals[(name, variant)] = totals.get((name, variant), Score()).add(score(path, truth, seen, field, walls))
        truth_crossings += score(truth[:, :2], truth, seen, field, walls).crossings
        starts[(name, "walls", winners(est))] += 1
        starts[(name, "free space", winners(learnt))] += 1
        starts[(name, "race", bool(race.costs["total"] <= est.costs["total"] * (1 + 1e-6)))] += 1
        starts[(name, "excess", "max")] = max(starts[(name, "excess", "max")], race.costs["total"] / est.costs["total"] - 1)
        used += 1
        between = int((~seen).sum())
        if name == "seq_eth" and between > keep.get("between", -1) and len(set(ids)) >= 3:
            keep.update(between=between, scene=scene, est=est, truth=truth, obs=obs, pid=pid)
    return [name, len(people), used, truth_crossings]


def picture(keep: dict) -> None:
    from worldtrack.viz.trajectory import observation_points, save_trajectory_plan
    est, scene, obs, pid = keep["est"], keep["scene"], keep["obs"], keep["pid"]
    save_trajectory_plan(scene, RESULTS / "trajectory_real_eth.png", {pid: est},
                         {pid: observation_points(obs, est, list(scene.cameras))}, {pid: keep["truth"][:, :2]},
                         coverage_height=1.7,
                         title=f"ETH seq_eth, person {pid}: MAP (solid, ±2σ), without barrier (dotted), "
                               f"truth (dashed); virtual cameras")


def report(seed: int, root: Path, missing: list[str], quick: bool, keep: dict, t_start: float,
           extra: dict | None = None) -> str:
    """Every sequence with the cameras of one seed: the table and which start won."""
    totals: dict = {}
    starts: Counter = Counter()
    seqs = []
    for name in SEQUENCES:
        if name in missing:
            print(f"{name}: not under {root}; skipped", file=sys.stderr)
            continue
        seqs.append(run_sequence(name, root, seed, totals, starts, quick, keep, extra))
        print(f"seed {seed}, {name} done ({time.perf_counter() - t_start:.0f} s)", file=sys.stderr)
    rows = []
    for name, n_people, used, truth_cross in seqs:
        kf = totals[(name, "Kalman+RTS")]
        for v in VARIANTS:
            s = totals[(name, v)]
            rows.append([name, v, used, s.between, s.between / kf.between, s.in_view, s.crossings, s.inside, s.steps])
        rows.append([name, "truth (annotations)", used, 0.0, 0.0, 0.0, truth_cross, "", ""])
    table = markdown_table(["sequence", "estimate", "people", "between views RMSE m", "÷ Kalman+RTS", "in view RMSE m",
                            "steps crossing a wall", "steps inside obstacles", "steps"], rows)
    won = "; ".join(f"{seq} ({env}): " + ", ".join(f"{s} {c}" for (q, e, s), c in sorted(starts.items(), key=str)
                                                   if q == seq and e == env)
                    for seq in SEQUENCES for env in ("walls", "free space")
                    if any(k[0] == seq and k[1] == env for k in starts))
    race = ", ".join(f"{seq} {starts[(seq, 'race', True)]} of {starts[(seq, 'race', True)] + starts[(seq, 'race', False)]}"
                     f" (largest excess {starts[(seq, 'excess', 'max')]:+.1e})"
                     for seq in SEQUENCES if (seq, "race", True) in starts or (seq, "race", False) in starts)
    cpu = ", ".join(f"{seq} {starts[(seq, 'cpu', 'walls')]:.2f} / {starts[(seq, 'cpu', 'none')]:.2f} s "
                    f"({starts[(seq, 'cpu', 'walls')] / max(starts[(seq, 'cpu', 'none')], 1e-9):.2f}×)"
                    for seq in SEQUENCES if (seq, "cpu", "none") in starts)
    return (f"## Camera seed {seed}\n\n{table}\n\nStart that won (every start run to convergence; '+' joins starts "
            f"whose optima agree within 1e-6): {won}.\n\nThe default estimate's race reached every start's best "
            f"objective within 1e-6 for: {race}.\n\nCPU seconds of the default estimate (walls) / without the "
            f"environment, all people: {cpu}.\n")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", default="0,1,2", help="camera placements (with heights and noise), e.g. 0,1,2")
    ap.add_argument("--quick", action="store_true", help="seed 0, 8 people per sequence; prints only")
    add_estimate_flags(ap, "trajectory_real")
    args = ap.parse_args(argv)
    extra = estimate_options(args)
    root = data_root()
    missing = [n for n, (f, _) in SEQUENCES.items() if not (root / f / "obsmat.txt").is_file()]
    if len(missing) == len(SEQUENCES):
        print(f"trajectory_real: no ETH/UCY data under {root} (set WORLDTRACK_DATA); skipped")
        return 0
    t_start = time.perf_counter()
    seeds = [0] if args.quick else [int(s) for s in args.seeds.split(",")]
    keep: dict = {}
    suffix, title_suffix = estimate_tail(args)
    sections = [report(seed, root, missing, args.quick, keep if seed == seeds[0] and not suffix else {},
                       t_start, extra) for seed in seeds]
    text = ("Head heights U(1.6, 1.8) m, estimated with 1.70 m; 2 px noise; grid 0.4 s.\n\n" + "\n".join(sections))
    print(text)
    if keep and not args.quick:
        picture(keep)
    save_result("trajectory_real" + suffix, "Seed 002 on ETH EWAP and UCY zara01 (virtual cameras)"
                + title_suffix, text, args.quick,
                time.perf_counter() - t_start, script="trajectory_real")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
