"""Helpers of the shared-map tests: a real ``redis-server``, workers as processes, waiting."""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

WORLDTRACK = [sys.executable, "-c", "import sys; from worldtrack.cli import main; sys.exit(main())"]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class RedisServer:
    """One ``redis-server`` process (no persistence) on 127.0.0.1."""

    def __init__(self, workdir: Path, extra: tuple[str, ...] = ()):
        exe = shutil.which("redis-server")
        if exe is None:
            pytest.skip("redis-server is not installed (make test installs it: apt-get install redis-server)")
        self.port = free_port()
        self.proc = subprocess.Popen([exe, "--port", str(self.port), "--bind", "127.0.0.1", "--save", "",
                                      "--appendonly", "no", "--dir", str(workdir), *extra],
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        import redis
        deadline = time.monotonic() + 10
        while True:
            try:
                redis.Redis(port=self.port, socket_timeout=1).ping()
                break
            except redis.AuthenticationError:
                break
            except redis.ResponseError:      # NOAUTH: it is up, and wants a password
                break
            except redis.ConnectionError:
                if time.monotonic() > deadline or self.proc.poll() is not None:
                    raise RuntimeError("redis-server did not start")
                time.sleep(0.05)

    @property
    def url(self) -> str:
        return f"redis://127.0.0.1:{self.port}/0"

    def stop(self) -> None:
        self.proc.terminate()
        try:
            self.proc.wait(5)
        except subprocess.TimeoutExpired:
            self.proc.kill()


def worker(scene_dir: Path, url: str, camera: str, out: Path, *extra: str) -> subprocess.Popen:
    """A ``worldtrack track --map`` worker for one camera of the scenario, as its own process."""
    cmd = [*WORLDTRACK, "track", str(scene_dir / "scene.yaml"), "--map", url, "--cameras", camera,
           "--video", f"{camera}={scene_dir / (camera + '.mp4')}", "--out", str(out), "--quiet", "--no-video",
           "--set", "map.wait_for_start=true", *extra]
    log = open(out.parent / f"{out.name}.log", "w")
    return subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=log, env={**os.environ, "PYTHONUNBUFFERED": "1"})


def wait_until(condition, timeout: float, every: float = 0.05, what: str = "condition"):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = condition()
        if value:
            return value
        time.sleep(every)
    raise AssertionError(f"timed out after {timeout} s waiting for {what}")
