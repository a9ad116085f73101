"""Per-frame rendering: people into the static scene, shadows, reflections, shading, the sensor.

For one camera and frame :class:`Renderer` does:

1. the **static layer** (floor, walls, obstacles; :func:`environment.render_static`), cached per
   camera pose, so a fixed camera pays for it once;
2. **people**: each part's screen box from its image conic (exact for ellipsoids; a capsule's box
   is the union of its end spheres' boxes), then :func:`kernels.trace_people` over those boxes,
   z-buffered against the static depth — depth, instance id, part hit (:mod:`people_pass`);
3. **shadows**: :func:`kernels.trace_shadows` from the bare floor towards the light inside each
   person's projected shadow box;
4. optional **floor reflection**: the people mirrored in the floor, traced like people;
5. **shading** (Lambert, ambient + directional; face and stripe textures) and the camera
   (:mod:`photometry`: exposure, light tint, white balance, vignetting, blur, noise);
6. **sensors** (:mod:`sensors`): disparity or RGB-D depth from a second viewpoint's depth;
7. **visibility ground truth**: per person the visible pixel count over the alone count, and
   whether the top of the head and the ground point are seen.

Visibility ``vis`` (gt.csv): the number of pixels whose instance id is the person, divided by the
number of pixels the person covers when rendered alone (no obstacles, no other people) on the
camera's image plane extended beyond the image border — the same camera model evaluated on a canvas
three times the image's width and height, centred on it. Obstacles, other people and the image
border all reduce it; 0 when the person is not in view at all.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from worldtrack.geometry.camera import Camera
from worldtrack.scene.model import Scene
from worldtrack.synth import kernels
from worldtrack.synth.bodies import ELLIPSOID, PARTS_PER_PERSON, TEX_HEAD, TEX_STRIPES, PartArrays
from worldtrack.synth.environment import FLOOR, Environment, StaticLayer, render_static, static_depth, value_noise
from worldtrack.synth.people_pass import PeopleBuffers, bounding_spheres, camera_frame_rays, people_pass, shadow_boxes
from worldtrack.synth.photometry import (WB_UNITY, Light, SensorNoise, WhiteBalance, expose, grey_world_mean,
                                         vignetting_map)
from worldtrack.synth.sensors import SensorSpec, kinect_depth, second_view, stereo_measurement


@dataclass(frozen=True)
class RenderOptions:
    """Rendering switches shared by all cameras of a sequence.

    Parameters
    ----------
    noise : SensorNoise
    shadow_strength : float in [0, 1] — share of the direct light a person's shadow removes
    reflection : float in [0, 1] — floor reflectivity for people's mirror images (0: off)
    supersample : int or None — sub-samples per axis for the static textures; None: 2 for images
        up to 320×240 (where floor texture would alias), 1 above
    """

    noise: SensorNoise = field(default_factory=SensorNoise)
    shadow_strength: float = 0.6
    reflection: float = 0.0
    supersample: int | None = None


@dataclass
class SynthFrame:
    """One camera's view of one frame.

    Attributes
    ----------
    image : (H, W, 3) uint8, BGR
    depth : (H, W) float32, metres along the optical axis, exact (inf where only sky)
    instance : (H, W) int32 — person id, 0 = background
    camera : Camera — the camera at this frame (moves for a robot camera)
    time : float, seconds
    wb_gains : (r, b) int — white-balance gains, 0–1023, 512 = ×1
    light_level : float
    shadow : (H, W) bool — floor pixels in a person's cast shadow
    sensor_depth : (H, W) float32 or None — measured depth (m, 0 = invalid) for stereo / RGB-D
    disparity : (H, W) float32 or None — measured disparity (px, 0 = invalid) for stereo
    """

    image: np.ndarray
    depth: np.ndarray
    instance: np.ndarray
    camera: Camera
    time: float
    wb_gains: tuple[int, int]
    light_level: float
    shadow: np.ndarray
    sensor_depth: np.ndarray | None = None
    disparity: np.ndarray | None = None


@dataclass
class Visibility:
    """Per person (rows in the order of the frame's people) for one camera."""

    visible_pixels: np.ndarray
    alone_pixels: np.ndarray
    head_visible: np.ndarray
    feet_visible: np.ndarray

    @property
    def fraction(self) -> np.ndarray:
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(self.alone_pixels > 0, self.visible_pixels / np.maximum(self.alone_pixels, 1), 0.0)


def _camera_key(camera: Camera) -> tuple:
    return (camera.id, camera.width, camera.height, camera.K.tobytes(), camera.dist.tobytes(),
            camera.R.tobytes(), camera.t.tobytes())


# ------------------------------------------------------------------------------------ shading

def _head_albedo(local: np.ndarray, skin: np.ndarray, hair: np.ndarray, style: np.ndarray) -> np.ndarray:
    """Face and hair on the head's unit sphere: local (K, 3) = (forward, left, up)."""
    lx, ly, lz = local[:, 0], local[:, 1], local[:, 2]
    out = skin.copy()
    short = (lz > 0.42 - 0.25 * np.clip(-lx, 0, 1)) | ((lx < -0.25) & (lz > -0.25))
    long_ = short | ((lx < 0.2) & (lz > -0.85)) | ((np.abs(ly) > 0.7) & (lz > -0.6) & (lx < 0.5))
    is_hair = np.where(style == 2, long_, short) & (style > 0)
    out[is_hair] = hair[is_hair]
    face = (lx > 0.45) & ~is_hair
    for s in (-1.0, 1.0):
        eye = face & (((ly - 0.33 * s) ** 2) / 0.012 + ((lz - 0.12) ** 2) / 0.004 < 1.0)
        out[eye] = [40.0, 35.0, 35.0]
        brow = face & (np.abs(lz - 0.3) < 0.045) & (np.abs(ly - 0.33 * s) < 0.16)
        out[brow] = hair[brow] * 0.8
    mouth = face & (np.abs(lz + 0.45) < 0.04) & (np.abs(ly) < 0.22)
    out[mouth] = [70.0, 70.0, 150.0]
    return out


def _fabric(local: np.ndarray, capsule: np.ndarray, seed: np.ndarray) -> np.ndarray:
    """Multiplicative cloth/skin texture (K,) around 1 from part-local metric coordinates (K, 3)."""
    x, y, z = local[:, 0], local[:, 1], local[:, 2]
    along = np.where(capsule, x, z)
    around = np.where(capsule, np.arctan2(z, y), np.arctan2(y, x)) * 0.08
    a = along + 7.31 * seed
    return 0.8 + 0.25 * value_noise(a, around, 0.05, 3) + 0.15 * value_noise(a, around, 0.018, 4)


def shade_people(camera: Camera, rays: np.ndarray, buffers: PeopleBuffers, parts: PartArrays,
                 hair: np.ndarray, hair_style: np.ndarray, light: Light,
                 person_ids: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Flat indices ``idx`` (K,) of the person pixels and their radiance (K, 3).

    Lambert shading of each part's albedo, with the face/hair and stripe textures and a fabric
    texture in the part's own coordinates (so it moves with the body; seeded by the person id)."""
    flat_hit = buffers.part_hit.ravel()
    idx = np.flatnonzero(flat_hit >= 0)
    if len(idx) == 0:
        return idx, np.zeros((0, 3), np.float32)
    p = flat_hit[idx]
    d = rays.reshape(-1, 3)[idx] @ camera.R                            # world directions
    s = buffers.zbuf.ravel()[idx] / (d @ camera.optical_axis)
    X = camera.centre + s[:, None] * d
    # Part-local metric coordinates l = A·(x − c) (A: rows = the part's axes).
    A = parts.axes[p]
    metric = np.einsum("kij,kj->ki", A, X - parts.centre[p])
    ell = parts.kind[p] == ELLIPSOID
    normal = np.empty_like(X)
    r2 = parts.radii[p[ell]] ** 2
    normal[ell] = np.einsum("kji,kj->ki", A[ell], metric[ell] / r2)   # ∇ of Σ (l_i / r_i)²
    cap = ~ell
    along = np.clip(metric[cap, 0], 0.0, np.linalg.norm(parts.end[p[cap]] - parts.centre[p[cap]], axis=1))
    normal[cap] = X[cap] - (parts.centre[p[cap]] + along[:, None] * A[cap, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    albedo = parts.albedo[p].astype(np.float64)
    tex = parts.texture[p]
    head = np.flatnonzero(tex == TEX_HEAD)
    if len(head):
        owner = parts.person[p[head]]
        unit = metric[head] / parts.radii[p[head]]
        albedo[head] = _head_albedo(unit, albedo[head], hair[owner].astype(np.float64), hair_style[owner])
    stripes = np.flatnonzero(tex == TEX_STRIPES)
    if len(stripes):
        unit_z = metric[stripes, 2] / parts.radii[p[stripes], 2]
        albedo[stripes[np.floor(unit_z * 5.0) % 2 == 0]] *= 0.5
    pid = parts.person[p] if person_ids is None else np.asarray(person_ids)[parts.person[p]]
    albedo *= _fabric(metric, cap, pid * PARTS_PER_PERSON + parts.part[p])[:, None]
    lam = np.maximum(normal @ light.L, 0.0)
    rad = albedo * (light.ambient + light.direct * lam)[:, None]
    return idx, rad.astype(np.float32)


# ------------------------------------------------------------------------------------ renderer

class Renderer:
    """Renders frames of one scene; keeps per-camera caches (static layers, rays, vignetting)."""

    def __init__(self, scene: Scene, environment: Environment, options: RenderOptions,
                 sensors: dict[str, SensorSpec] | None = None):
        self.scene = scene
        self.env = environment
        self.options = options
        self.sensors = dict(sensors or {})
        self._static: dict[tuple, StaticLayer] = {}
        self._rays: dict[tuple, np.ndarray] = {}
        self._vignette: dict[tuple, np.ndarray] = {}
        self._lit: dict[tuple, tuple] = {}
        self._emissive: dict[str, tuple] = {}

    # ---- caches
    def rays(self, camera: Camera) -> np.ndarray:
        key = (camera.width, camera.height, camera.K.tobytes(), camera.dist.tobytes())
        if key not in self._rays:
            self._rays[key] = camera_frame_rays(camera)
        return self._rays[key]

    def static_layer(self, camera: Camera, moving: bool = False) -> StaticLayer:
        """The empty scene through ``camera`` (cached; a moving camera keeps only the latest)."""
        key = _camera_key(camera)
        if key not in self._static:
            if moving:
                for k in [k for k in self._static if k[0] == camera.id]:
                    del self._static[k]
            ss = self.options.supersample
            if ss is None:
                ss = 2 if camera.width * camera.height <= 320 * 240 else 1
            ss = 1 if moving else ss
            self._static[key] = render_static(self.scene, camera, self.env, supersample=ss)
        return self._static[key]

    def static_depth(self, camera: Camera, moving: bool = False) -> np.ndarray:
        key = ("depth",) + _camera_key(camera)
        if key not in self._static:
            if moving:
                for k in [k for k in self._static if k[0] == "depth" and k[1] == camera.id]:
                    del self._static[k]
            self._static[key] = static_depth(self.scene, camera, self.env)
        return self._static[key]

    def emissive_pixels(self, camera: Camera, layer: StaticLayer) -> np.ndarray:
        """Flat indices of the layer's emissive pixels (sky, windows), cached per layer."""
        key = id(layer)
        hit = self._emissive.get(camera.id)
        if hit is None or hit[0] != key:
            hit = (key, np.flatnonzero(np.any(layer.emissive.reshape(-1, 3) > 0, axis=1)), layer)
            self._emissive[camera.id] = hit
        return hit[1]

    def vignette(self, camera: Camera) -> np.ndarray | None:
        if self.options.noise.vignetting <= 0:
            return None
        key = (camera.width, camera.height)
        if key not in self._vignette:
            self._vignette[key] = vignetting_map(camera.width, camera.height, self.options.noise.vignetting)
        return self._vignette[key]

    def lit_static(self, camera: Camera, layer: StaticLayer, light: Light) -> tuple[np.ndarray, np.ndarray]:
        """(ambient + direct·max(0, n·L))·albedo (H, W, 3) and max(0, n·L)·albedo, cached per light."""
        key = (_camera_key(camera), light.ambient, light.direct, tuple(np.round(light.L, 9)))
        hit = self._lit.get(camera.id)
        if hit is not None and hit[0] == key:
            return hit[1], hit[2]
        lam = np.maximum(layer.normal @ light.L.astype(np.float32), 0.0)
        direct = layer.albedo * lam[:, :, None]
        lit = layer.albedo * np.float32(light.ambient) + direct * np.float32(light.direct)
        self._lit[camera.id] = (key, lit, direct)
        return lit, direct

    # ---- one camera, one frame
    def render(self, camera: Camera, parts: PartArrays, person_ids: np.ndarray, hair: np.ndarray,
               hair_style: np.ndarray, light: Light, wb: WhiteBalance, frame: int, time: float,
               rng: np.random.Generator | None, ground_points: np.ndarray, moving: bool = False,
               with_noise: bool = True) -> tuple[SynthFrame, Visibility]:
        """Render one camera's view.

        Parameters
        ----------
        parts : the frame's people's parts (person indices 0…N−1 in ``person_ids`` order)
        person_ids : (N,) ids written into the instance image
        hair, hair_style : (N, 3), (N,) for the head shader
        light : the frame's Light; wb : the camera's WhiteBalance (updated in place)
        rng : noise source (None: noise-free)
        ground_points : (N, 3) the people's ground points (for the feet flag)
        """
        opts = self.options
        n = len(person_ids)
        layer = self.static_layer(camera, moving)
        rays = self.rays(camera)
        buf = people_pass(camera, rays, parts, n, person_ids, layer.depth)
        H, W = buf.zbuf.shape

        # Shadows on bare floor.
        shadow = np.zeros((H, W), dtype=bool)
        if n and opts.shadow_strength > 0 and light.direct > 0 and light.L[2] > 0.02:
            receiver = (layer.kind == FLOOR) & (buf.inst == 0)
            kernels.trace_shadows(layer.points, receiver, light.L.astype(np.float64),
                                  np.ascontiguousarray(parts.geometry()), bounding_spheres(parts),
                                  shadow_boxes(camera, parts, n, light.L),
                                  np.arange(n + 1, dtype=np.int64) * PARTS_PER_PERSON, shadow)

        # Radiance, already multiplied by the light level, exposure and tint ("raw").
        lit, direct = self.lit_static(camera, layer, light)
        mult = (np.float32(light.level * light.exposure) * np.asarray(light.tint, dtype=np.float32))
        raw = lit * mult[None, None, :]
        flat = raw.reshape(-1, 3)
        if shadow.any():
            raw[shadow] -= np.float32(opts.shadow_strength * light.direct) * direct[shadow] * mult
        if n and opts.reflection > 0:
            mirror = parts.mirrored_z()
            mbuf = people_pass(camera, rays, mirror, n, person_ids, np.full((H, W), np.inf, np.float32),
                               extended=False)
            floor_px = (layer.kind == FLOOR) & (buf.inst == 0) & (mbuf.inst > 0)
            mbuf.part_hit[~floor_px] = -1
            midx, mrad = shade_people(camera, rays, mbuf, mirror, hair, hair_style, light, person_ids)
            k = np.float32(opts.reflection)
            flat[midx] = (1 - k) * flat[midx] + k * (mrad * mult)
        idx, prad = shade_people(camera, rays, buf, parts, hair, hair_style, light, person_ids)
        flat[idx] = prad * mult
        eidx = self.emissive_pixels(camera, layer)
        if len(eidx):
            flat[eidx] += np.float32(light.exposure) * layer.emissive.reshape(-1, 3)[eidx]

        # Camera: white balance from the raw frame's grey world, then exposure to 8 bits.
        r_gain, b_gain = wb.update(frame, grey_world_mean(raw))
        gains = np.array([b_gain / WB_UNITY, 1.0, r_gain / WB_UNITY], dtype=np.float32)
        image = expose(raw, gains, opts.noise if with_noise else SensorNoise(0, 0, opts.noise.blur_sigma,
                                                                             opts.noise.vignetting),
                       rng if with_noise else None, self.vignette(camera))

        # Depth sensors.
        sensor_depth = disparity = None
        spec = self.sensors.get(camera.id)
        if spec is not None and spec.has_depth and rng is not None:
            other = second_view(camera, spec.baseline)
            obuf = people_pass(other, rays, parts, n, person_ids, self.static_depth(other, moving), extended=False)
            fx = float(camera.K[0, 0])
            if spec.kind == "stereo":
                grey = raw @ (gains * np.array([0.114, 0.587, 0.299], np.float32))
                disparity, sensor_depth = stereo_measurement(spec, buf.zbuf, obuf.zbuf, fx, grey, rng)
            else:
                sensor_depth = kinect_depth(spec, buf.zbuf, obuf.zbuf, fx, rng)

        vis = self._visibility(camera, buf, layer, parts, person_ids, ground_points)
        frame_out = SynthFrame(image, buf.zbuf, buf.inst, camera, time, (r_gain, b_gain), light.level, shadow,
                               sensor_depth, disparity)
        return frame_out, vis

    def background(self, camera: Camera, light: Light, wb_gains: tuple[int, int], moving: bool = False) -> np.ndarray:
        """The empty scene, noise-free, under ``light`` and fixed white-balance gains (uint8 BGR)."""
        layer = self.static_layer(camera, moving)
        lit, _ = self.lit_static(camera, layer, light)
        tint = np.asarray(light.tint, dtype=np.float32)
        raw = lit * (np.float32(light.level * light.exposure) * tint)[None, None, :]
        raw += np.float32(light.exposure) * layer.emissive
        gains = np.array([wb_gains[1] / WB_UNITY, 1.0, wb_gains[0] / WB_UNITY], dtype=np.float32)
        noise = SensorNoise(0.0, 0.0, self.options.noise.blur_sigma, self.options.noise.vignetting)
        return expose(raw, gains, noise, None, self.vignette(camera))

    def _visibility(self, camera: Camera, buf: PeopleBuffers, layer: StaticLayer, parts: PartArrays,
                    person_ids: np.ndarray, ground_points: np.ndarray) -> Visibility:
        n = len(person_ids)
        if n == 0:
            z = np.zeros(0)
            return Visibility(z.astype(np.int64), z.astype(np.int64), z.astype(bool), z.astype(bool))
        ids = np.asarray(person_ids, dtype=np.int64)
        counts = np.bincount(buf.inst.ravel(), minlength=int(ids.max()) + 1)[ids]
        flags = []
        for pts, floor_ok in ((parts.head_top, False), (ground_points, True)):
            uv, depth = camera.project(pts, return_depth=True)
            inside = camera.in_image(np.nan_to_num(uv, nan=-10.0)) & (depth > 0)
            iu = np.clip(np.rint(np.nan_to_num(uv[:, 0], nan=0)).astype(int), 0, camera.width - 1)
            iv = np.clip(np.rint(np.nan_to_num(uv[:, 1], nan=0)).astype(int), 0, camera.height - 1)
            seen_inst = buf.inst[iv, iu]
            seen_depth = buf.zbuf[iv, iu]
            tol = 0.03 + 0.01 * depth
            hidden = (seen_inst != ids) & (seen_depth < depth - tol)
            if floor_ok:
                hidden &= ~((seen_inst == 0) & (layer.kind[iv, iu] == FLOOR))
            flags.append(inside & ~hidden)
        return Visibility(counts.astype(np.int64), buf.alone.copy(), flags[0], flags[1])
