"""``worldtrack serve``: a live floor-plan view in the browser, of a finished run or of the shared map."""

from __future__ import annotations

import argparse
import os
import sys

from worldtrack.errors import InputError


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "serve", help="a floor-plan view in the browser: a finished run (worldtrack serve out/) or the live map",
        description="Serve a web page with the floor plan of the scene and the people on it: a finished run "
                    "(its tracks.csv, run.yaml and scene; a timeline to scrub and play) or, with --map, the "
                    "shared map on Redis as it is written. Binds 127.0.0.1:8000 by default; bound to any other "
                    "address it requires a token on every request (--token, WORLDTRACK_SERVE_TOKEN, or a "
                    "random one printed with the URL).")
    p.add_argument("run", nargs="?", default=None, metavar="DIR",
                   help="a finished run's output folder (worldtrack track --out DIR)")
    p.add_argument("--map", metavar="URL", default=None,
                   help="the live shared map instead: redis://[USER:PASSWORD@]HOST[:PORT][/DB] or rediss://…")
    p.add_argument("--scene", default=None, help="the scene file (live: required, it must be the map's scene; "
                                                 "a finished run: default the one run.yaml names)")
    p.add_argument("--host", default="127.0.0.1", help="address to listen on (default 127.0.0.1: this machine only)")
    p.add_argument("--port", type=int, default=8000, help="port (default 8000)")
    p.add_argument("--token", default=None, help="the token the page requires (default: WORLDTRACK_SERVE_TOKEN; "
                                                 "required, and made up if missing, when --host is not loopback)")
    p.add_argument("--trail", type=float, default=10.0, metavar="S", help="trail length in seconds (default 10)")
    p.add_argument("--frames", action="store_true",
                   help="a finished run: offer each camera's annotated frame as JPEG (off by default)")
    p.add_argument("--config", metavar="YAML", default=None, help="settings file (its map: section; live)")
    p.add_argument("--set", action="append", default=[], metavar="map.NAME=VALUE", dest="sets",
                   help="one map setting, e.g. map.prefix=floor2 (repeatable; live)")
    p.add_argument("--verbose", action="store_true", help="log every request")
    p.set_defaults(func=run)


def _run_source(args: argparse.Namespace):
    from worldtrack.serve.app import PageSource
    from worldtrack.serve.run import load_run
    if args.config or args.sets:
        raise InputError("--config/--set are for the live map (--map)")
    run = load_run(args.run, args.scene)
    frames = None
    if args.frames:
        from worldtrack.serve.frames import AnnotatedFrames
        frames = AnnotatedFrames(run.folder, run.cameras)
    return PageSource("run", run.scene, f"{run.scene.name} — {run.folder}", args.trail, run=run, frames=frames)


def _live_source(args: argparse.Namespace):
    import json

    from worldtrack.map.config import map_settings
    from worldtrack.map.connection import MapKeys, check_url, connect, redacted, scene_digest
    from worldtrack.map.replay import read_states
    from worldtrack.scene import load_scene
    from worldtrack.serve.app import PageSource
    from worldtrack.serve.live import LiveMap
    if args.frames:
        raise InputError("--frames: the shared map carries no images; frames are offered for a finished run")
    if not args.scene:
        raise InputError("--map: give the map's scene file with --scene (the map stores only its hash)")
    cfg = map_settings(args.config, args.sets)
    scene = load_scene(args.scene)
    client = connect(check_url(args.map))
    keys = MapKeys(cfg.prefix)
    theirs = json.loads(client.get(keys.scene) or "{}")
    if theirs and theirs.get("sha256") != scene_digest(args.scene):
        raise InputError(f"--scene {args.scene}: the map belongs to scene {theirs.get('name')!r} "
                         f"(sha256 {str(theirs.get('sha256'))[:12]}…), not this one")

    def history(pid: int, seconds: float) -> list:
        import time
        now = time.time()
        return [[round(s.t, 3), round(p.x, 3), round(p.y, 3), p.mode]
                for s in read_states(client, keys, now - seconds, None) for p in s.people if p.id == pid]

    return PageSource("live", scene, f"{scene.name} — {redacted(args.map)}", args.trail,
                      live=lambda publish: LiveMap(client, keys, scene, publish, trail_s=args.trail),
                      history=history)


def run(args: argparse.Namespace) -> int:
    try:
        from worldtrack.serve.app import make_app
    except ImportError as e:
        raise InputError(f"serve needs its web parts ({e.name}): pip install 'worldtrack[serve]'") from None
    from worldtrack.serve.server import TOKEN_ENV, bind, is_loopback, resolve_token, run_server
    if args.run and args.map:
        raise InputError("give a run folder or --map URL, not both")
    if not args.run and not args.map:
        raise InputError("give a finished run's folder (worldtrack serve out/) or the live map (--map redis://…)")
    if args.trail <= 0:
        raise InputError(f"--trail: expected seconds > 0, got {args.trail}")
    source = _run_source(args) if args.run else _live_source(args)   # the user's inputs first, then the port
    sock = bind(args.host, args.port)
    token = resolve_token(args.host, args.token)
    host = f"[{args.host}]" if ":" in args.host else args.host
    url = f"http://{host}:{sock.getsockname()[1]}/"
    if token and not (args.token or os.environ.get(TOKEN_ENV)):
        print(f"token (made up now; set {TOKEN_ENV} or --token to choose one): {token}", file=sys.stderr)
    if not is_loopback(args.host):
        print("warning: reachable from the network; every request needs the token", file=sys.stderr)
    print(f"serving {source.title} on {url}{'?token=' + token if token else ''}  (Ctrl-C to stop)",
          file=sys.stderr, flush=True)
    run_server(make_app(source, token), sock, quiet=not args.verbose)
    return 0


__all__ = ["register", "run"]
