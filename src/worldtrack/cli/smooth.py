"""``worldtrack smooth SCENE OBSERVATIONS… --out DIR``: head trajectories across cameras that do not
share views, by MAP estimation with the scene as environment model (paper 002)."""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from worldtrack.cli._args import positive
from worldtrack.errors import InputError
from worldtrack.io.observations import ObservationTable, observations_from_tracks, read_observations, write_trajectories
from worldtrack.scene import load_scene
from worldtrack.trajectory.estimate import TrajectoryOptions, estimate_trajectory
from worldtrack.trajectory.model import MotionPrior
from worldtrack.trajectory.observation import Observations
from worldtrack.trajectory.starts import START_NAMES


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "smooth", help="estimate head trajectories across cameras that do not share views (paper 002)",
        description="MAP estimate of each person's head trajectory from head pixels in cameras that need not "
                    "share views: a constant-velocity motion prior, the scene's walls and obstacles (people keep "
                    "clear of them) and the person's head height. Writes DIR/trajectory.csv (id,t,x,y,z,vx,vy,vz,"
                    "sigma_x,sigma_y,sigma_z,rho_xy,observed,barrier), DIR/floorplan.png (observations, estimate, "
                    "±2σ band, obstacles) and DIR/height.png.")
    p.add_argument("scene", help="scene YAML file (cameras, floor, obstacles)")
    p.add_argument("observations", nargs="+", metavar="OBSERVATIONS",
                   help="observations.csv with columns t,camera,u,v[,sigma_px][,id][,height][,u_feet,v_feet"
                        "[,sigma_feet_px]] (seconds, pixels of the head and of the floor below it: the feet make the "
                        "head height observable), or t,camera,left,top,right,bottom[,…] (a box: its top and bottom "
                        "centres), or CAM=tracks.csv from 'worldtrack track' on camera CAM (the head point of each "
                        "row is projected into CAM)")
    p.add_argument("--out", default="smooth_out", metavar="DIR", help="output folder (default: smooth_out)")
    p.add_argument("--person", type=int, action="append", default=[], metavar="ID",
                   help="only this person (repeatable; default: every id)")
    p.add_argument("--dt", default=None, metavar="S", help="time step in seconds (default: the cameras' frame interval)")
    p.add_argument("--height", default=None, metavar="M",
                   help="head height in metres for e_v (default: the observations' height column; else, with feet "
                        "pixels, fitted to the person; else the scene's person height)")
    p.add_argument("--sigma-px", default="2", metavar="PX", help="pixel noise where sigma_px is not given (default 2)")
    p.add_argument("--q", default=None, metavar="M2S3",
                   help=f"horizontal acceleration noise, m²/s³ (default {MotionPrior().q_horizontal:g})")
    p.add_argument("--first-velocity-sigma", default=None, metavar="M/S",
                   help=f"spread of the prior on the first velocity, per axis (default "
                        f"{MotionPrior().first_velocity_sigma:g} m/s; 'none': the paper's flat start)")
    p.add_argument("--clearance", default=None, metavar="M",
                   help=f"distance people keep from obstacles and walls (default {TrajectoryOptions().clearance:g} m)")
    p.add_argument("--weight", default=None, metavar="LAMBDA", help="λ, the environment's weight (default 1)")
    p.add_argument("--robust", default=None, metavar="K", help="Huber threshold on reprojection errors, in σ "
                                                               "(default: plain least squares)")
    p.add_argument("--no-environment", action="store_true", help="no obstacle barrier (the paper's comparison)")
    p.add_argument("--starts", default=",".join(START_NAMES), metavar="LIST",
                   help=f"initial trajectories, a comma list of {', '.join(START_NAMES)} (default: all)")
    p.add_argument("--no-plots", action="store_true", help="do not draw floorplan.png and height.png")
    p.add_argument("--quiet", action="store_true", help="no per-person lines")
    p.set_defaults(func=run)


def _options(args: argparse.Namespace) -> TrajectoryOptions:
    opts = TrajectoryOptions(starts=tuple(s.strip() for s in args.starts.split(",") if s.strip()),
                             environment=not args.no_environment)
    if args.dt is not None:
        opts = replace(opts, dt=positive(args.dt, "--dt", "0.1"))
    if args.q is not None:
        opts = replace(opts, motion=replace(opts.motion, q_horizontal=positive(args.q, "--q", "1.0")))
    if args.first_velocity_sigma is not None:
        sigma = (None if args.first_velocity_sigma.strip().lower() == "none"
                 else positive(args.first_velocity_sigma, "--first-velocity-sigma", "2"))
        opts = replace(opts, motion=replace(opts.motion, first_velocity_sigma=sigma))
    if args.clearance is not None:
        opts = replace(opts, clearance=positive(args.clearance, "--clearance", "0.2"))
    if args.weight is not None:
        opts = replace(opts, weight=positive(args.weight, "--weight", "1"))
    if args.robust is not None:
        opts = replace(opts, robust=positive(args.robust, "--robust", "3"))
    return opts


def read_inputs(items: list[str], cameras: dict, sigma_px: float) -> ObservationTable:
    """Every OBSERVATIONS argument read into one table."""
    tables = []
    for item in items:
        if "=" in item and not Path(item).exists():
            cid, path = (s.strip() for s in item.split("=", 1))
            if cid not in cameras:
                raise InputError(f"{item}: unknown camera {cid!r} (cameras: {', '.join(cameras)})")
            tables.append(observations_from_tracks(path, cameras[cid], sigma_px))
        else:
            tables.append(read_observations(item, cameras, sigma_px))
    return ObservationTable.concatenate(tables)


def run(args: argparse.Namespace) -> int:
    scene = load_scene(args.scene)
    sigma_px = positive(args.sigma_px, "--sigma-px", "2")
    table = read_inputs(args.observations, scene.cameras, sigma_px)
    options = _options(args)
    height_arg = positive(args.height, "--height", "1.70") if args.height is not None else None
    people = args.person or table.people()
    unknown = sorted(set(people) - set(table.people()))
    if unknown:
        raise InputError(f"--person {unknown[0]}: no observations of that id (ids: "
                         f"{', '.join(map(str, table.people()))})")
    field = scene.distance_field(0.05) if options.environment else None
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    estimates, columns, observations = {}, {}, {}
    for pid in people:
        rows = table.of(pid)
        if len(rows) < 2:
            print(f"person {pid}: {len(rows)} observation, skipped (need 2 or more)", file=sys.stderr)
            continue
        given = rows.height[np.isfinite(rows.height)]
        height = height_arg or (float(np.median(given)) if len(given) else scene.people.size_of(pid)[0])
        obs = Observations.from_rows(rows.time, rows.camera, rows.uv, scene.cameras, rows.sigma, rows.feet_uv,
                                     rows.feet_sigma)
        fit = not (height_arg or len(given)) and bool(obs.has_feet.any())
        t0 = time.perf_counter()
        try:
            est = estimate_trajectory(obs, field, replace(options, height=height, fit_height=fit))
        except InputError as e:                       # this person only (e.g. one time stamp): go on
            print(f"person {pid}: skipped: {e}", file=sys.stderr)
            continue
        estimates[pid], columns[pid], observations[pid] = est, est.columns(), obs
        write_trajectories(out / "trajectory.csv", columns)      # after every person: an interrupt keeps them
        if not args.quiet:
            seen = int(np.count_nonzero(est.observed))
            print(f"person {pid}: {len(est.times)} steps of {est.times[1] - est.times[0]:g} s, {len(obs)} observations "
                  f"on {seen} steps, head height {est.height:.2f} m{' (fitted: feet seen)' if fit else ''}; start '{est.start}' won "
                  f"(objective {est.costs['total']:.1f}: motion {est.costs['motion']:.1f}, observations "
                  f"{est.costs['observation']:.1f}, barrier {est.costs['barrier']:.2f}, height {est.costs['height']:.2f}); "
                  f"barrier active on {int(est.barrier_active.sum())} steps; {time.perf_counter() - t0:.2f} s",
                  file=sys.stderr)
    if not estimates:
        raise InputError("no person has 2 or more observations")
    print(f"trajectories: {out / 'trajectory.csv'}", file=sys.stderr)
    if not args.no_plots:
        _plots(scene, observations, estimates, out)
    return 0


def _plots(scene, observations: dict, estimates: dict, out: Path) -> None:
    from worldtrack.viz.trajectory import observation_points, save_height_plot, save_trajectory_plan
    ids = list(scene.cameras)
    points = {pid: observation_points(observations[pid], est, ids) for pid, est in estimates.items()}
    head = float(np.median([np.median(e.positions[:, 2]) for e in estimates.values()]))
    plan = save_trajectory_plan(scene, out / "floorplan.png", estimates, points, coverage_height=head)
    height = save_height_plot(out / "height.png", estimates)
    print(f"floor plan: {plan}\nheight plot: {height}", file=sys.stderr)
