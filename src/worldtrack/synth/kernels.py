"""Ray casting of people's parts: the Numba kernels and the plain NumPy references they must match.

Two kernels do all per-pixel work on people:

* :func:`trace_people` — camera rays against each person's parts inside that person's screen box,
  z-buffered against what is already there (the static scene), writing depth, instance id and the
  part hit; it also counts, per person, the pixels that person covers when rendered alone on the
  image plane extended beyond the image (the denominator of the ground truth's visibility);
* :func:`trace_shadows` — rays from floor points towards the light against each person's parts
  inside the person's shadow box on the screen.

Parts are packed as rows of :meth:`worldtrack.synth.bodies.PartArrays.geometry`:
``[kind, a(3), b(3), r, M(9)]`` — an ellipsoid ``|M·(p − a)| = 1`` (kind 0) or a capsule of radius
``r`` around the segment a–b (kind 1).

The references (:func:`trace_people_reference`, :func:`trace_shadows_reference`) cast every pixel
against every part with :mod:`worldtrack.geometry.raycast`; tests check that kernel and reference
agree on small images.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from worldtrack.geometry._kernels import distort, undistort
from worldtrack.geometry.camera import Camera
from worldtrack.geometry.raycast import ray_capsule, ray_ellipsoid

_EPS = 1e-9
_INF = np.inf


@njit(cache=True, inline="always")
def _sphere_hit(ox, oy, oz, dx, dy, dz, cx, cy, cz, r):
    """Nearest positive parameter of a unit-direction ray with a sphere, or inf."""
    px, py, pz = ox - cx, oy - cy, oz - cz
    b = px * dx + py * dy + pz * dz
    c = px * px + py * py + pz * pz - r * r
    disc = b * b - c
    if disc < 0.0:
        return _INF
    sq = math.sqrt(disc)
    s = -b - sq
    if s > _EPS:
        return s
    s = -b + sq
    if s > _EPS:
        return s
    return _INF


@njit(cache=True)
def _hit(g, p, ox, oy, oz, dx, dy, dz):
    """Nearest positive ray parameter of part ``p`` of the packed geometry ``g``, or inf."""
    if g[p, 0] == 0.0:
        # Ellipsoid: in local coordinates l = M·(x − a) it is the unit sphere.
        qx, qy, qz = ox - g[p, 1], oy - g[p, 2], oz - g[p, 3]
        lx = g[p, 8] * qx + g[p, 9] * qy + g[p, 10] * qz
        ly = g[p, 11] * qx + g[p, 12] * qy + g[p, 13] * qz
        lz = g[p, 14] * qx + g[p, 15] * qy + g[p, 16] * qz
        ex = g[p, 8] * dx + g[p, 9] * dy + g[p, 10] * dz
        ey = g[p, 11] * dx + g[p, 12] * dy + g[p, 13] * dz
        ez = g[p, 14] * dx + g[p, 15] * dy + g[p, 16] * dz
        a = ex * ex + ey * ey + ez * ez
        b = lx * ex + ly * ey + lz * ez
        c = lx * lx + ly * ly + lz * lz - 1.0
        disc = b * b - a * c
        if disc < 0.0:
            return _INF
        sq = math.sqrt(disc)
        s = (-b - sq) / a
        if s > _EPS:
            return s
        s = (-b + sq) / a
        if s > _EPS:
            return s
        return _INF
    # Capsule: the cylinder's side between the end planes, and the two end spheres.
    ax_, ay_, az_ = g[p, 1], g[p, 2], g[p, 3]
    bx, by, bz = g[p, 4] - ax_, g[p, 5] - ay_, g[p, 6] - az_
    r = g[p, 7]
    qx, qy, qz = ox - ax_, oy - ay_, oz - az_
    baba = bx * bx + by * by + bz * bz
    bard = bx * dx + by * dy + bz * dz
    baoa = bx * qx + by * qy + bz * qz
    rdoa = dx * qx + dy * qy + dz * qz
    oaoa = qx * qx + qy * qy + qz * qz
    best = _INF
    qa = baba - bard * bard
    if qa > 1e-12 * max(baba, 1e-12):
        qb = baba * rdoa - baoa * bard
        qc = baba * oaoa - baoa * baoa - r * r * baba
        disc = qb * qb - qa * qc
        if disc >= 0.0:
            s = (-qb - math.sqrt(disc)) / qa
            y = baoa + s * bard
            if s > 0.0 and y > 0.0 and y < baba:
                best = s
    s = _sphere_hit(ox, oy, oz, dx, dy, dz, ax_, ay_, az_, r)
    if s < best:
        best = s
    s = _sphere_hit(ox, oy, oz, dx, dy, dz, g[p, 4], g[p, 5], g[p, 6], r)
    if s < best:
        best = s
    return best


@njit(cache=True)
def _pixel_ray(u, v, intr):
    """Camera-frame unit ray of pixel (u, v): intr = [fx, fy, cx, cy, skew, k1, k2, p1, p2, k3]."""
    y = (v - intr[3]) / intr[1]
    x = (u - intr[2] - intr[4] * y) / intr[0]
    k1, k2, p1, p2, k3 = intr[5], intr[6], intr[7], intr[8], intr[9]
    if k1 != 0.0 or k2 != 0.0 or p1 != 0.0 or p2 != 0.0 or k3 != 0.0:
        xd, yd = x, y
        # The fixed-point inversion of Camera.undistort_normalised.
        x, y = undistort(xd, yd, k1, k2, p1, p2, k3, 200, 1e-12)
        # Beyond the lens's monotonic range the pixel has no ray (as in Camera): no hit.
        ex, ey = distort(x, y, k1, k2, p1, p2, k3)
        if not max(abs(ex - xd), abs(ey - yd)) <= 1e-7:
            return math.nan, math.nan, math.nan
    n = math.sqrt(x * x + y * y + 1.0)
    return x / n, y / n, 1.0 / n


class RayCamera(NamedTuple):
    """A camera as :func:`trace_people` casts rays from it.

    rays : (H, W, 3) float64 — unit rays of the image's pixels in the camera frame
    Rt : (3, 3) — camera → world rotation (``Rᵀ``); origin : (3,) camera centre, metres
    axis : (3,) — optical axis in world coordinates (depth = s·(d·axis))
    intr : (10,) — [fx, fy, cx, cy, skew, k1, k2, p1, p2, k3], for pixels outside the image
    """

    rays: np.ndarray
    Rt: np.ndarray
    origin: np.ndarray
    axis: np.ndarray
    intr: np.ndarray


class PackedPeople(NamedTuple):
    """People's parts as :func:`trace_people` reads them.

    geom : (P, 17) — packed parts, person-major
    part_box : (P, 4) int — pixel box [u0, u1) × [v0, v1) outside which part p is never hit
    person_box : (N, 4) int — union of the person's part boxes (may extend beyond the image)
    person_start : (N + 1,) int — parts of person n are ``person_start[n]:person_start[n + 1]``
    person_id : (N,) int — value written to ``inst``
    """

    geom: np.ndarray
    part_box: np.ndarray
    person_box: np.ndarray
    person_start: np.ndarray
    person_id: np.ndarray


@njit(cache=True)
def trace_people(camera, people, zbuf, inst, part_hit, alone):
    """Z-buffered ray casting of people (modifies ``zbuf``, ``inst``, ``part_hit``, ``alone``).

    Parameters
    ----------
    camera : RayCamera
    people : PackedPeople
    zbuf : (H, W) float32 — depth along the optical axis (m) of what is already drawn
    inst : (H, W) int32; part_hit : (H, W) int32 — global part index, −1 where no person
    alone : (N,) int64 — out: pixels the person covers when rendered alone, image border ignored
    """
    rays, Rt, origin, axis, intr = camera
    geom, part_box, person_box, person_start, person_id = people
    H, W = zbuf.shape
    for n in range(person_start.shape[0] - 1):
        p0, p1 = person_start[n], person_start[n + 1]
        count = 0
        for v in range(person_box[n, 2], person_box[n, 3]):
            for u in range(person_box[n, 0], person_box[n, 1]):
                inside = u >= 0 and u < W and v >= 0 and v < H
                # Quick reject: pixel outside every part box of this person.
                any_box = False
                for p in range(p0, p1):
                    if u >= part_box[p, 0] and u < part_box[p, 1] and v >= part_box[p, 2] and v < part_box[p, 3]:
                        any_box = True
                        break
                if not any_box:
                    continue
                if inside:
                    cx, cy, cz = rays[v, u, 0], rays[v, u, 1], rays[v, u, 2]
                else:
                    cx, cy, cz = _pixel_ray(float(u), float(v), intr)
                dx = Rt[0, 0] * cx + Rt[0, 1] * cy + Rt[0, 2] * cz
                dy = Rt[1, 0] * cx + Rt[1, 1] * cy + Rt[1, 2] * cz
                dz = Rt[2, 0] * cx + Rt[2, 1] * cy + Rt[2, 2] * cz
                best = _INF
                bp = -1
                for p in range(p0, p1):
                    if u < part_box[p, 0] or u >= part_box[p, 1] or v < part_box[p, 2] or v >= part_box[p, 3]:
                        continue
                    s = _hit(geom, p, origin[0], origin[1], origin[2], dx, dy, dz)
                    if s < best:
                        best = s
                        bp = p
                if bp >= 0:
                    count += 1
                    if inside:
                        depth = best * (dx * axis[0] + dy * axis[1] + dz * axis[2])
                        if depth < zbuf[v, u]:
                            zbuf[v, u] = depth
                            inst[v, u] = person_id[n]
                            part_hit[v, u] = bp
        alone[n] = count


@njit(cache=True)
def trace_shadows(points, receiver, light, geom, sphere, person_box, person_start, shadow):
    """Mark receiver pixels whose point sees a person's part towards the light (modifies ``shadow``).

    Parameters
    ----------
    points : (H, W, 3) float32 — world point seen at each pixel (metres)
    receiver : (H, W) bool — pixels that can receive a shadow (bare floor)
    light : (3,) unit direction towards the light
    geom : (P, 17) packed parts; sphere : (P, 4) bounding sphere (centre, radius) of each part
    person_box : (N, 4) int — screen box of each person's shadow, clipped to the image
    person_start : (N + 1,) int
    shadow : (H, W) bool — out
    """
    lx, ly, lz = light[0], light[1], light[2]
    for n in range(person_start.shape[0] - 1):
        p0, p1 = person_start[n], person_start[n + 1]
        for v in range(person_box[n, 2], person_box[n, 3]):
            for u in range(person_box[n, 0], person_box[n, 1]):
                if not receiver[v, u] or shadow[v, u]:
                    continue
                ox, oy, oz = points[v, u, 0], points[v, u, 1], points[v, u, 2]
                for p in range(p0, p1):
                    # Distance from the bounding sphere's centre to the ray (half-line).
                    qx, qy, qz = sphere[p, 0] - ox, sphere[p, 1] - oy, sphere[p, 2] - oz
                    t = qx * lx + qy * ly + qz * lz
                    r = sphere[p, 3]
                    if t < -r:
                        continue
                    d2 = qx * qx + qy * qy + qz * qz - t * t
                    if d2 > r * r:
                        continue
                    if _hit(geom, p, ox, oy, oz, lx, ly, lz) < _INF:
                        shadow[v, u] = True
                        break


# ------------------------------------------------------------------------------------ references

def hit_parts_reference(origin: np.ndarray, d: np.ndarray, geom: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Nearest hit of rays (N,) against every packed part, with :mod:`geometry.raycast`.

    Returns
    -------
    s : (N,) ray parameter, inf for a miss; part : (N,) index of the part hit, −1 for a miss
    """
    best = np.full(len(d), np.inf)
    which = np.full(len(d), -1, dtype=np.int64)
    for p, row in enumerate(geom):
        if row[0] == 0:
            M = row[8:17].reshape(3, 3)
            radii = 1.0 / np.linalg.norm(M, axis=1)
            s = ray_ellipsoid(origin, d, row[1:4], radii, M * radii[:, None])
        else:
            s = ray_capsule(origin, d, row[1:4], row[4:7], row[7])
        closer = s < best
        best[closer] = s[closer]
        which[closer] = p
    return best, which


def trace_people_reference(camera: Camera, geom: np.ndarray, person_start: np.ndarray, person_id: np.ndarray,
                           zbuf: np.ndarray, margin: tuple[int, int] | None = None):
    """Plain NumPy version of :func:`trace_people`: every pixel against every part.

    ``margin`` (mu, mv) extends the canvas by that many pixels on each side for the alone counts
    (the kernel's boxes must then lie within it). Returns ``(zbuf, inst, part_hit, alone)``.
    """
    H, W = zbuf.shape
    mu, mv = margin if margin is not None else (0, 0)
    vv, uu = np.mgrid[-mv:H + mv, -mu:W + mu]
    uv = np.column_stack([uu.ravel(), vv.ravel()]).astype(float)
    origin, d = camera.rays(uv)
    n_people = len(person_start) - 1
    alone = np.zeros(n_people, dtype=np.int64)
    inside = (uv[:, 0] >= 0) & (uv[:, 0] < W) & (uv[:, 1] >= 0) & (uv[:, 1] < H)
    zb = zbuf.astype(np.float64).ravel().copy()
    inst = np.zeros(H * W, dtype=np.int32)
    part_hit = np.full(H * W, -1, dtype=np.int32)
    flat = (uv[inside, 1].astype(int) * W + uv[inside, 0].astype(int))
    depth_per_s = d @ camera.optical_axis
    for n in range(n_people):
        p0, p1 = person_start[n], person_start[n + 1]
        s, which = hit_parts_reference(origin, d, geom[p0:p1])
        alone[n] = int(np.count_nonzero(np.isfinite(s)))
        depth = (s * depth_per_s)[inside]
        closer = depth < zb[flat]
        zb[flat[closer]] = depth[closer]
        inst[flat[closer]] = person_id[n]
        part_hit[flat[closer]] = (which[inside][closer] + p0)
    return zb.reshape(H, W).astype(np.float32), inst.reshape(H, W), part_hit.reshape(H, W), alone


def trace_shadows_reference(points: np.ndarray, receiver: np.ndarray, light: np.ndarray,
                            geom: np.ndarray) -> np.ndarray:
    """Plain NumPy version of :func:`trace_shadows`: every receiver pixel against every part."""
    H, W = receiver.shape
    shadow = np.zeros((H, W), dtype=bool)
    idx = np.flatnonzero(receiver.ravel())
    if len(idx) == 0 or len(geom) == 0:
        return shadow
    o = points.reshape(-1, 3)[idx].astype(np.float64)
    d = np.ascontiguousarray(np.broadcast_to(np.asarray(light, dtype=float), o.shape))
    s, _ = hit_parts_reference(o, d, geom)
    shadow.ravel()[idx] = np.isfinite(s)
    return shadow
