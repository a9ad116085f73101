"""Reaching the map: the Redis URL, credentials, TLS, key names, and the scene the map belongs to.

``redis://[USER:PASSWORD@]HOST[:PORT][/DB]`` or ``rediss://…`` (TLS, passed through to the client
as it is). A URL without credentials takes them from ``WORLDTRACK_REDIS_USER`` and
``WORLDTRACK_REDIS_PASSWORD`` (Redis 6 ACL users, or the plain ``requirepass`` password without a
user). The password is never printed: messages and ``run.yaml`` show :func:`redacted` URLs.

>>> redacted("redis://tracker:s3cret@10.0.0.5:6380/2")
'redis://tracker:***@10.0.0.5:6380/2'
>>> MapKeys("wt").observations("cam1"), MapKeys("wt").camera_lease("cam1")
('wt:obs:cam1', 'wt:lease:camera:cam1')
"""

from __future__ import annotations

import hashlib
import json
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from urllib.parse import quote, unquote, urlsplit, urlunsplit

from worldtrack.errors import InputError

#: Environment variables that hold the credentials when the URL does not.
USER_ENV = "WORLDTRACK_REDIS_USER"
PASSWORD_ENV = "WORLDTRACK_REDIS_PASSWORD"
SCHEMES = ("redis", "rediss")
_USERINFO = re.compile(r"(://[^/:@\s]*):[^/@\s]*@")


def redacted(url: str) -> str:
    """``url`` with its password replaced by ``***`` (for messages and logs)."""
    parts = urlsplit(url)
    if parts.password is None:
        return url
    user = parts.username or ""
    host = parts.hostname or ""
    if ":" in host:
        host = f"[{host}]"
    netloc = f"{user}:***@{host}" + (f":{parts.port}" if parts.port else "")
    return urlunsplit((parts.scheme, netloc, parts.path, parts.query, parts.fragment))


def hide_passwords(text: str) -> str:
    """``text`` with the password of every URL in it replaced by ``***`` (command lines, stream URLs).

    >>> hide_passwords("--video cam1=rtsp://admin:pw@10.1.1.9/live --map rediss://u:p%40ss@h:6380/0")
    '--video cam1=rtsp://admin:***@10.1.1.9/live --map rediss://u:***@h:6380/0'
    """
    return _USERINFO.sub(r"\1:***@", text)


def check_url(url: str) -> str:
    """``url`` if it is a Redis URL, else :class:`InputError` (the password is not repeated)."""
    parts = urlsplit(url)
    if parts.scheme not in SCHEMES or not parts.hostname:
        raise InputError(f"{redacted(url)}: expected a map URL redis://HOST[:PORT][/DB] or rediss://…")
    try:
        parts.port
    except ValueError:
        raise InputError(f"{redacted(url)}: the port is not a number") from None
    db = parts.path.strip("/")
    if db and not db.isdigit():
        raise InputError(f"{redacted(url)}: the database must be a number (e.g. /0), got {db!r}")
    return url


def with_credentials(url: str, env: dict[str, str] | None = None) -> str:
    """``url`` with the user and password of the environment added when it has none of its own."""
    env = os.environ if env is None else env
    parts = urlsplit(check_url(url))
    if parts.password is not None or not env.get(PASSWORD_ENV):
        return url
    user = parts.username or env.get(USER_ENV, "")
    host = parts.netloc.rsplit("@", 1)[-1]
    netloc = f"{quote(user, safe='')}:{quote(env[PASSWORD_ENV], safe='')}@{host}"
    return urlunsplit((parts.scheme, netloc, parts.path, parts.query, parts.fragment))


def connect(url: str, timeout_s: float = 5.0) -> Any:
    """A connected ``redis.Redis`` client for the map at ``url`` (strings decoded as UTF-8).

    Raises :class:`InputError` naming the (redacted) URL when the ``redis`` package is missing, the
    server cannot be reached or refuses the credentials.
    """
    try:
        import redis
    except ImportError:
        raise InputError("the shared map needs the redis client: pip install 'worldtrack[redis]'") from None
    full = with_credentials(url)
    where = redacted(url)
    client = redis.Redis.from_url(full, decode_responses=True, socket_timeout=timeout_s,
                                  socket_connect_timeout=timeout_s, health_check_interval=10)
    try:
        client.ping()
    except redis.AuthenticationError:
        if urlsplit(full).password is None:
            raise InputError(f"{where}: the server wants a password (give it in the URL or in "
                             f"{PASSWORD_ENV}, and the user in {USER_ENV})") from None
        user = unquote(urlsplit(full).username or "") or "default"
        raise InputError(f"{where}: the server refused user {user!r} and its password "
                         f"(give them in the URL or in {USER_ENV}/{PASSWORD_ENV})") from None
    except redis.ResponseError as e:
        if "NOAUTH" in str(e) or "WRONGPASS" in str(e):
            raise InputError(f"{where}: the server wants a password (give it in the URL or in "
                             f"{PASSWORD_ENV})") from None
        raise
    except (redis.ConnectionError, redis.TimeoutError, OSError) as e:
        raise InputError(f"{where}: cannot reach the map ({_first_line(e)})") from None
    except TypeError as e:           # an option in the URL's query the client does not take
        name = str(e).rsplit(" ", 1)[-1]
        raise InputError(f"{where}: the redis client takes no option {name} (TLS options such as "
                         f"ssl_ca_certs need rediss://)") from None
    return client


def _first_line(e: BaseException) -> str:
    text = str(e).strip().splitlines()
    return text[0] if text else type(e).__name__


@dataclass(frozen=True)
class MapKeys:
    """The names of a map's keys in Redis, all under one prefix."""

    prefix: str = "worldtrack"

    def _k(self, *parts: str) -> str:
        return ":".join((self.prefix, *parts))

    @property
    def scene(self) -> str:
        """String: JSON ``{"sha256", "name"}`` of the scene the map belongs to."""
        return self._k("scene")

    @property
    def epoch(self) -> str:
        """String: the wall-clock time (s) at which video files played as cameras start."""
        return self._k("epoch")

    @property
    def ids(self) -> str:
        """Counter: the last person id given out (workers that do not know the scene's cameras)."""
        return self._k("ids")

    def ids_of(self, camera: str) -> str:
        """Counter: how many ids the workers whose first camera is ``camera`` gave out
        (:meth:`worldtrack.map.worker.MapLink.new_id`)."""
        return self._k("ids", camera)

    def observations(self, camera: str) -> str:
        """Stream: one camera's observations, entry ids from capture times (ms)."""
        return self._k("obs", camera)

    @property
    def cameras(self) -> str:
        """Hash: camera → JSON ``{"fps", "worker"}`` of every camera a worker has published."""
        return self._k("cameras")

    @property
    def map_stream(self) -> str:
        """Stream: the fused map, one entry per time bucket (entry id = bucket start, ms)."""
        return self._k("map")

    @property
    def current(self) -> str:
        """Hash: the last map state and what the fusion role needs to resume."""
        return self._k("map", "current")

    @property
    def updates(self) -> str:
        """Pub/sub channel: every update of the live map (the fields of a map state, as JSON)."""
        return self._k("map", "updates")

    def camera_lease(self, camera: str) -> str:
        return self._k("lease", "camera", camera)

    @property
    def fusion_lease(self) -> str:
        return self._k("lease", "fusion")

    @property
    def workers(self) -> str:
        """Hash: worker name → JSON heartbeat (cameras, role, frames, dropped, lag, time)."""
        return self._k("workers")


def scene_digest(path: str | Path) -> str:
    """SHA-256 (hex) of a scene file's bytes."""
    try:
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()
    except OSError as e:
        raise InputError(f"{path}: cannot read the scene file ({e.strerror})") from None


def claim_scene(client: Any, keys: MapKeys, digest: str, name: str, url: str = "") -> None:
    """Tie the map to a scene, or check that it is already tied to this one.

    Raises :class:`InputError` (one line) when the map belongs to a scene with another hash.
    """
    mine = json.dumps({"sha256": digest, "name": name})
    if client.set(keys.scene, mine, nx=True):
        return
    theirs = json.loads(client.get(keys.scene) or "{}")
    if theirs.get("sha256") != digest:
        where = redacted(url) if url else "the map"
        raise InputError(f"{where} (prefix {keys.prefix!r}) belongs to scene {theirs.get('name')!r} "
                         f"(sha256 {str(theirs.get('sha256'))[:12]}…), not this scene {name!r} "
                         f"(sha256 {digest[:12]}…): use another database or --set map.prefix=…")


__all__ = ["MapKeys", "PASSWORD_ENV", "USER_ENV", "check_url", "claim_scene", "connect", "hide_passwords", "redacted",
           "scene_digest", "with_credentials"]
