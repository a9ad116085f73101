"""What the shared-map benchmarks share: a private redis-server, worker processes, percentiles.

The server is Debian's ``redis-server`` on a free 127.0.0.1 port without persistence; workers are
``worldtrack track --map`` processes (one camera each) that wait for ``worldtrack map start``.
"""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

WORLDTRACK = [sys.executable, "-c", "import sys; from worldtrack.cli import main; sys.exit(main())"]


class Server:
    """A redis-server of our own (stopped by :meth:`stop`)."""

    def __init__(self, workdir: Path):
        exe = shutil.which("redis-server")
        if exe is None:
            sys.exit("redis-server is not installed (apt-get install redis-server); skipped")
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            self.port = s.getsockname()[1]
        self.proc = subprocess.Popen([exe, "--port", str(self.port), "--bind", "127.0.0.1", "--save", "",
                                      "--appendonly", "no", "--dir", str(workdir)],
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        import redis
        for _ in range(200):
            try:
                redis.Redis(port=self.port).ping()
                break
            except redis.ConnectionError:
                time.sleep(0.05)
        self.url = f"redis://127.0.0.1:{self.port}/0"

    def flush(self) -> None:
        import redis
        redis.Redis(port=self.port).flushall()

    def stop(self) -> None:
        self.proc.terminate()
        self.proc.wait(10)


def run_workers(scene_dir: Path, url: str, cameras: list[str], out: Path, sets: list[str] = (),
                timeout: float = 600.0) -> float:
    """Run one worker per camera on the scenario in ``scene_dir`` until its videos end; returns the
    wall time (s) from ``map start`` to the last worker's exit."""
    import redis
    out.mkdir(parents=True, exist_ok=True)
    client = redis.Redis.from_url(url, decode_responses=True)
    procs = []
    for cam in cameras:
        log = open(out / f"{cam}.log", "w")
        cmd = [*WORLDTRACK, "track", str(scene_dir / "scene.yaml"), "--map", url, "--cameras", cam,
               "--video", f"{cam}={scene_dir / (cam + '.mp4')}", "--out", str(out / cam), "--quiet", "--no-video",
               "--set", "map.wait_for_start=true", *[a for s in sets for a in ("--set", s)]]
        procs.append(subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=log,
                                      env={**os.environ, "PYTHONUNBUFFERED": "1"}))
    deadline = time.monotonic() + timeout
    while not all(client.get(f"worldtrack:lease:camera:{c}") for c in cameras):
        if time.monotonic() > deadline or any(p.poll() is not None for p in procs):
            raise RuntimeError(f"workers did not start; see {out}/*.log")
        time.sleep(0.1)
    subprocess.run([*WORLDTRACK, "map", "start", url, "--in", "0.5"], check=True, capture_output=True)
    t0 = time.time()
    for p in procs:
        p.wait(max(1.0, deadline - time.monotonic()))
    bad = [c for c, p in zip(cameras, procs) if p.returncode != 0]
    if bad:
        raise RuntimeError(f"worker {bad[0]} failed: {(out / (bad[0] + '.log')).read_text()[-500:]}")
    return time.time() - t0


def percentiles(values, qs=(50, 99)) -> list[float]:
    v = np.asarray(list(values), float)
    return [float(np.percentile(v, q)) if len(v) else float("nan") for q in qs]


def load_average() -> str:
    try:
        return " ".join(f"{x:.1f}" for x in os.getloadavg())
    except OSError:
        return "?"
