"""Running the app: binding the port (one-line errors), the token rule, uvicorn.

The server binds 127.0.0.1 unless told otherwise. Bound to anything else it requires a token
(``--token``, else :data:`TOKEN_ENV`, else a random one made now and printed once with the URL).

>>> is_loopback("127.0.0.1"), is_loopback("localhost"), is_loopback("::1"), is_loopback("0.0.0.0")
(True, True, True, False)
"""

from __future__ import annotations

import errno
import ipaddress
import os
import secrets
import socket
from typing import Any

from worldtrack.errors import InputError

#: The environment variable that holds the page's token.
TOKEN_ENV = "WORLDTRACK_SERVE_TOKEN"


def is_loopback(host: str) -> bool:
    """True for an address only this machine can reach (127.0.0.0/8, ::1, ``localhost``)."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def resolve_token(host: str, token: str | None, env: dict[str, str] | None = None) -> str | None:
    """The token the server requires: None on loopback without one; else ``token``, the
    environment's, or a new random one."""
    env = os.environ if env is None else env
    token = token or env.get(TOKEN_ENV) or None
    if token is None and not is_loopback(host):
        token = secrets.token_urlsafe(18)
    return token


def bind(host: str, port: int) -> socket.socket:
    """A listening TCP socket on ``host:port``; :class:`InputError` (one line) when the port is taken,
    not allowed, or the address is not this machine's."""
    if not 0 <= port <= 65535:
        raise InputError(f"--port {port}: expected a port number 1-65535")
    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE)
    except socket.gaierror as e:
        raise InputError(f"--host {host}: not an address of this machine ({e.strerror})") from None
    family, _, _, _, address = infos[0]
    sock = socket.socket(family, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind(address)
        sock.listen(128)
    except OSError as e:
        sock.close()
        if e.errno == errno.EADDRINUSE:
            raise InputError(f"port {port} on {host} is in use (another server?): choose another with --port") from None
        if e.errno == errno.EACCES:
            raise InputError(f"port {port} on {host}: not allowed (ports below 1024 need root): use --port 8000") from None
        raise InputError(f"--host {host} --port {port}: cannot listen there ({e.strerror})") from None
    sock.set_inheritable(True)
    return sock


def run_server(app: Any, sock: socket.socket, quiet: bool = True) -> None:
    """Serve ``app`` on the bound socket with uvicorn until Ctrl-C (which uvicorn passes on after
    closing the connections)."""
    import uvicorn
    config = uvicorn.Config(app, log_level="warning" if quiet else "info", access_log=not quiet, ws="auto",
                            lifespan="on", timeout_graceful_shutdown=2)
    uvicorn.Server(config).run(sockets=[sock])


__all__ = ["TOKEN_ENV", "bind", "is_loopback", "resolve_token", "run_server"]
