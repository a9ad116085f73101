"""The static world as a camera sees it: textured floor, walls, ceiling or sky, obstacles, windows.

A scene file says where the floor, obstacles and cameras are; the synthetic world adds what a
real camera also sees: walls standing on every edge of the walkable floor polygons (and around
their holes), a ceiling (or open sky), surface textures and colours, posters, and emissive windows
(for backlight). :func:`render_static` ray-casts all of it once per camera pose, with 2×2
supersampling of the colours, and returns a :class:`StaticLayer` that the per-frame renderer lights
and draws people into.

Textures are procedural functions of the world point (value noise from an integer hash), so the
same seed always gives the same pixels.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from worldtrack.geometry.camera import Camera
from worldtrack.geometry.raycast import ray_plane_z, ray_quad
from worldtrack.scene.model import Box, Scene

# Surface kinds in StaticLayer.kind.
SKY, FLOOR, WALL, CEILING, OBSTACLE, WINDOW = 0, 1, 2, 3, 4, 5

FLOOR_STYLES = ("tiles", "carpet", "paving", "wood")


@dataclass(frozen=True)
class Window:
    """An emissive rectangle (a window or a bright doorway) given by 4 corners in order (4, 3)."""

    corners: np.ndarray
    radiance: tuple = (250.0, 250.0, 250.0)


@dataclass(frozen=True)
class Environment:
    """What the static world looks like (not part of the scene file).

    Parameters
    ----------
    wall_height : float, metres — also the ceiling height
    ceiling : bool — a ceiling at ``wall_height``; without it, rays that miss everything see sky
    walls : bool — walls on the edges of the walkable floor polygons
    floor_style : one of :data:`FLOOR_STYLES`
    floor_colour, wall_colour, ceiling_colour : (3,) BGR albedo
    sky_horizon, sky_zenith : (3,) BGR radiance of the sky (emissive)
    obstacle_colours : dict name → (3,) BGR, for obstacles of that name (default: a palette)
    windows : tuple of Window
    posters : int — coloured rectangles hung on the walls (texture for stereo, realism)
    seed : int — texture seed
    """

    wall_height: float = 2.8
    ceiling: bool = True
    walls: bool = True
    floor_style: str = "tiles"
    floor_colour: tuple = (150.0, 160.0, 165.0)
    wall_colour: tuple = (190.0, 200.0, 205.0)
    ceiling_colour: tuple = (210.0, 215.0, 215.0)
    sky_horizon: tuple = (235.0, 215.0, 200.0)
    sky_zenith: tuple = (215.0, 160.0, 110.0)
    obstacle_colours: dict = field(default_factory=dict)
    windows: tuple = ()
    posters: int = 4
    seed: int = 7

    def background_colours(self) -> np.ndarray:
        """(K, 3) the main background colours (for clothing that blends in)."""
        return np.array([self.floor_colour, self.wall_colour], dtype=float)


_OBSTACLE_PALETTE = np.array([[90, 120, 150], [60, 80, 110], [150, 150, 140], [120, 100, 80],
                              [70, 70, 75], [160, 140, 110]], dtype=float)
_POSTER_PALETTE = np.array([[40, 40, 160], [160, 90, 30], [40, 140, 60], [30, 160, 200], [120, 50, 120],
                            [200, 200, 200], [30, 30, 30]], dtype=float)


@dataclass
class StaticLayer:
    """The empty scene through one camera pose (all arrays H×W).

    Attributes
    ----------
    depth : float32, metres along the optical axis (inf for sky)
    kind : uint8 surface kind (SKY, FLOOR, …); surface : int16 index of the primitive
    points : (H, W, 3) float32 world point seen (NaN for sky)
    normal : (H, W, 3) float32 unit surface normal facing the camera
    albedo : (H, W, 3) float32 BGR, mean of 2×2 sub-samples
    emissive : (H, W, 3) float32 BGR radiance of sky and windows
    """

    depth: np.ndarray
    kind: np.ndarray
    surface: np.ndarray
    points: np.ndarray
    normal: np.ndarray
    albedo: np.ndarray
    emissive: np.ndarray


# ------------------------------------------------------------------------------------ noise

def _hash(i: np.ndarray, j: np.ndarray, seed: int) -> np.ndarray:
    """Integer lattice hash → uniform [0, 1) (vectorised, deterministic)."""
    h = (i.astype(np.int64) * 374761393 + j.astype(np.int64) * 668265263 + seed * 1442695041) & 0xFFFFFFFF
    h = ((h ^ (h >> 13)) * 1274126177) & 0xFFFFFFFF
    h = h ^ (h >> 16)
    return (h & 0xFFFFFF).astype(np.float64) / float(0x1000000)


def value_noise(x: np.ndarray, y: np.ndarray, scale: float, seed: int) -> np.ndarray:
    """Smooth noise in [0, 1) with features of size ``scale`` (metres) at points (x, y)."""
    gx, gy = x / scale, y / scale
    i0, j0 = np.floor(gx), np.floor(gy)
    fx, fy = gx - i0, gy - j0
    fx = fx * fx * (3 - 2 * fx)
    fy = fy * fy * (3 - 2 * fy)
    i0, j0 = i0.astype(np.int64), j0.astype(np.int64)
    a, b = _hash(i0, j0, seed), _hash(i0 + 1, j0, seed)
    c, d = _hash(i0, j0 + 1, seed), _hash(i0 + 1, j0 + 1, seed)
    return (a * (1 - fx) + b * fx) * (1 - fy) + (c * (1 - fx) + d * fx) * fy


def _fbm(x, y, scales, seed):
    out = np.zeros_like(x)
    wsum = 0.0
    for k, s in enumerate(scales):
        w = 1.0 / (k + 1)
        out += w * value_noise(x, y, s, seed + 31 * k)
        wsum += w
    return out / wsum


# ------------------------------------------------------------------------------------ textures

def floor_albedo(xy: np.ndarray, env: Environment) -> np.ndarray:
    """BGR albedo (N, 3) of the floor at world points (N, 2)."""
    x, y = xy[:, 0], xy[:, 1]
    base = np.asarray(env.floor_colour, dtype=float)
    seed = env.seed
    style = env.floor_style
    if style == "tiles":
        t = 0.5
        tile_i, tile_j = np.floor(x / t), np.floor(y / t)
        per_tile = 0.92 + 0.16 * _hash(tile_i.astype(np.int64), tile_j.astype(np.int64), seed)
        fx, fy = x / t - tile_i, y / t - tile_j
        grout = (np.minimum(fx, 1 - fx) < 0.012 / t) | (np.minimum(fy, 1 - fy) < 0.012 / t)
        speck = 0.9 + 0.2 * _fbm(x, y, (0.15, 0.04), seed + 1)
        f = per_tile * speck * np.where(grout, 0.62, 1.0)
    elif style == "carpet":
        f = 0.8 + 0.35 * _fbm(x, y, (0.6, 0.12, 0.03), seed + 2)
    elif style == "paving":
        bw, bh = 0.2, 0.1
        row = np.floor(y / bh)
        xs = x / bw + 0.5 * (row % 2)
        col = np.floor(xs)
        fx, fy = xs - col, y / bh - row
        joint = (np.minimum(fx, 1 - fx) < 0.01 / bw) | (np.minimum(fy, 1 - fy) < 0.01 / bh)
        f = (0.85 + 0.3 * _hash(col.astype(np.int64), row.astype(np.int64), seed)) \
            * (0.85 + 0.3 * _fbm(x, y, (1.5, 0.05), seed + 3)) * np.where(joint, 0.55, 1.0)
    else:  # wood planks along x
        pw = 0.15
        plank = np.floor(y / pw)
        grain = _fbm(x * 0.15, y * 3.0, (0.05, 0.01), seed + 4)
        f = (0.85 + 0.25 * _hash(plank.astype(np.int64), np.floor(x / 1.2 + plank * 0.37).astype(np.int64), seed)) \
            * (0.85 + 0.3 * grain) * np.where(np.abs(y / pw - plank - 0.5) > 0.47, 0.6, 1.0)
    return np.clip(base[None, :] * f[:, None], 0, 255)


def wall_albedo(p: np.ndarray, along: np.ndarray, wall_index: np.ndarray, env: Environment,
                posters: np.ndarray) -> np.ndarray:
    """BGR albedo (N, 3) of walls at world points p (N, 3); ``along`` is the distance along the wall."""
    base = np.asarray(env.wall_colour, dtype=float)
    z = p[:, 2]
    f = 0.93 + 0.1 * _fbm(along + 17.0 * wall_index, z, (0.8, 0.1), env.seed + 5)
    out = base[None, :] * f[:, None]
    skirting = z < 0.08
    out[skirting] = base * 0.45
    for w, a0, a1, z0, z1, b, g, r in posters:
        m = (wall_index == w) & (along >= a0) & (along <= a1) & (z >= z0) & (z <= z1)
        if np.any(m):
            stripe = 0.75 + 0.25 * (np.floor((along[m] - a0) / 0.07 + np.floor((z[m] - z0) / 0.09)) % 2)
            out[m] = np.array([b, g, r])[None, :] * stripe[:, None]
    return np.clip(out, 0, 255)


# ------------------------------------------------------------------------------------ geometry

def wall_quads(scene: Scene, env: Environment) -> list[np.ndarray]:
    """(4, 3) corners of the wall on every edge of the walkable polygons (outer rings and holes)."""
    if not env.walls:
        return []
    h = env.wall_height
    quads = []
    for poly in scene.walkable.polygons:
        for ring in (poly.outer, *poly.holes):
            ring = np.asarray(ring, dtype=float)
            for k in range(len(ring)):
                a, b = ring[k], ring[(k + 1) % len(ring)]
                if np.linalg.norm(b - a) < 1e-9:
                    continue
                quads.append(np.array([[a[0], a[1], 0.0], [b[0], b[1], 0.0], [b[0], b[1], h], [a[0], a[1], h]]))
    return quads


def _posters(quads: list[np.ndarray], env: Environment) -> np.ndarray:
    """Rows (wall, along0, along1, z0, z1, B, G, R) of posters placed deterministically."""
    rng = np.random.default_rng(env.seed)
    rows = []
    for _ in range(env.posters if quads else 0):
        w = int(rng.integers(len(quads)))
        length = float(np.linalg.norm(quads[w][1, :2] - quads[w][0, :2]))
        pw, ph = rng.uniform(0.4, 1.0), rng.uniform(0.4, 0.8)
        if length < pw + 0.4:
            continue
        a0 = rng.uniform(0.2, length - pw - 0.2)
        z0 = rng.uniform(1.0, max(1.05, min(env.wall_height - ph - 0.2, 1.6)))
        colour = _POSTER_PALETTE[rng.integers(len(_POSTER_PALETTE))]
        rows.append((w, a0, a0 + pw, z0, z0 + ph, *colour))
    return np.array(rows, dtype=float).reshape(-1, 8)


def _box_normal(box: Box, p: np.ndarray) -> np.ndarray:
    """Outward normals (N, 3) of a box at surface points p (N, 3)."""
    c, s = np.cos(box.yaw), np.sin(box.yaw)
    Rt = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    local = (p - box.centre) @ Rt.T / (np.asarray(box.size) / 2.0)
    k = np.argmax(np.abs(local), axis=1)
    n_local = np.zeros_like(local)
    n_local[np.arange(len(p)), k] = np.sign(local[np.arange(len(p)), k])
    return n_local @ Rt


def _rays_in_screen_box(camera: Camera, uv: np.ndarray, corners: np.ndarray) -> np.ndarray | None:
    """Indices of the rays (pixel coordinates ``uv``) inside the screen box of a convex shape's
    corners (points along its edges are projected, so lens distortion is covered); None when the
    shape reaches behind the camera (test every ray)."""
    c = np.asarray(corners, dtype=float)
    t = np.linspace(0.0, 1.0, 7)[:, None, None]
    pts = (c[None, :, None, :] * (1 - t[..., None]) + c[None, None, :, :] * t[..., None]).reshape(-1, 3)
    img, depth = camera.project(pts, return_depth=True)
    if np.any(~(depth > 1e-3)) or not np.all(np.isfinite(img)):
        return None
    u0, v0 = img.min(axis=0) - 2.0
    u1, v1 = img.max(axis=0) + 2.0
    return np.flatnonzero((uv[:, 0] >= u0) & (uv[:, 0] <= u1) & (uv[:, 1] >= v0) & (uv[:, 1] <= v1))


def static_depth(scene: Scene, camera: Camera, env: Environment) -> np.ndarray:
    """(H, W) float32 depth (m along the optical axis, inf for sky) of the empty scene; no textures."""
    quads = wall_quads(scene, env)
    return _cast(scene, camera, env, quads, np.zeros((0, 8)), 0.0, 0.0, full=True, depth_only=True)


def render_static(scene: Scene, camera: Camera, env: Environment, supersample: int = 2) -> StaticLayer:
    """Ray-cast the empty scene through ``camera``.

    Depth, kind, points and normals come from the pixel-centre rays; albedo and emissive radiance
    are averaged over ``supersample × supersample`` sub-pixel rays (anti-aliasing of textures).
    """
    H, W = camera.height, camera.width
    quads = wall_quads(scene, env)
    posters = _posters(quads, env)
    centre = _cast(scene, camera, env, quads, posters, 0.0, 0.0, full=True)
    if supersample > 1:
        offs = (np.arange(supersample) + 0.5) / supersample - 0.5
        alb = np.zeros((H * W, 3))
        emi = np.zeros((H * W, 3))
        for du in offs:
            for dv in offs:
                a, e = _cast(scene, camera, env, quads, posters, du, dv, full=False)
                alb += a
                emi += e
        alb /= supersample ** 2
        emi /= supersample ** 2
    else:
        alb, emi = centre["albedo"], centre["emissive"]
    f32 = lambda a, *shape: np.ascontiguousarray(a.reshape(H, W, *shape), dtype=np.float32)
    return StaticLayer(f32(centre["depth"]), centre["kind"].reshape(H, W).astype(np.uint8),
                       centre["surface"].reshape(H, W).astype(np.int16), f32(centre["points"], 3),
                       f32(centre["normal"], 3), f32(alb, 3), f32(emi, 3))


def _cast(scene, camera, env, quads, posters, du, dv, full, depth_only=False):
    H, W = camera.height, camera.width
    vv, uu = np.mgrid[0:H, 0:W]
    uv = np.column_stack([uu.ravel() + du, vv.ravel() + dv]).astype(float)
    o, d = camera.rays(uv)
    n = len(d)
    best = np.full(n, np.inf)
    kind = np.full(n, SKY, dtype=np.int64)
    surf = np.full(n, -1, dtype=np.int64)

    def consider(s, k, idx):
        closer = s < best
        best[closer] = s[closer]
        kind[closer] = k
        surf[closer] = idx

    def consider_in_view(corners, hit_fn, k, idx, offset=0.0):
        # Only rays through the primitive's screen box are cast (most obstacles are small).
        sel = _rays_in_screen_box(camera, uv, corners)
        if sel is None:
            s = hit_fn(d)
        else:
            if len(sel) == 0:
                return
            s = np.full(n, np.inf)
            s[sel] = hit_fn(d[sel])
        consider(np.where(np.isfinite(s), s - offset, np.inf), k, idx)

    consider(ray_plane_z(o, d, 0.0), FLOOR, 0)
    if env.ceiling:
        consider(ray_plane_z(o, d, env.wall_height), CEILING, 0)
    for i, q in enumerate(quads):
        consider_in_view(q, lambda dd, q=q: ray_quad(o, dd, q), WALL, i)
    for i, ob in enumerate(scene.obstacles):
        corners = ob.corners if isinstance(ob, Box) else np.asarray(ob.corners, float)
        consider_in_view(corners, lambda dd, ob=ob: ob.intersect(o, dd), OBSTACLE, i)
    for i, wdw in enumerate(env.windows):
        # Windows sit 2 mm in front of whatever they are drawn on (they win ties with walls).
        q = np.asarray(wdw.corners, float)
        consider_in_view(q, lambda dd, q=q: ray_quad(o, dd, q), WINDOW, i, offset=0.002)
    hit = np.isfinite(best)
    if depth_only:
        depth = np.where(hit, best * (d @ camera.optical_axis), np.inf)
        return np.ascontiguousarray(depth.reshape(camera.height, camera.width), dtype=np.float32)
    p = np.full((n, 3), np.nan)
    p[hit] = o + best[hit, None] * d[hit]
    albedo = np.zeros((n, 3))
    emissive = np.zeros((n, 3))
    normal = np.zeros((n, 3))
    m = kind == FLOOR
    albedo[m] = floor_albedo(p[m, :2], env)
    normal[m] = [0.0, 0.0, 1.0]
    m = kind == CEILING
    if np.any(m):
        cf = 0.95 + 0.05 * value_noise(p[m, 0], p[m, 1], 0.5, env.seed + 9)
        albedo[m] = np.asarray(env.ceiling_colour)[None, :] * cf[:, None]
        normal[m] = [0.0, 0.0, -1.0]
    m = np.flatnonzero(kind == WALL)
    if len(m):
        widx = surf[m]
        q0 = np.array([q[0] for q in quads])[widx]
        q1 = np.array([q[1] for q in quads])[widx]
        edge = q1[:, :2] - q0[:, :2]
        length = np.linalg.norm(edge, axis=1)
        along = np.einsum("ij,ij->i", p[m, :2] - q0[:, :2], edge) / length
        albedo[m] = wall_albedo(p[m], along, widx, env, posters)
        nrm = np.column_stack([-edge[:, 1], edge[:, 0], np.zeros(len(m))]) / length[:, None]
        normal[m] = nrm
    m = np.flatnonzero(kind == OBSTACLE)
    for i, ob in enumerate(scene.obstacles):
        sel = m[surf[m] == i]
        if not len(sel):
            continue
        colour = np.asarray(env.obstacle_colours.get(ob.name, _OBSTACLE_PALETTE[i % len(_OBSTACLE_PALETTE)]), float)
        pts = p[sel]
        if isinstance(ob, Box):
            nrm = _box_normal(ob, pts)
            top = nrm[:, 2] > 0.5
            grain = 0.85 + 0.25 * _fbm(pts[:, 0] * 0.3 + pts[:, 2], pts[:, 1] * 3 + pts[:, 2] * 2, (0.05, 0.015),
                                       env.seed + 11 + i)
            f = grain * np.where(top, 1.15, 0.85)
        else:
            q = np.asarray(ob.corners, float)
            nrm = np.cross(q[1] - q[0], q[2] - q[0])
            nrm = np.broadcast_to(nrm / np.linalg.norm(nrm), pts.shape).copy()
            f = 0.9 + 0.15 * _fbm(pts[:, 0] + pts[:, 1], pts[:, 2], (0.05, 0.01), env.seed + 13 + i)
        albedo[sel] = np.clip(colour[None, :] * f[:, None], 0, 255)
        normal[sel] = nrm
    m = kind == WINDOW
    if np.any(m):
        emissive[m] = np.array([w.radiance for w in env.windows], dtype=float)[surf[m]]
        quads = [np.asarray(w.corners, float) for w in env.windows]
        nrm = np.array([np.cross(q[1] - q[0], q[2] - q[0]) for q in quads])
        normal[m] = (nrm / np.linalg.norm(nrm, axis=1, keepdims=True))[surf[m]]
    m = kind == SKY
    if np.any(m):
        elev = np.clip(d[m, 2], 0.0, 1.0) ** 0.5
        emissive[m] = (np.asarray(env.sky_horizon)[None, :] * (1 - elev[:, None])
                       + np.asarray(env.sky_zenith)[None, :] * elev[:, None])
    if not full:
        return albedo, emissive
    # Normals face the camera (walls and patches are two-sided).
    flip = np.einsum("ij,ij->i", normal, d) > 0
    normal[flip] *= -1
    depth = np.where(hit, best * (d @ camera.optical_axis), np.inf)
    return {"depth": depth, "kind": kind, "surface": surf, "points": p, "normal": normal,
            "albedo": albedo, "emissive": emissive}
