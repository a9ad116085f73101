"""``worldtrack map status|fuse|reset URL``: look at a shared map, run its fusion role, or clear it."""

from __future__ import annotations

import argparse
import sys
import threading
import time

from worldtrack.errors import InputError


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument("url", help="the map: redis://[USER:PASSWORD@]HOST[:PORT][/DB] or rediss://… (credentials "
                               "may also come from WORLDTRACK_REDIS_USER / WORLDTRACK_REDIS_PASSWORD)")
    p.add_argument("--config", metavar="YAML", default=None, help="settings file (its map: section)")
    p.add_argument("--set", action="append", default=[], metavar="map.NAME=VALUE", dest="sets",
                   help="one map setting, e.g. map.prefix=floor2 (repeatable)")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("map", help="a shared map on Redis: status, fusion, reset",
                       description="Look at or serve a shared position map on Redis.")
    verbs = p.add_subparsers(dest="map_command", metavar="<verb>")
    s = verbs.add_parser("status", help="workers, cameras, leases, lag and people")
    _common(s)
    s.add_argument("--json", action="store_true", help="print the status as one JSON object")
    s.set_defaults(func=run_status)
    f = verbs.add_parser("fuse", help="contend for the fusion role and serve it (no cameras)")
    _common(f)
    f.add_argument("--seconds", type=float, default=None, help="stop after this long (default: until Ctrl-C)")
    f.set_defaults(func=run_fuse)
    st = verbs.add_parser("start", help="play the workers' video files from now on (sets the map's epoch)")
    _common(st)
    st.add_argument("--in", dest="lead", type=float, default=1.0, metavar="S",
                    help="frame 0 plays this many seconds from now (default 1)")
    st.set_defaults(func=run_start)
    r = verbs.add_parser("reset", help="delete every key of the map (its streams, leases, ids)")
    _common(r)
    r.add_argument("--yes", action="store_true", help="really delete")
    r.set_defaults(func=run_reset)
    p.set_defaults(func=lambda args: p.print_help() or 2)


def _open(args: argparse.Namespace):
    from worldtrack.map.config import map_settings
    from worldtrack.map.connection import MapKeys, check_url, connect, redacted
    cfg = map_settings(args.config, args.sets)
    return cfg, connect(check_url(args.url)), MapKeys(cfg.prefix), redacted(args.url)


def run_status(args: argparse.Namespace) -> int:
    import json

    from worldtrack.map.status import format_status, map_status
    cfg, client, keys, where = _open(args)
    status = map_status(client, keys)
    print(json.dumps(status, default=str) if args.json else format_status(status, where))
    return 0


def run_fuse(args: argparse.Namespace) -> int:
    from worldtrack.interrupts import StopRequests
    from worldtrack.map.fusion_role import DRAIN_S, FusionRole
    from worldtrack.map.lease import worker_name
    cfg, client, keys, where = _open(args)
    name = worker_name()
    role = FusionRole(client, keys, cfg, name, log=lambda s: print(f"{name}: {s}", file=sys.stderr, flush=True))
    stop, done = threading.Event(), threading.Event()

    def serve() -> None:
        try:
            role.run(stop)
        finally:
            done.set()
    th = threading.Thread(target=serve, name="fusion", daemon=True)
    print(f"{name}: contending for the fusion role of {where}", file=sys.stderr, flush=True)
    t_end = None if args.seconds is None else time.monotonic() + args.seconds
    # Ctrl-C / SIGTERM only set a flag (StopRequests): a KeyboardInterrupt landing in Thread.join
    # makes Python 3.11 take the thread for finished while it still writes. The holder then writes
    # what it has for at most DRAIN_S and gives the role back; the process exits (130 / 143) with the
    # record intact up to its last bucket. A second signal stops at once.
    with StopRequests() as requests:
        th.start()
        while not done.is_set() and not requests.requested and (t_end is None or time.monotonic() < t_end):
            done.wait(0.1)
        stop.set()
        done.wait(DRAIN_S + 1.0)
    s = role.stats
    print(f"{name}: {s.buckets} map states written, {s.observations} observations read, {s.late} late, "
          f"{s.malformed} malformed", file=sys.stderr)
    if requests.requested:
        raise requests.interrupt()
    return 0


def run_start(args: argparse.Namespace) -> int:
    from worldtrack.map.timings import set_epoch
    cfg, client, keys, where = _open(args)
    epoch = set_epoch(client, keys, args.lead, cfg.bucket_s)
    print(f"{where}: video files play from {epoch:.3f} (in {args.lead:g} s)", file=sys.stderr)
    return 0


def run_reset(args: argparse.Namespace) -> int:
    cfg, client, keys, where = _open(args)
    if not args.yes:
        raise InputError(f"map reset deletes every key under {cfg.prefix!r} on {where}: add --yes")
    doomed = list(client.scan_iter(match=f"{cfg.prefix}:*", count=1000))
    if doomed:
        client.delete(*doomed)
    print(f"{where}: deleted {len(doomed)} keys under {cfg.prefix!r}", file=sys.stderr)
    return 0
