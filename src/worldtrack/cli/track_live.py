"""``worldtrack track`` with live cameras and/or a shared map (``--map redis://… --cameras …``).

A worker connects to the map (and refuses a map of another scene), builds its tracker, waits as a
standby while another worker holds its cameras, then tracks them: frames come from grab threads
(:mod:`worldtrack.io.live`), each step is synchronised with the map and published
(:mod:`worldtrack.map.worker`), and a fusion thread takes the fusion role whenever it is free
(:mod:`worldtrack.map.fusion_role`). The local outputs (``tracks.csv``, videos, floor plan, run.yaml)
are written as in any run; the shared ones come from ``worldtrack replay``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import threading
import time
from pathlib import Path

from worldtrack.errors import InputError


def _say(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


def _backgrounds(args: argparse.Namespace, scene, sources: dict) -> dict:
    """Background images given or found for the cameras; live cameras without one are left out
    (estimated from their first frames once the stream is open)."""
    from worldtrack.cli.track import _pair
    from worldtrack.io.live import is_live
    from worldtrack.io.sources import background_from_video, read_image
    explicit = dict(_pair(b, "--background") for b in args.background)
    out = {}
    for cid, src in sources.items():
        cam = scene.camera(cid)
        if cid in explicit:
            out[cid] = read_image(explicit[cid], cam, "background")
        elif not is_live(src):
            guess = Path(str(src)).parent / f"{cid}_background.png"
            out[cid] = read_image(guess, cam, "background") if guess.is_file() else background_from_video(src)
    return out


def warm_up(cfg, scene, backgrounds: dict) -> float:
    """Step a throw-away tracker over a few made-up frames (a dark box where a person would stand in
    each camera's view) so that its compiled kernels are loaded before the cameras' clock runs:
    the first real frame then takes milliseconds, not seconds. Returns the seconds it took."""
    import cv2
    import numpy as np

    from worldtrack.foreground import foregrounds_from_config
    from worldtrack.trackers import make_tracker
    from worldtrack.trackers.base import Frame
    t0 = time.perf_counter()
    tracker = make_tracker(cfg.method, scene, foregrounds_from_config(scene, backgrounds, cfg.foreground),
                           cfg.section())
    frames = {}
    for cid, bg in backgrounds.items():
        cam = scene.camera(cid)
        img = bg.copy()
        floor = cam.backproject(np.array([[cam.width / 2, cam.height * 0.7]]), 0.0)[0]
        feet, head = cam.project(np.array([[floor[0], floor[1], 0.0], [floor[0], floor[1], 1.7]]))
        if np.isfinite(feet).all() and np.isfinite(head).all():
            half = max(2, int(abs(feet[1] - head[1]) * 0.15))
            cv2.rectangle(img, (int(feet[0]) - half, int(min(head[1], feet[1]))),
                          (int(feet[0]) + half, int(max(head[1], feet[1]))), (25, 25, 25), -1)
        frames[cid] = img
    for i in range(4):
        tracker.step({c: Frame(img, i * 0.1, i) for c, img in frames.items()}, i * 0.1)
    return time.perf_counter() - t0


class _Worker:
    """The map side of a run: connection, link, leases, fusion thread, heartbeat."""

    def __init__(self, args: argparse.Namespace, cfg, scene, cameras: list[str], fps: float):
        from worldtrack.map.connection import MapKeys, check_url, claim_scene, connect, redacted, scene_digest
        from worldtrack.map.fusion_role import FusionRole
        from worldtrack.map.lease import worker_name
        from worldtrack.map.starved import name_connection
        from worldtrack.map.worker import MapLink
        self.where = redacted(check_url(args.map))
        self.cfg = cfg.stage("map")
        self.client = connect(args.map)
        self.keys = MapKeys(self.cfg.prefix)
        claim_scene(self.client, self.keys, scene_digest(args.scene), scene.name, args.map)
        self.name = worker_name()
        name_connection(self.client, self.name)     # the fusion tells this worker starved from dead by it
        self.link = MapLink(self.client, self.keys, self.cfg, self.name, {c: scene.camera(c) for c in cameras}, fps,
                            occlusion={c: scene.occlusion(c).floor_distance for c in cameras},
                            scene_cameras=list(scene.cameras))
        self.link.register()
        self.fusion = FusionRole(self.client, self.keys, self.cfg, self.name, log=lambda s: _say(f"{self.name}: {s}"))
        self.stop = threading.Event()
        self.state = "standby"
        self.source = None
        self.frames = 0
        if self.cfg.fusion_in_worker:
            threading.Thread(target=self.fusion.run, args=(self.stop,), name="fusion", daemon=True).start()
        self.keeper = None

    def beat(self) -> None:
        stats = self.source.stats() if self.source is not None else {}
        now = time.time()
        last = self.link.last_capture
        self.client.hset(self.keys.workers, self.name, json.dumps({
            "cameras": sorted(self.link.cameras), "state": self.state, "fusion": self.fusion.holding,
            "frames": self.frames, "dropped": sum(s.dropped for s in stats.values()),
            "reconnects": sum(s.reconnects for s in stats.values()),
            "lag_s": None if last is None else round(now - last, 3), "t": now, "pid": os.getpid()}))

    def wait_for_cameras(self) -> None:
        """Block (as a standby) until this worker holds all its cameras."""
        from worldtrack.map.lease import LeaseKeeper, acquire_all
        leases = list(self.link.leases.values())
        self.keeper = LeaseKeeper([], self.cfg.renew_s, self._lost, beat=self.beat)
        self.keeper.start()
        t0, said = time.time(), False
        while not acquire_all(leases):
            if not said:
                held = {c: le.holder()[0] for c, le in self.link.leases.items()}
                _say(f"{self.name}: standby for {', '.join(self.link.cameras)} (held: "
                     + ", ".join(f"{c} by {h}" for c, h in held.items() if h) + ")")
                said = True
            time.sleep(self.cfg.renew_s / 2)
        self.keeper.leases.extend(leases)
        self.state = "tracking"
        _say(f"{self.name}: owns {', '.join(self.link.cameras)} on {self.where}"
             + (f" (after {time.time() - t0:.2f} s as standby)" if said else ""))

    def _lost(self, lease) -> None:
        _say(f"{self.name}: lost the lease {lease.key}")

    def close(self) -> None:
        self.state = "stopped"
        self.stop.set()
        if self.link.lockstep:          # the run's end, not a starved batch worker: not waited for
            self.link.lockstep = False
            try:
                self.link.register()
            except Exception:
                pass
        if self.keeper is not None:
            self.keeper.stop(release=True)
        from worldtrack.map.fusion_role import DRAIN_S
        deadline = time.time() + DRAIN_S + 0.5
        while self.fusion.holding and time.time() < deadline:
            time.sleep(0.02)
        try:
            self.client.hdel(self.keys.workers, self.name)
        except Exception:
            pass


def run_live(args: argparse.Namespace, cfg) -> int:
    """``worldtrack track`` on live cameras and/or a shared map; returns the exit status."""
    from worldtrack.cli.track import _init, _pair
    from worldtrack.foreground import foregrounds_from_config
    from worldtrack.io.live import LiveSource, background_from_live, check_source, is_live, parse_source
    from worldtrack.io.runinfo import write_run_info
    from worldtrack.pipeline import run_tracking
    from worldtrack.scene import load_scene
    from worldtrack.trackers import make_tracker
    import worldtrack.io.video, worldtrack.viz.floorplan, worldtrack.viz.overlay  # noqa: E401,F401  (not later: on a
    # shared map the clock runs from when the cameras are taken)

    scene = load_scene(args.scene)
    videos = dict(_pair(v, "--video") for v in args.video)
    own = [c.strip() for c in args.cameras.split(",") if c.strip()] if args.cameras else list(videos)
    if args.cameras and not args.map:
        raise InputError("--cameras is for a worker of a shared map: give --map redis://HOST:PORT/DB too")
    for c in own:
        scene.camera(c)
        if c not in videos:
            raise InputError(f"--cameras {c}: give its video or stream with --video {c}=…")
    sources = {c: parse_source(videos[c]) for c in own}
    for c, s in sources.items():
        check_source(c, s)
    backgrounds = _backgrounds(args, scene, sources)
    worker = _Worker(args, cfg, scene, own, args.fps or 10.0) if args.map else None
    timings_file = None
    try:
        position_map = None
        if worker is not None:
            from worldtrack.map.shared_ids import SharedPositionMap
            position_map = SharedPositionMap(worker.link.new_id)

        def build(backgrounds):
            return make_tracker(cfg.method, scene, foregrounds_from_config(scene, backgrounds, cfg.foreground),
                                cfg.section(), position_map=position_map)
        # Built before taking the cameras: a standby is ready when it takes over.
        tracker = build(backgrounds) if len(backgrounds) == len(sources) else None
        if tracker is not None:
            _say(f"tracker ready (kernels loaded in {warm_up(cfg, scene, backgrounds):.1f} s)")
        if worker is not None:
            worker.wait_for_cameras()
        if worker is not None and worker.cfg.wait_for_start and not all(is_live(s) for s in sources.values()):
            _say(f"{worker.name}: waiting for `worldtrack map start` to play the video files")
        epoch = worker.link.epoch(wait=worker.cfg.wait_for_start) if worker is not None else time.time()
        pace = worker.cfg.pace_files if worker is not None else False
        source = LiveSource(sources, scene.cameras, fps=args.fps, epoch=epoch, pace=pace, stop=args.frames)
        source.start()
        if worker is not None:
            worker.source = source
            worker.link.fps = source.fps
            worker.link.lockstep = not pace and not source.live
            worker.link.register()
        missing = [c for c in sources if c not in backgrounds]
        if missing:
            _say(f"{', '.join(missing)}: no background image given; estimating it from the first frames")
            live_bg = background_from_live(source)
            backgrounds.update({c: live_bg[c] for c in missing})
            tracker = build(backgrounds)
        for text in args.init:
            tid, x, y = _init(text)
            tracker.init_track(x, y, track_id=tid)
        if worker is not None:
            from worldtrack.map.timings import StepTimings
            from worldtrack.map.map_tracker import MapTracker

            def stepped(t: float) -> None:
                worker.frames += 1
            Path(args.out).mkdir(parents=True, exist_ok=True)
            timings_file = open(Path(args.out) / "map_timings.csv", "w", buffering=1)
            tracker = MapTracker(tracker, worker.link, on_step=stepped, timings=StepTimings(timings_file))
        from worldtrack.map.connection import hide_passwords
        argv = [hide_passwords(a) for a in (getattr(args, "command_line", None) or sys.argv)]
        write_run_info(Path(args.out), cfg.to_mapping(), inputs={
            "scene": args.scene, "videos": {c: hide_passwords(str(v)) for c, v in videos.items()},
            "map": worker.where if worker else None, "cameras": own, "init": list(args.init),
            "fps": args.fps, "frames": args.frames}, argv=argv)
        result = run_tracking(scene, source, tracker, args.out, write_video=not args.no_video,
                              json_stream=sys.stdout if args.json else None, progress=not args.quiet,
                              show_ring=args.show_ring)
    finally:
        if timings_file is not None:
            timings_file.close()
        if worker is not None:
            worker.close()
    for cid, s in source.stats().items():
        _say(f"{cid}: {s.frames} frames grabbed, {s.dropped} dropped, {s.reconnects} reconnects, "
             f"{s.outage_s:.1f} s without signal")
    if worker is not None:
        confirmed = worker.link.exchange.confirmed if worker.link.exchange is not None else 0
        _say(f"{worker.name}: {worker.link.handed_over} people taken from the map before they entered its "
             f"views, {worker.link.claimed} new people took a map id, {confirmed} confirmed on another worker's view")
    _say(f"{result.frames} frames in {result.seconds:.1f} s ({result.fps:.1f} frames/s), "
         f"{len(result.track_ids)} tracks; tracks: {result.tracks_csv}")
    if result.error:
        raise InputError(result.error + f" (outputs up to frame {result.frames - 1} kept in {result.out_dir})")
    if result.interrupted:
        raise KeyboardInterrupt
    return 0
