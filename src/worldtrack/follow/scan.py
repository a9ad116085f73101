"""The robot's planar range sensor round its body (worldtrack, beyond seed 001), and who walks in it.

The stereo camera sees 66° ahead. A person walking at the robot on a steady bearing 40–90° off its
heading is never in that view until they touch it (held-out seed 17 of issue 35: a walker closing
from 41–46° for 3 s), and at less than 0.4 m the stereo has no depth at all. Following robots carry
a 2-D range scanner at knee height for this; the closed loop (:mod:`~worldtrack.follow.loop`) can
give the simulated robot one:

* :func:`simulate_scan` — the scanner's hit points (world floor coordinates, m) from the world's
  truth: people as circles (half their shoulder width), walls and obstacles by sphere tracing the
  scene's distance field, with range noise. The follower reads only the points;
* :func:`segments` — the scan cut into objects where neighbouring rays' hits jump apart; person-sized
  ones (≤ ``max_extent``) are movers, wider ones walls;
* :class:`ScanMovers` — each person-sized segment's centre and velocity, from the nearest segment
  of the previous scans (smoothed), for :func:`~worldtrack.follow.movers.moving_speed_limit`.

>>> import numpy as np
>>> hits = simulate_scan((0.0, 0.0), 0.0, np.array([[1.0, 0.9]]), np.array([0.2]), lambda xy: np.full(len(xy), 9.0))
>>> seg = segments(hits, origin=(0.0, 0.0))
>>> len(seg), bool(np.hypot(*(seg[0] - (1.0, 0.9))) < 0.05)         # one person, 42° off the heading
(1, True)
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


def simulate_scan(centre, yaw: float, people_xy: np.ndarray, people_radius: np.ndarray, clearance_at,
                  fov_deg: float = 270.0, step_deg: float = 1.0, max_range: float = 4.0, noise: float = 0.02,
                  rng: np.random.Generator | None = None) -> np.ndarray:
    """(M, 2) world points (m) where the scanner's rays from ``centre`` hit something within ``max_range``,
    in ray order (counter-clockwise from −``fov_deg``/2 off the heading ``yaw``).

    people_xy (K, 2), people_radius (K,) : circles, m; clearance_at(xy (N, 2)) → (N,) distance to the
    nearest wall or obstacle (m, ≤ 0 inside); noise : range σ, m (``rng``: a Generator, or none).
    """
    angles = yaw + np.radians(np.arange(-fov_deg / 2, fov_deg / 2 + 1e-9, step_deg))
    rays = np.column_stack([np.cos(angles), np.sin(angles)])                     # (R, 2)
    origin = np.asarray(centre, float)
    rng_ = np.full(len(rays), np.inf)
    # Walls and obstacles: sphere tracing (step by the distance to the nearest one).
    t = np.zeros(len(rays))
    for _ in range(48):
        d = clearance_at(origin + t[:, None] * rays)
        hit = d < 0.02
        t = np.where(hit, t, t + np.maximum(d, 0.02))
        if np.all(hit | (t > max_range)):
            break
    rng_ = np.where(clearance_at(origin + t[:, None] * rays) < 0.05, t, rng_)
    people_xy = np.asarray(people_xy, float).reshape(-1, 2)
    if len(people_xy):
        rel = people_xy - origin                                                 # (K, 2)
        along = rays @ rel.T                                                     # (R, K)
        off2 = np.sum(rel ** 2, axis=1)[None] - along ** 2
        disc = np.asarray(people_radius, float)[None] ** 2 - off2
        enter = np.where((disc >= 0) & (along > 0), along - np.sqrt(np.maximum(disc, 0.0)), np.inf)
        rng_ = np.minimum(rng_, np.where(enter > 0, enter, np.inf).min(axis=1))
    if rng is not None:
        rng_ = rng_ + rng.normal(0.0, noise, len(rng_))
    keep = rng_ <= max_range
    return origin + rng_[keep, None] * rays[keep]


def segments(points: np.ndarray, origin=None, gap: float = 0.2, max_extent: float = 0.8,
             behind: float = 0.12) -> np.ndarray:
    """(J, 2) centres (m) of the person-sized objects in a scan (points (M, 2) in ray order): runs of
    hits each within ``gap`` m of the previous, at most ``max_extent`` m end to end; each run's mean
    is moved ``behind`` m away from the scanner at ``origin`` (the seen arc of a 0.2 m body is its
    near half, whose mean lies 2r/π ≈ 0.13 m short of its centre)."""
    points = np.asarray(points, float).reshape(-1, 2)
    if len(points) == 0:
        return np.zeros((0, 2))
    jumps = np.flatnonzero(np.hypot(*np.diff(points, axis=0).T) > gap) + 1
    runs = np.split(np.arange(len(points)), jumps)
    out = np.array([points[r].mean(axis=0) for r in runs
                    if len(r) >= 2 and np.hypot(*(points[r[-1]] - points[r[0]])) <= max_extent]).reshape(-1, 2)
    if origin is not None and len(out):
        away = out - np.asarray(origin, float)
        out = out + behind * away / np.maximum(np.linalg.norm(away, axis=1, keepdims=True), 1e-9)
    return out


@dataclass
class ScanMovers:
    """Person-sized scan segments followed from scan to scan: centres (K, 2) m and velocities (K, 2) m/s.

    A segment takes the velocity of the nearest one of the previous scan within ``reach`` m (how far a
    walker goes in a frame, with slack), blended with time constant ``tau`` s; a new one starts at rest.
    """

    reach: float = 0.35
    tau: float = 0.3
    xy: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    velocity: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    t: float | None = None

    def update(self, centres: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Take this scan's segment centres (J, 2) at time ``t`` (s); returns (centres, velocities)."""
        centres = np.asarray(centres, float).reshape(-1, 2)
        velocity = np.zeros_like(centres)
        if self.t is not None and t > self.t and len(self.xy) and len(centres):
            dt = t - self.t
            d = np.hypot(centres[:, None, 0] - self.xy[None, :, 0], centres[:, None, 1] - self.xy[None, :, 1])
            near = d.argmin(axis=1)
            matched = d[np.arange(len(centres)), near] < self.reach
            w = 1.0 - np.exp(-dt / self.tau)
            raw = (centres - self.xy[near]) / dt
            velocity[matched] = (1 - w) * self.velocity[near[matched]] + w * raw[matched]
        self.xy, self.velocity, self.t = centres, velocity, t
        return centres, velocity
