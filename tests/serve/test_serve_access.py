"""Who may look: 401 without the token when bound beyond loopback (HTTP and websocket); one-line
errors with exit status 2 for a missing folder, a port in use, an unreachable map."""

from __future__ import annotations

import asyncio
import socket
import urllib.error
import urllib.request
from typing import Any

import pytest

from _servekit import Server, free_port
from worldtrack.cli import main

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


def status(url: str, headers: dict | None = None) -> tuple[int, Any]:
    try:
        with urllib.request.urlopen(urllib.request.Request(url, headers=headers or {}), timeout=5) as r:
            return r.status, r.headers
    except urllib.error.HTTPError as e:
        return e.code, e.headers


def ws_status(url: str, headers: dict | None = None) -> int:
    """The HTTP status of a websocket handshake (101 when accepted)."""
    import websockets

    async def go():
        try:
            async with websockets.connect(url, additional_headers=headers or {}, open_timeout=5):
                return 101
        except websockets.exceptions.InvalidStatus as e:
            return e.response.status_code
    return asyncio.run(go())


def test_beyond_loopback_every_request_needs_the_token(finished_run):
    pytest.importorskip("websockets")
    server = Server(str(finished_run), host="0.0.0.0", token="s3cret-token")
    try:
        base = server.url
        for path in ("", "api/plan", "api/run", "static/app.js", "api/frame/c1/3"):
            code, headers = status(base + path)
            assert code == 401, f"/{path} without the token: {code}"
            assert headers.get("WWW-Authenticate") == "Bearer"
        assert status(base + "api/plan?token=wrong")[0] == 401
        assert status(base + "api/plan", {"Authorization": "Bearer wrong"})[0] == 401
        ws = base.replace("http", "ws") + "ws"
        assert ws_status(ws) == 401
        code, headers = status(base + "?token=s3cret-token")                   # the link the server prints
        assert code == 200 and "HttpOnly" in headers.get("set-cookie", "")
        cookie = headers["set-cookie"].split(";")[0]
        assert status(base + "api/run", {"Cookie": cookie})[0] == 200           # the page's own requests
        assert status(base + "api/plan", {"Authorization": "Bearer s3cret-token"})[0] == 200
        assert ws_status(ws, {"Cookie": cookie}) == 101
    finally:
        err = server.stop()
    assert "?token=s3cret-token" in err and "reachable from the network" in err


def test_the_token_rule():
    from worldtrack.serve.server import is_loopback, resolve_token
    assert resolve_token("127.0.0.1", None, env={}) is None                      # loopback: none needed
    assert resolve_token("::1", None, env={"WORLDTRACK_SERVE_TOKEN": "abc"}) == "abc"
    assert resolve_token("0.0.0.0", "mine", env={"WORLDTRACK_SERVE_TOKEN": "abc"}) == "mine"
    made_up = {resolve_token("0.0.0.0", None, env={}) for _ in range(3)}
    assert len(made_up) == 3 and all(len(t) >= 20 for t in made_up)             # random, long
    assert resolve_token("10.1.2.3", None, env={"WORLDTRACK_SERVE_TOKEN": ""}) not in (None, "")
    assert not is_loopback("192.168.1.5") and not is_loopback("example.org") and is_loopback("127.0.0.2")


def test_loopback_needs_no_token(run_server):
    assert status(run_server.url + "api/plan")[0] == 200
    assert status(run_server.url + "api/frame/c1/0")[0] == 200
    assert status(run_server.url + "api/frame/c9/0")[0] == 404


@pytest.mark.parametrize("args, message", [
    (["serve", "{tmp}/nothing"], "error: {tmp}/nothing: no such folder"),
    (["serve", "{tmp}"], "error: {tmp}: no tracks.csv in it"),
    (["serve"], "error: give a finished run's folder"),
    (["serve", "--map", "redis://127.0.0.1:{free}/0", "--scene", "{scene}"],
     "error: redis://127.0.0.1:{free}/0: cannot reach the map"),
    (["serve", "--map", "redis://127.0.0.1:{free}/0"], "error: --map: give the map's scene file with --scene"),
    (["serve", "{run}", "--port", "{busy}"], "error: port {busy} on 127.0.0.1 is in use"),
])
def test_mistakes_give_one_line_and_exit_2(args, message, tmp_path, finished_run, capsys):
    pytest.importorskip("starlette")
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen(1)
        values = {"tmp": tmp_path, "free": free_port(), "scene": finished_run.parent / "syn" / "scene.yaml",
                  "run": finished_run, "busy": busy.getsockname()[1]}
        assert main([a.format(**values) for a in args]) == 2
    err = capsys.readouterr().err
    assert err.startswith(message.format(**values)), err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
