"""Helpers of the ``worldtrack serve`` tests: the server as its own process, the browser's view of the people."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "map"))
from _mapkit import RedisServer, free_port  # noqa: E402,F401

WORLDTRACK = [sys.executable, "-c", "import sys; from worldtrack.cli import main; sys.exit(main())"]


def chromium_path() -> str | None:
    for name in ("chromium", "chromium-browser"):
        exe = shutil.which(name)
        if exe:
            return exe
    return None


class Server:
    """``worldtrack serve …`` as its own process on a free port of 127.0.0.1."""

    def __init__(self, *args: str, host: str = "127.0.0.1", token: str | None = None, env: dict | None = None,
                 timeout: float = 30.0):
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}/"
        self.token = token
        cmd = [*WORLDTRACK, "serve", *args, "--host", host, "--port", str(self.port)]
        if token:
            cmd += ["--token", token]
        self.proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                                     env={**os.environ, **(env or {})})
        deadline = time.monotonic() + timeout
        while True:
            try:
                urllib.request.urlopen(self.url + "api/plan" + (f"?token={token}" if token else ""), timeout=2)
                return
            except urllib.error.HTTPError:
                return                       # up (answering 401 or similar)
            except OSError:
                if self.proc.poll() is not None:
                    raise RuntimeError(f"worldtrack serve exited: {self.proc.stderr.read()}")
                if time.monotonic() > deadline:
                    self.stop()
                    raise RuntimeError("worldtrack serve did not start")
                time.sleep(0.1)

    def stop(self) -> str:
        self.proc.terminate()
        try:
            _, err = self.proc.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            _, err = self.proc.communicate()
        return err


#: Every person's dot centre in SVG user units, as the browser lays it out (screen → SVG by the
#: SVG's own screen matrix, so the page's CSS size does not matter).
DOTS_JS = """() => {
  const inv = document.getElementById('plan').getScreenCTM().inverse();
  return [...document.querySelectorAll('#people .person')].map(g => {
    const r = g.querySelector('.dot').getBoundingClientRect();
    const p = new DOMPoint(r.x + r.width / 2, r.y + r.height / 2).matrixTransform(inv);
    return {id: +g.dataset.id, u: p.x, v: p.y, cls: g.getAttribute('class')};
  });
}"""


def open_page(page, url: str) -> None:
    """Load the page and wait until it has drawn the plan and the people."""
    page.goto(url)
    page.wait_for_function("window.worldtrack && window.worldtrack.ready", timeout=20000)
