"""People traced into one camera's image (step 2 of :class:`worldtrack.synth.render.Renderer`).

Each body part's screen box comes from its image conic (exact for ellipsoids; a capsule's box is the
union of its end spheres' boxes), the boxes are joined per person, and :func:`kernels.trace_people`
ray-casts only inside them, z-buffered against the static scene's depth: per pixel the depth, the
person's instance id and the part hit, and per person the pixels they cover when alone (the
visibility's denominator). :func:`shadow_boxes` and :func:`bounding_spheres` bound the shadow pass
(step 3) the same way.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from worldtrack.geometry.camera import Camera
from worldtrack.geometry.quadric import dual_conic_bbox
from worldtrack.synth import kernels
from worldtrack.synth.bodies import CAPSULE, ELLIPSOID, PARTS_PER_PERSON, PartArrays


@dataclass
class PeopleBuffers:
    zbuf: np.ndarray
    inst: np.ndarray
    part_hit: np.ndarray
    alone: np.ndarray


def _intrinsics(camera: Camera) -> np.ndarray:
    K = camera.K
    return np.array([K[0, 0], K[1, 1], K[0, 2], K[1, 2], K[0, 1], *camera.dist], dtype=np.float64)


def camera_frame_rays(camera: Camera) -> np.ndarray:
    """(H, W, 3) float64 unit rays of every pixel in the camera frame (distortion undone)."""
    v, u = np.mgrid[0:camera.height, 0:camera.width]
    uv = np.stack([u, v], axis=-1).astype(float)
    _, d = camera.moved(np.eye(3), np.zeros(3)).rays(uv)      # world frame = camera frame
    return np.ascontiguousarray(d, dtype=np.float64)


# ------------------------------------------------------------------------------------ screen boxes

def _rect_edge_points(x0: np.ndarray, x1: np.ndarray, y0: np.ndarray, y1: np.ndarray, n: int = 9) -> np.ndarray:
    """(B, 4n, 2) points along the edges of the rectangles ``[x0, x1] × [y0, y1]`` (each (B,)):
    ``n`` evenly spaced points, corners included, on the y0, y1, x0 and x1 edges in turn."""
    t = np.linspace(0.0, 1.0, n)[None, :]
    x0, x1, y0, y1 = (np.asarray(a, dtype=float)[:, None] for a in (x0, x1, y0, y1))
    xs, ys = x0 + (x1 - x0) * t, y0 + (y1 - y0) * t
    edge_x = np.concatenate([xs, xs, np.repeat(x0, n, 1), np.repeat(x1, n, 1)], axis=1)
    edge_y = np.concatenate([np.repeat(y0, n, 1), np.repeat(y1, n, 1), ys, ys], axis=1)
    return np.stack([edge_x, edge_y], axis=-1)


def _blob_boxes(camera: Camera, centres: np.ndarray, S: np.ndarray, margin: float = 1.5) -> np.ndarray:
    """Pixel boxes (B, 4) float [u0, u1, v0, v1] of ellipsoids ``(x − c)ᵀ S⁻¹ (x − c) ≤ 1``.

    NaN rows where the ellipsoid reaches behind the camera (no bounded image).
    """
    B = len(centres)
    Q = np.zeros((B, 4, 4))
    Q[:, :3, :3] = S - centres[:, :, None] * centres[:, None, :]
    Q[:, :3, 3] = -centres
    Q[:, 3, :3] = -centres
    Q[:, 3, 3] = -1.0
    P = camera.P
    dual = P @ Q @ P.T
    box = dual_conic_bbox(dual)
    a = camera.optical_axis
    reach = np.sqrt(np.einsum("i,bij,j->b", a, S, a))
    depth = camera.depth(centres)
    in_front = depth - reach > 1e-3
    box[~in_front] = np.nan
    behind = depth + reach < 0.0          # entirely behind the camera: never hit
    box[behind] = [np.inf, -np.inf, np.inf, -np.inf]
    if camera.has_distortion:
        ok = np.all(np.isfinite(box), axis=1)
        pts = _rect_edge_points(*(box[ok, k] for k in range(4)))
        real = camera.distort_pixels(pts.reshape(-1, 2)).reshape(pts.shape)
        box[ok] = np.column_stack([real[..., 0].min(1), real[..., 0].max(1), real[..., 1].min(1), real[..., 1].max(1)])
        margin += 1.0
    box[:, [0, 2]] -= margin
    box[:, [1, 3]] += margin
    return box


def part_boxes(camera: Camera, parts: PartArrays) -> np.ndarray:
    """Integer pixel boxes (P, 4) ``[u0, u1) × [v0, v1)`` containing each part's image.

    Clamped to the extended canvas ``[−W, 2W) × [−H, 2H)``; a part reaching behind the camera gets
    the whole canvas.
    """
    W, H = camera.width, camera.height
    P = len(parts)
    ell = parts.kind == ELLIPSOID
    cap = ~ell
    centres = np.concatenate([parts.centre[ell], parts.centre[cap], parts.end[cap]])
    S_e = parts.shape_matrices()[ell]
    r2 = parts.radius[cap] ** 2
    S_c = r2[:, None, None] * np.eye(3)[None]
    S = np.concatenate([S_e, S_c, S_c])
    box = _blob_boxes(camera, centres, S)
    out = np.empty((P, 4))
    ne, nc = int(ell.sum()), int(cap.sum())
    out[ell] = box[:ne]
    ba, bb = box[ne:ne + nc], box[ne + nc:]
    out[cap] = np.column_stack([np.minimum(ba[:, 0], bb[:, 0]), np.maximum(ba[:, 1], bb[:, 1]),
                                np.minimum(ba[:, 2], bb[:, 2]), np.maximum(ba[:, 3], bb[:, 3])])
    bad = np.any(np.isnan(out), axis=1)
    empty = ~bad & (np.isinf(out[:, 0]) & np.isinf(out[:, 1]))
    lo = np.array([-W, -W, -H, -H], dtype=float)
    hi = np.array([2 * W, 2 * W, 2 * H, 2 * H], dtype=float)
    out[bad] = [-W, 2 * W, -H, 2 * H]
    out[empty] = [0, -1, 0, -1]
    ib = np.empty((P, 4), dtype=np.int64)
    ib[:, [0, 2]] = np.floor(np.clip(out[:, [0, 2]], lo[[0, 2]], hi[[0, 2]]))
    ib[:, [1, 3]] = np.ceil(np.clip(out[:, [1, 3]], lo[[1, 3]], hi[[1, 3]])) + 1
    ib[:, [1, 3]] = np.minimum(ib[:, [1, 3]], [2 * W, 2 * H])
    return ib


def bounding_spheres(parts: PartArrays) -> np.ndarray:
    """(P, 4) centre and radius of a sphere containing each part."""
    mid = np.where((parts.kind == CAPSULE)[:, None], (parts.centre + parts.end) / 2, parts.centre)
    half = np.where(parts.kind == CAPSULE, np.linalg.norm(parts.end - parts.centre, axis=1) / 2, 0.0)
    return np.column_stack([mid, half + parts.radius])


def shadow_boxes(camera: Camera, parts: PartArrays, n_people: int, light_dir: np.ndarray) -> np.ndarray:
    """Integer pixel boxes (N, 4), clipped to the image, containing each person's floor shadow.

    Each part's bounding sphere (radius ρ) casts a shadow within ρ / L_z of its centre's shadow
    point on the floor; the person's floor box is the union of those discs and the person's own
    footprint, and its image box comes from points along the box's edges (lens distortion bends
    them). A box reaching behind the camera gives the whole image.
    """
    W, H = camera.width, camera.height
    L = np.asarray(light_dir, dtype=float)
    L = L / np.linalg.norm(L)
    lz = max(L[2], 0.05)
    sph = bounding_spheres(parts)
    foot = sph[:, :3] - (sph[:, 2:3] / lz) * L[None, :]
    rad = sph[:, 3] / lz
    start = np.arange(n_people) * PARTS_PER_PERSON
    x0 = np.minimum(np.minimum.reduceat(foot[:, 0] - rad, start), np.minimum.reduceat(sph[:, 0], start) - 0.3)
    x1 = np.maximum(np.maximum.reduceat(foot[:, 0] + rad, start), np.maximum.reduceat(sph[:, 0], start) + 0.3)
    y0 = np.minimum(np.minimum.reduceat(foot[:, 1] - rad, start), np.minimum.reduceat(sph[:, 1], start) - 0.3)
    y1 = np.maximum(np.maximum.reduceat(foot[:, 1] + rad, start), np.maximum.reduceat(sph[:, 1], start) + 0.3)
    edge = _rect_edge_points(x0, x1, y0, y1)
    pts = np.concatenate([edge, np.zeros(edge.shape[:-1] + (1,))], axis=-1)   # (N, 36, 3) on the floor
    uv = camera.project(pts)
    ok = np.all(np.isfinite(uv), axis=(1, 2))
    u0 = np.floor(np.nanmin(uv[..., 0], axis=1, initial=np.inf, where=np.isfinite(uv[..., 0]))) - 2
    u1 = np.ceil(np.nanmax(uv[..., 0], axis=1, initial=-np.inf, where=np.isfinite(uv[..., 0]))) + 3
    v0 = np.floor(np.nanmin(uv[..., 1], axis=1, initial=np.inf, where=np.isfinite(uv[..., 1]))) - 2
    v1 = np.ceil(np.nanmax(uv[..., 1], axis=1, initial=-np.inf, where=np.isfinite(uv[..., 1]))) + 3
    box = np.column_stack([np.clip(u0, 0, W), np.clip(u1, 0, W), np.clip(v0, 0, H), np.clip(v1, 0, H)])
    box[~ok] = [0, W, 0, H]
    return box.astype(np.int64)


def people_pass(camera: Camera, rays: np.ndarray, parts: PartArrays, n_people: int, person_ids: np.ndarray,
                zbuf_init: np.ndarray, extended: bool = True) -> PeopleBuffers:
    """Trace people into a copy of ``zbuf_init`` with the Numba kernel.

    ``extended=False`` clips the boxes to the image (faster; the alone counts then ignore the
    image border) — for views whose visibility is not reported (the stereo right view, mirrors).
    """
    H, W = zbuf_init.shape
    zbuf = np.array(zbuf_init, dtype=np.float32, copy=True)
    inst = np.zeros((H, W), dtype=np.int32)
    part_hit = np.full((H, W), -1, dtype=np.int32)
    alone = np.zeros(n_people, dtype=np.int64)
    if n_people == 0:
        return PeopleBuffers(zbuf, inst, part_hit, alone)
    boxes = part_boxes(camera, parts)
    if not extended:
        boxes[:, :2] = np.clip(boxes[:, :2], 0, W)
        boxes[:, 2:] = np.clip(boxes[:, 2:], 0, H)
    start = np.arange(n_people + 1, dtype=np.int64) * PARTS_PER_PERSON
    pbox = np.column_stack([
        np.minimum.reduceat(boxes[:, 0], start[:-1]), np.maximum.reduceat(boxes[:, 1], start[:-1]),
        np.minimum.reduceat(boxes[:, 2], start[:-1]), np.maximum.reduceat(boxes[:, 3], start[:-1])]).astype(np.int64)
    ray_camera = kernels.RayCamera(rays, np.ascontiguousarray(camera.R.T), camera.centre.astype(np.float64),
                                   camera.optical_axis.astype(np.float64), _intrinsics(camera))
    people = kernels.PackedPeople(np.ascontiguousarray(parts.geometry()), boxes, pbox, start,
                                  np.asarray(person_ids, dtype=np.int64))
    kernels.trace_people(ray_camera, people, zbuf, inst, part_hit, alone)
    return PeopleBuffers(zbuf, inst, part_hit, alone)
