"""Shared pieces of the seed-002 benchmarks: problems, the baseline, and how estimates are scored.

Scores, per person, on the estimate's grid against the ground-truth head points:

- *in view*: steps with at least one observation; horizontal RMSE and head-height RMSE;
- *between views*: the other steps (between the first and last observation); horizontal RMSE;
- *inside obstacles*: steps whose floor position has a negative signed distance (inside a desk,
  a screen, a wall, or outside the floor);
- *wall crossings*: steps whose straight segment to the next step crosses a wall line.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import ROOT, save_result  # noqa: E402,F401

from worldtrack.geometry.camera import Camera  # noqa: E402
from worldtrack.trajectory.environment import inside_obstacles, segment_crossings  # noqa: E402
from worldtrack.trajectory.model import TimeGrid  # noqa: E402
from worldtrack.trajectory.observation import Observations  # noqa: E402
from worldtrack.trajectory.smoother import kalman_rts  # noqa: E402


def pin_to_one_core(cpu: int | None) -> str:
    """Run this process on one processor (the speed targets are for one core); what was granted."""
    if cpu is None or not hasattr(os, "sched_setaffinity"):
        return "not pinned"
    try:
        os.sched_setaffinity(0, {cpu})
    except OSError as e:
        return f"not pinned ({e.strerror})"
    return f"pinned to cpu {cpu}"


def walks_parser(doc: str, repeats: int, quick_size: int = 300) -> argparse.ArgumentParser:
    """The options of the benchmarks that time long office walks (``--sizes``, ``--seeds``,
    ``--repeats``, ``--cpu``, ``--quick``); ``doc``'s first paragraph is the description."""
    ap = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    ap.add_argument("--sizes", default="1000,10000")
    ap.add_argument("--seeds", default="3,42,90")
    ap.add_argument("--repeats", type=int, default=repeats)
    ap.add_argument("--cpu", type=int, default=1, help="processor to pin to (-1: do not pin)")
    ap.add_argument("--quick", action="store_true", help=f"T = {quick_size}, seed 3, one repeat; prints only")
    return ap


def walks_of(args: argparse.Namespace, quick_size: int = 300) -> tuple[str, list[int], list[int], int]:
    """Pin this process as ``args.cpu`` asks; (what was granted, walk sizes, seeds, repeats)."""
    cpu = pin_to_one_core(None if args.cpu < 0 else args.cpu)
    if args.quick:
        return cpu, [quick_size], [3], 1
    return cpu, [int(s) for s in args.sizes.split(",")], [int(s) for s in args.seeds.split(",")], args.repeats


def add_seed_blocks(ap: argparse.ArgumentParser, name: str) -> None:
    """``--held-out`` and ``--never-used`` (seeds labelled in the table) and ``--tag`` (writes
    ``results/<name>_<tag>.md`` instead)."""
    ap.add_argument("--held-out", default="", help="seeds (comma-separated) labelled held-out in the table")
    ap.add_argument("--never-used", default="", help="seeds labelled never-used")
    ap.add_argument("--tag", default="", help=f"writes results/{name}_<tag>.md instead")


def block_of(args: argparse.Namespace) -> dict[int, str]:
    """Seed → its block's label from :func:`add_seed_blocks`' options (a seed not named is dev)."""
    return {int(s): name for name, given in (("held-out", args.held_out), ("never-used", args.never_used))
            for s in given.split(",") if s}


def rows_of_walks(sizes: list[int], seeds: list[int], labels: dict[int, str], row) -> list[list]:
    """``row(T, seed, block)`` for every walk size and seed (``labels``: :func:`block_of`, dev when not
    named), each row printed to stderr as it comes (long runs show their progress)."""
    rows = []
    for T in sizes:
        for seed in seeds:
            rows.append(row(T, seed, labels.get(seed, "dev")))
            print(" | ".join(map(str, rows[-1])), file=sys.stderr, flush=True)
    return rows


def iteration_totals(rows: list[list], sizes: list[int], variants: int, note=None) -> list[list]:
    """Per walk size a row "all" summing the iterations (each cell's leading integer) of the default (column 2)
    and of each of ``variants`` columns after it; ``note(cells)`` (optional) adds a text after a variant's sum."""
    totals = []
    for T in sizes:
        mine = [r for r in rows if r[0] == T]

        def its(i: int) -> int:
            return sum(int(str(r[i]).split()[0]) for r in mine)
        totals.append([T, "all", its(2), *(its(3 + k) if note is None else
                                           f"{its(3 + k)}, {note([r[3 + k] for r in mine])}" for k in range(variants))])
    return totals


def save_walks(name: str, title: str, text: str, args: argparse.Namespace, seconds: float) -> None:
    """``save_result`` for a walk benchmark: ``results/<name>[_<tag>].md`` (``--tag``, :func:`add_seed_blocks`)."""
    save_result(name + (f"_{args.tag}" if args.tag else ""), title, text, args.quick, seconds, script=name)


def add_estimate_flags(ap: argparse.ArgumentParser, name: str) -> None:
    """Issue 34's opt-in estimate options as flags: ``--route-timing`` (``TrajectoryOptions.route_timing``),
    ``--outward`` (``SolverOptions.outward_curvature``) and, with it, ``--shrink`` (``shrink_on_reject``) and
    ``--finish`` (``finish_newton``). Any of them writes ``results/<name>`` with :func:`estimate_tail`'s suffix and
    no picture."""
    ap.add_argument("--route-timing", default="constant", choices=["constant", "cubic"],
                    help=f"TrajectoryOptions.route_timing (opt-in cubic, 34m): writes results/{name}_cubic.md, "
                         "no picture")
    ap.add_argument("--outward", type=float, default=None,
                    help=f"SolverOptions.outward_curvature (opt-in, 34n): writes results/{name}_outward.md, no picture")
    ap.add_argument("--shrink", action="store_true", help="with --outward also SolverOptions.shrink_on_reject (34g); "
                    "adds _shrink to the results file")
    ap.add_argument("--finish", action="store_true", help="with --outward also SolverOptions.finish_newton (34o); "
                    "adds _finish to the results file")


def estimate_options(args: argparse.Namespace) -> dict:
    """Keyword options of ``estimate_trajectory`` from :func:`add_estimate_flags`' flags."""
    from worldtrack.trajectory.solver import SolverOptions

    extra: dict = {"route_timing": args.route_timing}
    if args.outward is not None:
        extra["solver"] = SolverOptions(outward_curvature=args.outward, shrink_on_reject=args.shrink,
                                        finish_newton=args.finish)
    return extra


def estimate_tail(args: argparse.Namespace) -> tuple[str, str]:
    """(results file suffix, title suffix) of :func:`add_estimate_flags`' flags; ("", "") for the defaults."""
    cubic, outward = args.route_timing != "constant", args.outward is not None
    tail = ("_shrink" if outward and args.shrink else "") + ("_finish" if outward and args.finish else "")
    return (("_cubic" if cubic else "") + ("_outward" if outward else "") + tail,
            (" (route_timing='cubic')" if cubic else "") + (f" (outward_curvature={args.outward})" if outward else "")
            + tail.replace("_", " "))


def least_cpu(fn, repeats: int):
    """(least CPU seconds of ``repeats`` calls of ``fn``, the last call's result)."""
    best, out = float("inf"), None
    for _ in range(repeats):
        c0 = time.process_time()
        out = fn()
        best = min(best, time.process_time() - c0)
    return best, out


def rmse(e: np.ndarray) -> float:
    return float(np.sqrt(np.mean(e ** 2))) if len(e) else float("nan")


@dataclass
class Score:
    """One estimate against the truth; the fields are per-person sums and counts for pooling."""

    in_view_sq: float = 0.0
    in_view_z_sq: float = 0.0
    in_view_n: int = 0
    between_sq: float = 0.0
    between_n: int = 0
    inside: int = 0
    crossings: int = 0
    steps: int = 0

    def add(self, other: "Score") -> "Score":
        return Score(*(a + b for a, b in zip(vars(self).values(), vars(other).values())))

    @property
    def in_view(self) -> float:
        return float(np.sqrt(self.in_view_sq / max(self.in_view_n, 1)))

    @property
    def in_view_z(self) -> float:
        return float(np.sqrt(self.in_view_z_sq / max(self.in_view_n, 1)))

    @property
    def between(self) -> float:
        return float(np.sqrt(self.between_sq / max(self.between_n, 1)))


def score(xy: np.ndarray, truth: np.ndarray, seen: np.ndarray, field=None, walls=None, z: np.ndarray | None = None) -> Score:
    """Score a floor path (n, 2) (and head heights z (n,)) against truth (n, 3)."""
    e = np.hypot(*(xy - truth[:, :2]).T)
    ez = (z - truth[:, 2]) if z is not None else np.zeros(len(xy))
    return Score(float(np.sum(e[seen] ** 2)), float(np.sum(ez[seen] ** 2)), int(seen.sum()),
                 float(np.sum(e[~seen] ** 2)), int((~seen).sum()),
                 int(inside_obstacles(field, xy).sum()) if field is not None else 0,
                 int(segment_crossings(xy, walls).sum()) if walls is not None and len(walls) else 0, len(xy))


def baseline(obs: Observations, times: np.ndarray, q: float, height: float):
    """The Kalman + RTS smoother on the estimate's grid."""
    grid = TimeGrid(float(times[0]), float(times[1] - times[0]), len(times))
    return kalman_rts(obs, grid, q, height)


def with_distortion(cameras: dict[str, Camera], dist=(-0.12, 0.03, 0.0006, -0.0004, 0.0)) -> dict[str, Camera]:
    """The same cameras with lens distortion (k3 = 0: GTSAM's Cal3DS2 has none)."""
    return {cid: Camera(cid, c.width, c.height, c.K, c.R, c.t, np.asarray(dist, float)) for cid, c in cameras.items()}


def project_observations(cameras: dict[str, Camera], times: np.ndarray, points: np.ndarray, noise_px: float,
                         rng: np.random.Generator, margin_px: float = 0.0) -> tuple[Observations, np.ndarray]:
    """Head points (T, 3) at ``times`` seen by every camera whose image holds them, with Gaussian
    pixel noise; also the row of ``points`` of each observation."""
    rows, ids, uvs = [], [], []
    for cid, cam in cameras.items():
        uv, depth = cam.project(points, return_depth=True)
        ok = (depth > 0) & cam.in_image(uv, margin_px)
        rows.append(np.flatnonzero(ok))
        ids.append(np.full(ok.sum(), cid, dtype=object))
        uvs.append(uv[ok])
    rows_a = np.concatenate(rows)
    order = np.argsort(rows_a, kind="stable")
    rows_a = rows_a[order]
    uv = np.concatenate(uvs)[order] + rng.normal(0.0, noise_px, (len(order), 2))
    noisy = np.ones(len(uv), dtype=bool)
    for cid, cam in cameras.items():                 # noise may push a pixel off the edge: drop it
        sel = np.concatenate(ids)[order] == cid
        noisy[sel] = cam.in_image(uv[sel])
    cam_ids = np.concatenate(ids)[order]
    keep = np.flatnonzero(noisy)
    obs = Observations.from_rows(times[rows_a[keep]], cam_ids[keep], uv[keep], cameras, 2.0 if noise_px <= 0 else noise_px)
    return obs, rows_a[keep]


def long_office_walk(steps: int, seed: int = 0, fps: float = 10.0):
    """(scene with distorted cameras, times (T,), head points (T, 3), height) of one person walking the
    detour office for ``steps`` frames at ``fps`` (the speed benchmark's problem)."""
    from worldtrack.synth import make_scenario
    sc = make_scenario("non-overlapping", frames=steps, seed=seed, people=1, layout="detours", size=(640, 480),
                       legs=max(10, steps // 12), fps=fps)
    person = sc.people[0]
    t = np.arange(steps) / fps
    bob = 0.015 * np.sin(2 * np.pi * 1.8 * t) * (person.track.speed > 0.1)
    points = np.column_stack([person.track.xy, person.shape.height - 0.02 + bob])
    scene = sc.scene.with_cameras(with_distortion(sc.scene.cameras))
    return scene, t, points, float(person.shape.height)


def winners(estimate, rel: float = 1e-6) -> str:
    """The starts whose optimum is within ``rel`` of the best ("map+straight" when two tie)."""
    best = min(estimate.start_objectives.values())
    return "+".join(sorted(k for k, v in estimate.start_objectives.items() if v <= best + rel * abs(best)))
