"""Fixtures of the ``worldtrack serve`` tests: a finished synthetic run, the server as its own
process, and a real browser (Debian's ``chromium`` driven by Playwright; ``make test`` installs
it; no browser is downloaded at run time). Without chromium or Playwright the browser tests are
skipped with one line saying so; the live-map test uses the real ``redis-server`` of the map tests.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from _servekit import RedisServer, Server, chromium_path


@pytest.fixture(scope="session")
def browser():
    pytest.importorskip("starlette")
    sync_api = pytest.importorskip("playwright.sync_api")
    exe = chromium_path()
    if exe is None:
        pytest.skip("chromium is not installed (make test installs it: apt-get install chromium)")
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=exe, args=["--no-sandbox", "--disable-gpu"])
        yield b
        b.close()


@pytest.fixture
def page(browser):
    context = browser.new_context(viewport={"width": 1400, "height": 900})
    pg = context.new_page()
    errors: list[str] = []
    pg.on("pageerror", lambda e: errors.append(str(e)))
    yield pg
    context.close()
    assert not errors, f"JavaScript errors on the page: {errors}"


@pytest.fixture(scope="session")
def finished_run(tmp_path_factory) -> Path:
    """A real run: the crowd scenario (4 people, 2 corner cameras, 30 frames, 320x240) tracked by
    ``worldtrack track --method blobs`` with annotated videos."""
    from worldtrack.cli import main
    base = tmp_path_factory.mktemp("serve_run")
    assert main(["synth", "crowd", "--set", "people=4", "--set", "cameras=2", "--frames", "30", "--size", "320x240",
                 "--seed", "3", "--out", str(base / "syn"), "--no-progress"]) == 0
    assert main(["track", str(base / "syn" / "scene.yaml"), "--video", f"c1={base / 'syn' / 'c1.mp4'}",
                 "--video", f"c2={base / 'syn' / 'c2.mp4'}", "--method", "blobs", "--out", str(base / "run"),
                 "--quiet"]) == 0
    mark_unmeasurable(base / "run" / "tracks.csv")
    return base / "run"


def mark_unmeasurable(path) -> tuple[int, int]:
    """Flag one row of the middle frame ``unmeasurable`` (as the ellipsoid tracker flags a person
    whose body no camera shows enough of; the blobs tracker never does): returns (frame, id)."""
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    rows = [line.split(",") for line in lines[1:]]
    frames = sorted({int(r[header.index("frame")]) for r in rows})
    k = next(i for i, r in enumerate(rows) if int(r[header.index("frame")]) == frames[len(frames) // 2])
    rows[k][header.index("flags")] = "unmeasurable"
    path.write_text("\n".join([lines[0], *(",".join(r) for r in rows)]) + "\n")
    return int(rows[k][header.index("frame")]), int(rows[k][header.index("id")])


@pytest.fixture(scope="session")
def run_server(finished_run):
    pytest.importorskip("starlette")
    server = Server(str(finished_run), "--frames", "--trail", "2")
    yield server
    server.stop()


@pytest.fixture(scope="session")
def redis_server(tmp_path_factory):
    pytest.importorskip("redis")
    server = RedisServer(tmp_path_factory.mktemp("redis_serve"))
    yield server
    server.stop()
