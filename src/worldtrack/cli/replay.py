"""``worldtrack replay URL --from T --to T --out DIR``: the shared map's tracks, plan and video."""

from __future__ import annotations

import argparse
import sys

from worldtrack.errors import InputError


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "replay", help="rebuild tracks.csv, the floor plan and a plan video from a shared map",
        description="Read the map states of a shared map on Redis between two capture times and write "
                    "DIR/tracks.csv (one row per person present per state), and with --scene "
                    "DIR/floorplan.png and DIR/plan.mp4.")
    p.add_argument("url", help="the map: redis://[USER:PASSWORD@]HOST[:PORT][/DB] or rediss://…")
    p.add_argument("--from", dest="t_from", default=None, metavar="T",
                   help="first capture time: Unix seconds, ISO 8601, or relative to now as --from=-15m "
                        "(default: the stream's start)")
    p.add_argument("--to", dest="t_to", default=None, metavar="T", help="last capture time (default: the end)")
    p.add_argument("--out", default="replay", metavar="DIR",
                   help="output folder (default: replay); frame 0 is --from's bucket, else the map's epoch or first state")
    p.add_argument("--scene", default=None, help="the map's scene file: draws the floor plan and plan video "
                                                 "(must be the scene the map belongs to)")
    p.add_argument("--no-video", action="store_true", help="do not write plan.mp4")
    p.add_argument("--config", metavar="YAML", default=None, help="settings file (its map: section)")
    p.add_argument("--set", action="append", default=[], metavar="map.NAME=VALUE", dest="sets",
                   help="one map setting, e.g. map.prefix=floor2 (repeatable)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import json

    from worldtrack.map.config import map_settings
    from worldtrack.map.connection import MapKeys, check_url, connect, redacted, scene_digest
    from worldtrack.map.replay import parse_time, replay
    cfg = map_settings(args.config, args.sets)
    t_from = parse_time(args.t_from) if args.t_from is not None else None
    t_to = parse_time(args.t_to) if args.t_to is not None else None
    if t_from is not None and t_to is not None and t_to < t_from:
        raise InputError(f"--to {args.t_to} is before --from {args.t_from}")
    client = connect(check_url(args.url))
    keys = MapKeys(cfg.prefix)
    scene = None
    if args.scene:
        from worldtrack.scene import load_scene
        scene = load_scene(args.scene)
        theirs = json.loads(client.get(keys.scene) or "{}")
        if theirs and theirs.get("sha256") != scene_digest(args.scene):
            raise InputError(f"--scene {args.scene}: the map belongs to scene {theirs.get('name')!r} "
                             f"(sha256 {str(theirs.get('sha256'))[:12]}…), not this one")
    result = replay(client, keys, args.out, t_from, t_to, scene=scene, bucket_s=cfg.bucket_s, origin=t_from,
                    video=not args.no_video)
    if result.states == 0:
        raise InputError(f"{redacted(args.url)}: no map states between {args.t_from or 'the start'} and "
                         f"{args.t_to or 'the end'} (prefix {cfg.prefix!r})")
    print(f"{result.states} map states, {result.rows} rows, {len(result.ids)} people; tracks: {result.tracks_csv}",
          file=sys.stderr)
    if result.floorplan:
        print(f"floor plan: {result.floorplan}", file=sys.stderr)
    if result.video:
        print(f"plan video: {result.video}", file=sys.stderr)
    return 0
