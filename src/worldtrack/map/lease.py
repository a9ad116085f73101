"""Leases: who owns a camera, who holds the fusion role. ``SET key owner NX PX ttl``, renewed.

A lease is a key whose value is its holder's name and which expires ``ttl`` after its last
renewal. Only the holder renews or releases it (a compare-and-set in a Lua script, so a holder that
stalled past its ttl cannot renew a lease somebody else has taken since). Writes that only the
holder may make (a camera's observations, the map) check the lease in the same script
(:data:`FENCED_XADD`), so a worker that lost its lease cannot write after its successor.
"""

from __future__ import annotations

import os
import socket
import threading
import uuid
from typing import Any, Callable, Iterable

_RENEW = """
if redis.call('GET', KEYS[1]) == ARGV[1] then
  return redis.call('PEXPIRE', KEYS[1], ARGV[2])
end
return 0
"""
_RELEASE = """
if redis.call('GET', KEYS[1]) == ARGV[1] then
  return redis.call('DEL', KEYS[1])
end
return 0
"""
#: The fence every holder-only write starts with: KEYS[1] is the lease, ARGV[1] its owner.
_IF_NOT_OURS_RETURN_0 = """
if redis.call('GET', KEYS[1]) ~= ARGV[1] then
  return 0
end
"""
#: The fence, then XADD arguments for KEYS[2] capped at MINID ARGV[3] (if any), id ARGV[2].
_FENCED_XADD_ARGS = _IF_NOT_OURS_RETURN_0 + """local args = {KEYS[2]}
if ARGV[3] ~= '' then
  table.insert(args, 'MINID'); table.insert(args, '~'); table.insert(args, ARGV[3])
end
table.insert(args, ARGV[2])
"""
#: XADD only while holding the lease: KEYS = (lease, stream), ARGV = (owner, id, minid, field, value, …).
#: Returns the entry id, 0 when the lease is not ours, -1 when the id is not above the stream's last.
FENCED_XADD = _FENCED_XADD_ARGS + """for i = 4, #ARGV do table.insert(args, ARGV[i]) end
local ok, res = pcall(redis.call, 'XADD', unpack(args))
if not ok then
  return -1
end
return res
"""

#: The fusion's record of a bucket (:mod:`worldtrack.map.fusion_role`). KEYS = (lease, map stream, current hash); ARGV = (owner, id, minid, state, last bucket, written, t,
#: people count, updates channel, update, field, value, …). 1 written, 0 not our lease, -1 bucket
#: already written, 2 written but not published (an ACL user without the channel: ``&prefix:*``).
WRITE_MAP = _FENCED_XADD_ARGS + """for i = 11, #ARGV do table.insert(args, ARGV[i]) end
local ok = pcall(redis.call, 'XADD', unpack(args))
if not ok then
  return -1
end
redis.call('HSET', KEYS[3], 'state', ARGV[4], 'last_bucket', ARGV[5], 'written', ARGV[6], 't', ARGV[7],
           'people', ARGV[8], 'holder', ARGV[1])
for i = 11, #ARGV, 2 do
  if ARGV[i] == 'people' or ARGV[i] == 'aliases' or ARGV[i] == 'reports' then
    redis.call('HSET', KEYS[3], 'map_' .. ARGV[i], ARGV[i + 1])
  end
end
local sent = redis.pcall('PUBLISH', ARGV[9], ARGV[10])
if type(sent) == 'table' and sent.err then
  return 2
end
return 1
"""

#: The live map between complete buckets. KEYS = (lease, current hash); ARGV = (owner, updates
#: channel, update, written, t, people count, people, aliases, reports). 1 written, 0 not our lease,
#: 2 written but not published.
UPDATE_MAP = _IF_NOT_OURS_RETURN_0 + """redis.call('HSET', KEYS[2], 'written', ARGV[4], 't', ARGV[5], 'people', ARGV[6], 'map_people', ARGV[7],
           'map_aliases', ARGV[8], 'map_reports', ARGV[9])
local sent = redis.pcall('PUBLISH', ARGV[2], ARGV[3])
if type(sent) == 'table' and sent.err then
  return 2
end
return 1
"""


def worker_name() -> str:
    """A name for this process that no other process shares: ``host:pid:random``."""
    return f"{socket.gethostname()}:{os.getpid()}:{uuid.uuid4().hex[:6]}"


class Lease:
    """One lease on ``key`` for ``owner``, ``ttl_s`` seconds long.

    >>> # with a client c: Lease(c, "wt:lease:camera:cam1", "w1", 1.0).acquire() -> True or False
    """

    def __init__(self, client: Any, key: str, owner: str, ttl_s: float):
        self.client, self.key, self.owner = client, key, owner
        self.ttl_ms = max(1, int(round(ttl_s * 1000)))
        self._renew = client.register_script(_RENEW)
        self._release = client.register_script(_RELEASE)

    def acquire(self) -> bool:
        """Take the lease if it is free (or renew it if it is ours already)."""
        if self.client.set(self.key, self.owner, nx=True, px=self.ttl_ms):
            return True
        return self.renew()

    def renew(self) -> bool:
        """Extend the lease if it is still ours; False if it has expired or been taken."""
        return bool(self._renew(keys=[self.key], args=[self.owner, self.ttl_ms]))

    def release(self) -> None:
        """Give the lease up (only if it is still ours)."""
        self._release(keys=[self.key], args=[self.owner])

    def holder(self) -> tuple[str | None, float]:
        """Who holds the lease and for how much longer (s; 0 when free)."""
        pipe = self.client.pipeline()
        pipe.get(self.key)
        pipe.pttl(self.key)
        who, ttl = pipe.execute()
        return who, max(0, int(ttl)) / 1000.0 if who else 0.0


def acquire_all(leases: Iterable[Lease]) -> bool:
    """Take every lease or none (in key order, giving back the ones taken if one is held)."""
    taken: list[Lease] = []
    for lease in sorted(leases, key=lambda le: le.key):
        if not lease.acquire():
            for t in taken:
                t.release()
            return False
        taken.append(lease)
    return True


class LeaseKeeper(threading.Thread):
    """Renews leases every ``every_s`` seconds in the background; calls ``on_lost(lease)`` once for a
    lease somebody else has taken and stops renewing it. A lease that expired (this process stalled
    past its ttl) but that nobody took is taken again."""

    def __init__(self, leases: Iterable[Lease], every_s: float, on_lost: Callable[[Lease], None],
                 beat: Callable[[], None] | None = None):
        super().__init__(name="lease-keeper", daemon=True)
        self.leases = list(leases)
        self.every_s = every_s
        self.on_lost = on_lost
        self.beat = beat
        self._halt = threading.Event()

    def run(self) -> None:
        while not self._halt.wait(self.every_s):
            for lease in list(self.leases):
                try:
                    ok = lease.renew()
                except Exception:      # a dropped connection: retried at the next beat
                    continue
                if not ok and not lease.acquire():     # expired but free again: ours again
                    self.leases.remove(lease)
                    self.on_lost(lease)
            if self.beat is not None:
                try:
                    self.beat()
                except Exception:
                    pass

    def stop(self, release: bool = True) -> None:
        self._halt.set()
        if release:
            for lease in self.leases:
                try:
                    lease.release()
                except Exception:
                    pass


__all__ = ["FENCED_XADD", "UPDATE_MAP", "WRITE_MAP", "Lease", "LeaseKeeper", "acquire_all", "worker_name"]
