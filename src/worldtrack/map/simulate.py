"""Simulated cameras for the shared map: observation publishers without images.

For measuring the fusion (throughput, lag, fail-over) apart from tracking: ``cameras`` cameras on a
grid of ``cell_m``-metre floor cells, each watching its cell, each cell with ``people`` walkers
(random walk at about 1 m/s, kept inside the cell); every camera publishes an observation of its
people ``fps`` times a second, under its own lease, exactly as a worker would.

>>> import numpy as np
>>> floor = SimulatedFloor(cameras=4, people=5, rng=np.random.default_rng(0))
>>> floor.positions.shape, floor.ids[:3].tolist()
((4, 5, 2), [1, 2, 3])
"""

from __future__ import annotations

import math
import threading
import time
from typing import Any, Callable

import numpy as np

from worldtrack.map.config import MapConfig
from worldtrack.map.connection import MapKeys
from worldtrack.map.lease import FENCED_XADD, Lease
from worldtrack.map.messages import Estimate, Observation, encode_observation, stream_id_ms


class SimulatedFloor:
    """Walkers on a grid of cells, one camera per cell (metres, seconds)."""

    def __init__(self, cameras: int, people: int, rng: np.random.Generator, cell_m: float = 5.0,
                 speed_mps: float = 1.0):
        self.cameras, self.people, self.cell_m, self.speed = int(cameras), int(people), cell_m, speed_mps
        side = math.ceil(math.sqrt(self.cameras))
        k = np.arange(self.cameras)
        self.origins = np.column_stack([k % side, k // side]) * cell_m          # (C, 2)
        self.positions = self.origins[:, None, :] + rng.uniform(0.5, cell_m - 0.5, (self.cameras, self.people, 2))
        angle = rng.uniform(0, 2 * np.pi, (self.cameras, self.people))
        self.velocity = speed_mps * np.stack([np.cos(angle), np.sin(angle)], axis=-1)
        self.ids = np.arange(1, self.cameras * self.people + 1)
        self.rng = rng

    def advance(self, dt: float) -> None:
        """Walk ``dt`` seconds; walkers turn a little each step and bounce off their cell's edges."""
        turn = self.rng.normal(0, 0.3 * math.sqrt(max(dt, 1e-6)), self.velocity.shape[:2])
        c, s = np.cos(turn), np.sin(turn)
        vx, vy = self.velocity[..., 0], self.velocity[..., 1]
        self.velocity = np.stack([c * vx - s * vy, s * vx + c * vy], axis=-1)
        self.positions = self.positions + self.velocity * dt
        lo = self.origins[:, None, :] + 0.3
        hi = self.origins[:, None, :] + self.cell_m - 0.3
        out = (self.positions < lo) | (self.positions > hi)
        self.velocity = np.where(out, -self.velocity, self.velocity)
        self.positions = np.clip(self.positions, lo, hi)

    def observation(self, camera: int, t: float, worker: str, frame: int, sent: float) -> Observation:
        """What camera ``camera`` reports at ``t``: its cell's people, seen, support 0.7."""
        people = tuple(Estimate(int(self.ids[camera * self.people + j]), float(x), float(y), 1.7, 0.45,
                                float(vx), float(vy), 0.8, 0.7, True, 400.0, 0.0, 400.0)
                       for j, ((x, y), (vx, vy)) in enumerate(zip(self.positions[camera], self.velocity[camera])))
        return Observation(f"sim{camera:03d}", t, worker, frame, sent, people)


class Publishers:
    """Publish a :class:`SimulatedFloor`'s observations to a map at ``fps``, each camera under its
    own lease (renewed), from one thread, until :meth:`stop`.

    ``clock`` gives capture times; ``jitter_s`` spreads the cameras' capture phases.
    """

    def __init__(self, client: Any, keys: MapKeys, cfg: MapConfig, floor: SimulatedFloor, fps: float = 10.0,
                 clock: Callable[[], float] = time.time, name: str = "sim"):
        self.client, self.keys, self.cfg, self.floor, self.fps, self.clock = client, keys, cfg, floor, fps, clock
        self.name = name
        self.cams = [f"sim{k:03d}" for k in range(floor.cameras)]
        self.leases = [Lease(client, keys.camera_lease(c), name, cfg.lease_s) for c in self.cams]
        self._xadd = client.register_script(FENCED_XADD)
        self._stop = threading.Event()
        self.published = 0
        self.overruns = 0
        self.thread = threading.Thread(target=self._run, name="publishers", daemon=True)

    def start(self) -> "Publishers":
        import json
        self.client.hset(self.keys.cameras, mapping={c: json.dumps({"fps": self.fps, "worker": self.name})
                                                    for c in self.cams})
        pipe = self.client.pipeline(transaction=False)
        for le in self.leases:
            pipe.set(le.key, self.name, px=le.ttl_ms)
        pipe.execute()
        self.thread.start()
        return self

    def _run(self) -> None:
        period = 1.0 / self.fps
        t_next = math.ceil(self.clock() / period) * period + period / 2
        last_renew, frame = 0.0, 0
        while not self._stop.is_set():
            delay = t_next - self.clock()
            if delay > 0 and self._stop.wait(delay):
                break
            if delay < -period:
                self.overruns += 1
            self.floor.advance(period)
            pipe = self.client.pipeline(transaction=False)
            now = self.clock()
            if now - last_renew > self.cfg.renew_s:
                for le in self.leases:
                    pipe.pexpire(le.key, le.ttl_ms)
                last_renew = now
            for k, cam in enumerate(self.cams):
                o = self.floor.observation(k, t_next, self.name, frame, self.clock())
                args = [self.name, f"{stream_id_ms(o.t)}-*", str(stream_id_ms(o.t - self.cfg.retention_s))]
                for key, value in encode_observation(o).items():
                    args += [key, value]
                self._xadd(keys=[self.keys.camera_lease(cam), self.keys.observations(cam)], args=args, client=pipe)
            pipe.execute()
            self.published += len(self.cams)
            frame += 1
            t_next += period

    def stop(self) -> None:
        self._stop.set()
        self.thread.join(5)
        for le in self.leases:
            le.release()


__all__ = ["Publishers", "SimulatedFloor"]
