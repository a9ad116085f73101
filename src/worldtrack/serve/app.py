"""The web app: a Starlette ASGI application serving the page, the plan, the run and the live map.

Routes (all ``GET``; nothing can be changed through the page):

* ``/`` — the page (``static/index.html``, plain HTML/SVG/JS shipped in the package, no CDN);
* ``/api/plan`` — the scene in SVG pixels (:func:`worldtrack.serve.plan.plan_json`), the mode and
  what the page offers;
* ``/api/run`` — a finished run's timeline (:func:`worldtrack.serve.run.timeline_json`);
* ``/api/history/<id>`` — live: one person's path over the last ``history_s`` from the map stream;
* ``/api/frame/<camera>/<frame>`` — an annotated frame as JPEG (only with ``--frames``);
* ``/ws`` — live: a websocket that pushes every map state and the camera status as JSON text.

With a ``token`` every request and websocket must carry it: ``Authorization: Bearer TOKEN``, the
query ``?token=TOKEN`` (opening the page that way also sets an HttpOnly, SameSite=Strict cookie,
so the page's own requests carry it), or that cookie. Anything else gets 401 (a websocket's
handshake too, where the server supports denial responses; else it is closed with 1008).
"""

from __future__ import annotations

import asyncio
import contextlib
import hmac
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs

from starlette.applications import Starlette
from starlette.responses import FileResponse, JSONResponse, PlainTextResponse, Response
from starlette.routing import Mount, Route, WebSocketRoute
from starlette.staticfiles import StaticFiles
from starlette.websockets import WebSocket, WebSocketDisconnect

from worldtrack.scene.model import Scene

STATIC = Path(__file__).resolve().parent / "static"
COOKIE = "worldtrack_token"
#: Messages a slow browser may fall behind by before the oldest are dropped (about 3 s of map states).
QUEUE_MESSAGES = 32


@dataclass
class PageSource:
    """What the page shows: a finished run (``mode="run"``) or the live map (``mode="live"``).

    ``live`` is a callable ``publish -> LiveMap`` (started with the app, stopped with it);
    ``history`` a callable ``(id, seconds) -> list`` for the live person history.
    """

    mode: str
    scene: Scene
    title: str
    trail_s: float = 10.0
    run: Any = None
    live: Any = None
    history: Any = None
    frames: Any = None
    _cache: dict[str, bytes] = field(default_factory=dict)

    def cached(self, name: str, make) -> bytes:
        if name not in self._cache:
            self._cache[name] = json.dumps(make(), separators=(",", ":"), allow_nan=False).encode()
        return self._cache[name]


class Hub:
    """Fan-out of the live messages (JSON text) to every connected browser; thread-safe publish."""

    def __init__(self) -> None:
        self.loop: asyncio.AbstractEventLoop | None = None
        self.queues: set[asyncio.Queue] = set()
        self.dropped = 0

    def publish(self, text: str) -> None:
        """Called from any thread."""
        if self.loop is not None and not self.loop.is_closed():
            self.loop.call_soon_threadsafe(self._fan_out, text)

    def _fan_out(self, text: str) -> None:
        for q in self.queues:
            if q.full():
                q.get_nowait()
                self.dropped += 1
            q.put_nowait(text)


class TokenGate:
    """ASGI middleware: 401 for every HTTP request and websocket without the token."""

    def __init__(self, app, token: str | None):
        self.app, self.token = app, token

    def _given(self, scope) -> tuple[str | None, bool]:
        headers = {k.decode("latin-1").lower(): v.decode("latin-1") for k, v in scope.get("headers", [])}
        query = parse_qs(scope.get("query_string", b"").decode("latin-1")).get("token", [None])[0]
        if query:
            return query, True
        auth = headers.get("authorization", "")
        if auth.lower().startswith("bearer "):
            return auth[7:].strip(), False
        for part in headers.get("cookie", "").split(";"):
            name, _, value = part.strip().partition("=")
            if name == COOKIE:
                return value, False
        return None, False

    async def __call__(self, scope, receive, send):
        if scope["type"] not in ("http", "websocket") or self.token is None:
            return await self.app(scope, receive, send)
        given, in_query = self._given(scope)
        if given is None or not hmac.compare_digest(given.encode(), self.token.encode()):
            return await self._deny(scope, receive, send)
        if scope["type"] == "http" and in_query:
            cookie = f"{COOKIE}={self.token}; Path=/; HttpOnly; SameSite=Strict".encode()

            async def send_with_cookie(message):
                if message["type"] == "http.response.start":
                    message = {**message, "headers": [*message.get("headers", []), (b"set-cookie", cookie)]}
                await send(message)
            return await self.app(scope, receive, send_with_cookie)
        return await self.app(scope, receive, send)

    async def _deny(self, scope, receive, send):
        body = b"401: this worldtrack page needs its token (open it as /?token=TOKEN)\n"
        if scope["type"] == "http":
            return await PlainTextResponse(body.decode(), status_code=401,
                                           headers={"WWW-Authenticate": "Bearer"})(scope, receive, send)
        await receive()                                   # websocket.connect
        if "websocket.http.response" in scope.get("extensions", {}):
            await send({"type": "websocket.http.response.start", "status": 401,
                        "headers": [(b"content-type", b"text/plain"), (b"content-length", str(len(body)).encode())]})
            await send({"type": "websocket.http.response.body", "body": body})
        else:
            await send({"type": "websocket.close", "code": 1008})


def _same_origin(websocket: WebSocket) -> bool:
    origin = websocket.headers.get("origin")
    if not origin:
        return True
    return origin.split("://", 1)[-1].rstrip("/") == websocket.headers.get("host", "")


def make_app(source: PageSource, token: str | None = None) -> Any:
    """The ASGI app for ``source``; with ``token``, wrapped in :class:`TokenGate`."""
    from worldtrack.serve.plan import plan_json
    hub = Hub()
    plan = json.dumps({**plan_json(source.scene), "mode": source.mode, "title": source.title,
                       "trail_s": source.trail_s, "frames": source.frames.cameras if source.frames else []},
                      separators=(",", ":")).encode()

    async def index(request):
        return FileResponse(STATIC / "index.html", headers={"Cache-Control": "no-store"})

    async def api_plan(request):
        return Response(plan, media_type="application/json")

    async def api_run(request):
        if source.run is None:
            return JSONResponse({"error": "not a finished run"}, status_code=404)
        from worldtrack.serve.run import timeline_json
        body = await asyncio.to_thread(source.cached, "run", lambda: timeline_json(source.run))
        return Response(body, media_type="application/json")

    async def api_history(request):
        if source.history is None:
            return JSONResponse({"error": "history comes from the live map"}, status_code=404)
        try:
            pid = int(request.path_params["pid"])
            seconds = min(float(request.query_params.get("s", 120)), 3600.0)
        except ValueError:
            return JSONResponse({"error": "expected /api/history/<id>?s=<seconds>"}, status_code=400)
        return JSONResponse(await asyncio.to_thread(source.history, pid, seconds))

    async def api_frame(request):
        if source.frames is None:
            return PlainTextResponse("frames are off (worldtrack serve --frames)", status_code=404)
        try:
            frame = int(request.path_params["frame"])
        except ValueError:
            return PlainTextResponse("expected /api/frame/<camera>/<frame number>", status_code=400)
        jpeg = await asyncio.to_thread(source.frames.jpeg, request.path_params["camera"], frame)
        if jpeg is None:
            return PlainTextResponse("no such camera or frame", status_code=404)
        return Response(jpeg, media_type="image/jpeg", headers={"Cache-Control": "max-age=3600"})

    async def ws(websocket: WebSocket):
        if not _same_origin(websocket):
            await websocket.close(code=1008)
            return
        await websocket.accept()
        q: asyncio.Queue = asyncio.Queue(maxsize=QUEUE_MESSAGES)
        hub.queues.add(q)
        live = websocket.app.state.live
        try:
            for text in live.backlog() if live else ():
                await websocket.send_text(text)

            async def pump():
                while True:
                    await websocket.send_text(await q.get())
            sender = asyncio.create_task(pump())
            try:
                while (await websocket.receive())["type"] != "websocket.disconnect":
                    pass
            finally:
                sender.cancel()
        except (WebSocketDisconnect, RuntimeError):
            pass
        finally:
            hub.queues.discard(q)

    @contextlib.asynccontextmanager
    async def lifespan(app):
        hub.loop = asyncio.get_running_loop()
        app.state.live = source.live(hub.publish) if source.live else None
        app.state.hub = hub
        if app.state.live:
            app.state.live.start()
        try:
            yield
        finally:
            if app.state.live:
                await asyncio.to_thread(app.state.live.stop)
            if source.frames:
                source.frames.close()

    routes = [Route("/", index), Route("/api/plan", api_plan), Route("/api/run", api_run),
              Route("/api/history/{pid}", api_history), Route("/api/frame/{camera}/{frame}", api_frame),
              WebSocketRoute("/ws", ws), Mount("/static", StaticFiles(directory=STATIC), name="static")]
    app = Starlette(routes=routes, lifespan=lifespan)
    return TokenGate(app, token) if token else app


__all__ = ["Hub", "PageSource", "TokenGate", "make_app"]
