"""Initial trajectories for the non-convex objective (the paper runs the optimiser "from several
empirically given initial trajectories and keeps the one with the lowest objective").

- ``straight``: each observation back-projected to the person's head height, averaged per step,
  joined by straight lines at constant speed across the gaps between views.
- ``map``: the MAP without the obstacle barrier (motion, observations, height), started from
  ``straight`` — a smooth least-squares path, blind to walls (built by :mod:`.estimate`).
- ``shortest``: as ``straight``, but every gap whose straight line comes closer to an obstacle
  than the clearance follows the shortest path through free space instead (Dijkstra on the
  distance field's raster, ``scipy.sparse.csgraph``; cells inside the clearance cost more, cells
  inside obstacles are barred), walked at constant speed. This start carries the right topology
  (which side of a partition, which door) that the barrier alone cannot find. With ``timing="cubic"``
  (``TrajectoryOptions.route_timing``, opt-in) each route is walked with the motion prior's own timing
  between two states instead, :func:`cubic_timing` (34m: the start's error the leader's last iterations
  remove is mostly along the path, ``benchmarks/trajectory_slides.py``).
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from worldtrack.errors import InputError
from worldtrack.scene.floor import FloorGrid
from worldtrack.trajectory.kernels import field_values, raster_route
from worldtrack.trajectory.model import STATE, TimeGrid
from worldtrack.trajectory.observation import ObservationTerm

START_NAMES = ("straight", "map", "shortest")
#: How a route of the ``shortest`` start is walked in time (see :func:`shortest_path_start`).
ROUTE_TIMINGS = ("constant", "cubic")
#: Gaps whose ends fall in the same cells of this size (m) share one shortest-path search.
ROUTE_CACHE_CELL = 0.25


def anchor_points(term: ObservationTerm, head_height: float) -> tuple[np.ndarray, np.ndarray]:
    """Steps with observations (K,) and the mean of their back-projections to ``head_height`` (K, 2)."""
    obs = term.obs
    xy = np.full((len(obs), 2), np.nan)
    for cam, sel in zip(obs.cameras, term.rows_by_camera):
        xy[sel] = cam.backproject(obs.uv[sel], head_height)[:, :2]
    ok = np.all(np.isfinite(xy), axis=1)
    if not ok.any():
        raise InputError(f"no observation's viewing ray reaches the head height {head_height:.2f} m")
    steps, inverse = np.unique(term.step[ok], return_inverse=True)
    sums = np.zeros((len(steps), 2))
    np.add.at(sums, inverse, xy[ok])
    return steps, sums / np.bincount(inverse)[:, None]


def states_from_positions(xy: np.ndarray, grid: TimeGrid, head_height: float) -> np.ndarray:
    """X (n, 6) from floor positions (n, 2): velocities by finite differences, head at ``head_height``."""
    X = np.zeros((grid.n, STATE))
    X[:, 0], X[:, 2] = xy[:, 0], xy[:, 1]
    X[:, 1] = np.gradient(xy[:, 0], grid.dt)
    X[:, 3] = np.gradient(xy[:, 1], grid.dt)
    X[:, 4] = head_height
    return X


def straight_start(term: ObservationTerm, grid: TimeGrid, head_height: float,
                   anchors: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """Start ``straight``: (n, 6) — linear in time between observed steps, constant outside them.
    ``anchors``: :func:`anchor_points` of ``term`` at ``head_height`` if already computed."""
    steps, xy = anchors or anchor_points(term, head_height)
    k = np.arange(grid.n)
    path = np.column_stack([np.interp(k, steps, xy[:, 0]), np.interp(k, steps, xy[:, 1])])
    return states_from_positions(path, grid, head_height)


def shortest_path_start(term: ObservationTerm, grid: TimeGrid, head_height: float, field: FloorGrid,
                        clearance: float, resolution: float = 0.1,
                        anchors: tuple[np.ndarray, np.ndarray] | None = None, timing: str = "constant",
                        velocities: np.ndarray | None = None) -> np.ndarray:
    """Start ``shortest``: ``straight`` with every blocked gap replaced by a free-space shortest path.
    ``anchors``: :func:`anchor_points` of ``term`` at ``head_height`` if already computed. ``timing``: each
    route walked at constant speed, or ``"cubic"``: by :func:`cubic_timing`, its end speeds ``velocities``
    ((n, 2) floor velocities, m/s, e.g. the MAP's without the barrier) at the gap's two ends along the route."""
    if timing not in ROUTE_TIMINGS or (timing == "cubic" and velocities is None):
        raise InputError(f"route timing: expected one of {', '.join(ROUTE_TIMINGS)} (cubic with velocities), "
                         f"got {timing!r}")
    steps, xy = anchors or anchor_points(term, head_height)
    k = np.arange(grid.n)
    path = np.column_stack([np.interp(k, steps, xy[:, 0]), np.interp(k, steps, xy[:, 1])])
    routes: dict[tuple, np.ndarray | None] = {}     # long tracks cross the same gaps again and again
    gaps = np.flatnonzero(np.diff(steps) > 1)
    for i in gaps[_blocked_gaps(field, xy[gaps], xy[gaps + 1], clearance)]:
        k0, k1 = steps[i], steps[i + 1]
        a, b = xy[i], xy[i + 1]
        key = tuple(np.rint(np.r_[a, b] / ROUTE_CACHE_CELL).astype(int))
        if key not in routes:
            routes[key] = free_space_route(field, a, b, clearance, resolution)
        route = routes[key]
        if route is not None:
            route = np.vstack([a, route[1:-1], b])          # a cached route, joined to these ends
            if timing == "cubic":
                path[k0:k1 + 1] = walk_route(route, (k1 - k0) * grid.dt, velocities[k0], velocities[k1], k1 - k0 + 1)
            else:
                path[k0:k1 + 1] = resample_by_length(route, k1 - k0 + 1)
    return states_from_positions(path, grid, head_height)


def _blocked(field: FloorGrid, a: np.ndarray, b: np.ndarray, clearance: float) -> bool:
    """Whether the segment a → b (m) comes closer to an obstacle than ``clearance`` (m), sampled every
    half raster cell (the reference of :func:`_blocked_gaps`)."""
    n = max(2, int(np.ceil(np.linalg.norm(b - a) / (field.resolution / 2))) + 1)
    pts = a + np.linspace(0.0, 1.0, n)[:, None] * (b - a)
    return bool(np.any(_distances(field, pts) < clearance))


def _blocked_gaps(field: FloorGrid, a: np.ndarray, b: np.ndarray, clearance: float) -> np.ndarray:
    """(G,) :func:`_blocked` of every segment a[g] → b[g] ((G, 2) m) in one lookup: the same sample points,
    hence the same answers."""
    if len(a) == 0:
        return np.zeros(0, dtype=bool)
    pts, first = _gap_samples(field, a, b)
    return np.logical_or.reduceat(_distances(field, pts) < clearance, first)


def _gap_samples(field: FloorGrid, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The points :func:`_blocked` samples on every segment a[g] → b[g], concatenated (M, 2), and the index
    of each segment's first point (G,): ``np.linspace``'s arithmetic, its last point set to the stop."""
    n = np.maximum(2, np.ceil(np.hypot(*(b - a).T) / (field.resolution / 2)).astype(np.int64) + 1)
    gap = np.repeat(np.arange(len(a)), n)
    first = np.r_[0, np.cumsum(n)[:-1]]
    frac = (np.arange(len(gap)) - first[gap]) * (1.0 / (n - 1))[gap]
    frac[first + n - 1] = 1.0
    return a[gap] + frac[:, None] * (b - a)[gap], first


def resample_by_length(route: np.ndarray, n: int) -> np.ndarray:
    """``n`` points equally spaced by arc length along a polyline (M, 2), ends included."""
    seg = np.hypot(*np.diff(route, axis=0).T)
    s = np.r_[0.0, np.cumsum(seg)]
    if s[-1] <= 0:
        return np.repeat(route[:1], n, axis=0)
    target = np.linspace(0.0, s[-1], n)
    return np.column_stack([np.interp(target, s, route[:, 0]), np.interp(target, s, route[:, 1])])


def cubic_timing(length: float, duration: float, v0: float, v1: float, n: int) -> np.ndarray:
    """(n,) arc length (m) at n equal time steps over ``duration`` (s) along a route of ``length`` (m): the cubic
    s(t) from (0, v0) to (``length``, v1) (speeds in m/s, negative ones taken as 0) — the path of least squared
    acceleration between two states, the motion prior's mean between them — kept in [0, length], non-decreasing.

    >>> cubic_timing(2.0, 2.0, 1.0, 1.0, 5).tolist()          # the mean speed at both ends: constant speed
    [0.0, 0.5, 1.0, 1.5, 2.0]
    """
    tau = np.linspace(0.0, 1.0, n)
    h10, h01, h11 = tau ** 3 - 2 * tau ** 2 + tau, -2 * tau ** 3 + 3 * tau ** 2, tau ** 3 - tau ** 2
    s = h10 * duration * max(v0, 0.0) + h01 * length + h11 * duration * max(v1, 0.0)
    return np.maximum.accumulate(np.clip(s, 0.0, length))


def walk_route(route: np.ndarray, duration: float, v0: np.ndarray, v1: np.ndarray, n: int) -> np.ndarray:
    """``n`` points (n, 2) along a polyline (M, 2), m, at equal time steps over ``duration`` (s), with
    :func:`cubic_timing`; the end speeds are the velocities v0, v1 ((2,), m/s) along the route's first and
    last half metre (or half its length)."""
    s = np.r_[0.0, np.cumsum(np.hypot(*np.diff(route, axis=0).T))]
    if s[-1] <= 0:
        return np.repeat(route[:1], n, axis=0)
    h = min(0.5, s[-1] / 2)
    at = lambda a: np.column_stack([np.interp(a, s, route[:, 0]), np.interp(a, s, route[:, 1])])  # noqa: E731
    (ahead,), (behind,) = at(h) - route[0], route[-1] - at(s[-1] - h)
    speed0 = float(np.dot(v0, ahead)) / max(float(np.hypot(*ahead)), 1e-12)
    speed1 = float(np.dot(v1, behind)) / max(float(np.hypot(*behind)), 1e-12)
    return at(cubic_timing(s[-1], duration, speed0, speed1, n))


def free_space_route(field: FloorGrid, a: np.ndarray, b: np.ndarray, clearance: float,
                     resolution: float = 0.1, margin: float | None = None) -> np.ndarray | None:
    """Shortest path (M, 2) from a to b (metres) through free space, or None if there is none.

    Searched on a raster of ``resolution`` metres, 8-connected, over the box around a and b grown by
    ``margin`` (default: 2 m or half their distance, whichever is larger) and, if that box holds no
    way through, over the whole field. Each edge costs its length times the mean of its two cells'
    weights: 1 beyond 1.5 × clearance from obstacles, rising to 11 at the clearance; cells inside
    obstacles are barred (but for the two ends' own cells, should an observation put them there).
    """
    margin = max(2.0, 0.5 * float(np.linalg.norm(b - a))) if margin is None else margin
    ny, nx = field.values.shape
    whole = (field.origin, field.origin + field.resolution * np.array([nx - 1, ny - 1]))
    for lo, hi in ((np.minimum(a, b) - margin, np.maximum(a, b) + margin), whole):
        route = _route_in_box(field, a, b, clearance, resolution, lo, hi)
        if route is not None:
            return route
    return None


def _route_in_box(field: FloorGrid, a: np.ndarray, b: np.ndarray, clearance: float, resolution: float,
                  lo: np.ndarray, hi: np.ndarray, reference: bool = False) -> np.ndarray | None:
    xs = np.arange(lo[0], hi[0] + resolution / 2, resolution)
    ys = np.arange(lo[1], hi[1] + resolution / 2, resolution)
    gx, gy = np.meshgrid(xs, ys)
    d = _distances(field, np.column_stack([gx.ravel(), gy.ravel()]))
    soft = 1.5 * max(clearance, 1e-3)
    weight = 1.0 + 10.0 * np.clip((soft - d) / soft, 0.0, 1.0)
    ny, nx = gx.shape
    start = _nearest_cell(a, lo, resolution, nx, ny)
    goal = _nearest_cell(b, lo, resolution, nx, ny)
    free = d >= 0
    free[[start, goal]] = True
    if reference:
        cells = _scipy_route(weight.reshape(ny, nx), free.reshape(ny, nx), start, goal, resolution)
    else:
        cells = raster_route(weight.reshape(ny, nx), free.reshape(ny, nx), start, goal, float(resolution))
    if len(cells) == 0:
        return None
    pts = np.column_stack([gx.ravel()[cells], gy.ravel()[cells]])
    return np.vstack([a, pts[1:-1], b]) if len(pts) > 2 else np.vstack([a, b])


def _scipy_route(weight: np.ndarray, free: np.ndarray, start: int, goal: int, resolution: float) -> np.ndarray:
    """The reference of :func:`~.kernels.raster_route`: the raster's graph for
    ``scipy.sparse.csgraph.dijkstra`` (from the start to every cell), then the path back from the goal."""
    ny, nx = free.shape
    idx = np.arange(nx * ny).reshape(ny, nx)
    src, dst, length = [], [], []
    for dj, di in ((0, 1), (1, 0), (1, 1), (1, -1)):
        j0, j1 = max(0, -dj), ny - max(0, dj)
        i0, i1 = max(0, -di), nx - max(0, di)
        p = idx[j0:j1, i0:i1].ravel()
        q = idx[j0 + dj:j1 + dj, i0 + di:i1 + di].ravel()
        ok = free.ravel()[p] & free.ravel()[q]
        src.append(p[ok])
        dst.append(q[ok])
        length.append(np.full(int(ok.sum()), resolution * np.hypot(di, dj)))
    p, q, ell = np.concatenate(src), np.concatenate(dst), np.concatenate(length)
    w = weight.ravel()
    graph = coo_matrix((ell * 0.5 * (w[p] + w[q]), (p, q)), shape=(nx * ny, nx * ny)).tocsr()
    dist, pred = dijkstra(graph, directed=False, indices=start, return_predecessors=True)
    if not np.isfinite(dist[goal]):
        return np.empty(0, dtype=np.int64)
    cells = [goal]
    while cells[-1] != start:
        cells.append(pred[cells[-1]])
    return np.array(cells[::-1])


def _distances(field: FloorGrid, xy: np.ndarray) -> np.ndarray:
    """``sample_field(field, xy)[0]`` (the same numbers) without the gradient, compiled: the route's
    raster holds thousands of points per gap."""
    return field_values(np.ascontiguousarray(field.values, dtype=float), np.asarray(field.origin, dtype=float),
                        float(field.resolution), np.ascontiguousarray(xy, dtype=float))


def _nearest_cell(p: np.ndarray, lo: np.ndarray, res: float, nx: int, ny: int) -> int:
    i = int(np.clip(np.rint((p[0] - lo[0]) / res), 0, nx - 1))
    j = int(np.clip(np.rint((p[1] - lo[1]) / res), 0, ny - 1))
    return j * nx + i
