"""A batch worker starved of CPU, told from a dead one: by its connection to Redis.

The fusion waits for a batch worker's report of every bucket while the worker's camera lease lives
(:meth:`~worldtrack.map.fusion_role.FusionRole._waits_for`), so that a batch run writes the same map
however loaded the machine is. The lease is renewed by a thread of the worker; on a machine loaded
enough that this thread does not run for ``lease_s`` (1 s), the lease lapses although the worker is
alive, the fusion writes the bucket without its report, and the run no longer repeats.

A dead worker's process is gone, and the operating system has closed its connections to Redis (also
after ``SIGKILL``); a starved one still has them open. So each worker names its connection after
itself (``CLIENT SETNAME``, :func:`name_connection`), and the fusion, before treating a batch camera
whose lease lapsed as dead, looks whether its worker is still connected (``CLIENT LIST``,
:class:`StarvedWorkers`) — for at most ``map.starved_wait_s``, so that a worker that hangs does not
hold the map for ever. A worker that ends its run says so first (it registers its cameras without
``lockstep``), and a Redis user not allowed ``CLIENT`` commands gets the old rule (lapsed = dead).
"""

from __future__ import annotations

import time
from typing import Any, Callable, Mapping


def name_connection(client: Any, name: str) -> bool:
    """Name one of ``client``'s connections ``name`` (``CLIENT SETNAME``; spaces become ``_``);
    False when the server or the Redis user does not allow it."""
    try:
        import redis
        client.client_setname(name.replace(" ", "_"))
        return True
    except (redis.ResponseError, redis.ConnectionError):
        return False


class StarvedWorkers:
    """Which batch cameras whose lease lapsed still have their worker connected to Redis.

    Parameters
    ----------
    client : redis.Redis
    wait_s : how long (s) after its lease lapsed a camera is still waited for (0: never)
    clock : monotonic clock, s
    """

    def __init__(self, client: Any, wait_s: float, clock: Callable[[], float] = time.monotonic):
        self.client, self.wait_s, self.clock = client, wait_s, clock
        self._since: dict[str, float] = {}          # camera -> when its lease was first seen lapsed

    def connected(self, lapsed: Mapping[str, str]) -> list[str]:
        """The cameras of ``lapsed`` (``{camera: its worker's name}``: batch cameras whose lease
        lapsed) whose worker still has a connection named after it, lapsed less than ``wait_s`` ago.
        One ``CLIENT LIST`` when some camera is still within ``wait_s``."""
        now = self.clock()
        self._since = {c: self._since.get(c, now) for c in lapsed}
        due = [c for c in lapsed if now - self._since[c] < self.wait_s and lapsed[c]]
        if not due:
            return []
        try:
            import redis
            names = {c.get("name") for c in self.client.client_list()}
        except (redis.ResponseError, redis.ConnectionError):
            return []
        return [c for c in due if lapsed[c].replace(" ", "_") in names]


__all__ = ["StarvedWorkers", "name_connection"]
