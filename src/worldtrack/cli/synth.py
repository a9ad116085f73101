"""``worldtrack synth SCENARIO --out DIR``: render a built-in synthetic sequence to a folder."""

from __future__ import annotations

import argparse

import yaml

from worldtrack.errors import InputError


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "synth", help="render a synthetic multi-camera sequence with exact ground truth",
        usage="worldtrack synth SCENARIO --out DIR [options]\n       worldtrack synth --list",
        description="Render a built-in scenario (people walking in a calibrated room) to video or PNG "
                    "frames, with depth/disparity where the sensor has them, gt.csv, frames.csv and "
                    "scene.yaml. Same seed, same files. `worldtrack synth --list` shows the scenarios.")
    p.add_argument("scenario", nargs="?", metavar="SCENARIO", help="scenario name (see --list; required unless --list)")
    p.add_argument("--out", metavar="DIR", help="output folder, created (required unless --list)")
    p.add_argument("--frames", type=int, help="number of frames (default: the scenario's length)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--size", metavar="WxH", help="image size in pixels, e.g. 640x480 (default: the scenario's)")
    p.add_argument("--png", action="store_true", help="write lossless PNG frames instead of MP4 video")
    p.add_argument("--instances", action="store_true", help="also write 16-bit person-id images")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="NAME=VALUE",
                   help="scenario parameter, e.g. --set people=20 --set camera=both (repeatable)")
    p.add_argument("--list", action="store_true", help="list the scenarios and their parameters, then exit")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--no-progress", action="store_true", dest="quiet", help=argparse.SUPPRESS)  # the former name
    p.set_defaults(func=run)


def _parse_overrides(items: list[str]) -> dict:
    out = {}
    for item in items:
        if "=" not in item:
            raise InputError(f"--set: expected NAME=VALUE, got {item!r}")
        name, value = item.split("=", 1)
        try:
            parsed = yaml.safe_load(value)
        except yaml.YAMLError:
            parsed = value
        if isinstance(parsed, list):
            parsed = tuple(parsed)
        out[name.strip().replace("-", "_")] = parsed
    return out


def run(args: argparse.Namespace) -> int:
    from worldtrack.synth import list_scenarios, make_scenario, scenario_parameters, write_sequence

    if args.list:
        for name, summary in list_scenarios().items():
            params = ", ".join(f"{k}={v!r}" for k, v in scenario_parameters(name).items())
            print(f"{name:16s} {summary}\n{'':16s} parameters: {params}")
        from dataclasses import fields
        from worldtrack.synth import Common
        common = ", ".join(f"{f.name}={f.default!r}" for f in fields(Common))
        print(f"\nevery scenario also takes: {common}")
        return 0
    if not args.scenario:
        raise InputError(f"expected a scenario name (one of: {', '.join(sorted(list_scenarios()))})")
    if args.scenario not in list_scenarios():
        raise InputError(f"unknown scenario {args.scenario!r} (known: {', '.join(sorted(list_scenarios()))})")
    if not args.out:
        raise InputError("--out: expected an output folder")
    scenario = make_scenario(args.scenario, size=args.size, frames=args.frames, seed=args.seed,
                             **_parse_overrides(args.overrides))
    out = write_sequence(scenario, args.out, png=args.png, progress=not args.quiet, instances=args.instances)
    print(f"wrote {scenario.n_frames} frames of {scenario.name!r} from {len(scenario.camera_ids)} camera(s) to {out}")
    return 0
