"""The Numba kernels agree with their plain NumPy references."""

import numpy as np
import pytest

from worldtrack.geometry.camera import Camera
from worldtrack.synth import kernels
from worldtrack.synth.bodies import PARTS_PER_PERSON, BodyShape, body_parts
from worldtrack.synth.joints import posed
from worldtrack.synth.photometry import SensorNoise, expose, expose_reference, noise_bytes, vignetting_map
from worldtrack.synth.people_pass import bounding_spheres, camera_frame_rays, people_pass, shadow_boxes


def _people(n=3, seed=0):
    rng = np.random.default_rng(seed)
    xy = np.column_stack([rng.uniform(-1.0, 1.0, n), rng.uniform(1.5, 3.5, n)])
    shapes = [BodyShape(float(h), float(w)) for h, w in zip(rng.uniform(1.5, 1.95, n), rng.uniform(0.35, 0.55, n))]
    ja = posed(xy, rng.uniform(-np.pi, np.pi, n), rng.uniform(0, 6, n), rng.uniform(0, 1.1, n), np.zeros(n))
    return body_parts(shapes, ja)


CAMERAS = [
    Camera.look_at("pin", 96, 72, position=(0.0, -1.5, 2.4), target=(0.0, 2.5, 0.8), hfov_deg=70),
    Camera.look_at("dist", 96, 72, position=(0.2, 2.0, 3.0), target=(0.0, 2.5, 0.0), hfov_deg=90,
                   dist=(-0.25, 0.05, 0.0, 0.0, 0.0)),
    Camera.look_at("near", 64, 48, position=(0.0, 1.2, 1.2), target=(0.0, 3.0, 1.0), hfov_deg=80),
]


@pytest.mark.parametrize("camera", CAMERAS, ids=lambda c: c.id)
def test_trace_people_matches_reference(camera):
    parts = _people()
    n = 3
    H, W = camera.height, camera.width
    floor = np.full((H, W), np.inf, np.float32)
    floor[H // 2:, :] = 3.0  # a fake static surface in the lower half
    ids = np.array([4, 7, 9])
    fast = people_pass(camera, camera_frame_rays(camera), parts, n, ids, floor)
    start = np.arange(n + 1) * PARTS_PER_PERSON
    zb, inst, part_hit, alone = kernels.trace_people_reference(camera, parts.geometry(), start, ids, floor,
                                                               margin=(W, H))
    differ = fast.inst != inst
    assert differ.sum() <= 2                      # boundary pixels at most
    both = (fast.inst > 0) & (inst > 0) & ~differ
    assert both.sum() > 100
    np.testing.assert_allclose(fast.zbuf[both], zb[both], atol=1e-4)
    np.testing.assert_array_equal(fast.part_hit[both], part_hit[both])
    np.testing.assert_allclose(fast.alone, alone, atol=2)


def test_trace_shadows_matches_reference():
    camera = CAMERAS[0]
    parts = _people(3, seed=1)
    rays = camera_frame_rays(camera)
    d = rays.reshape(-1, 3).astype(float) @ camera.R
    s = -camera.centre[2] / d[:, 2]
    pts = (camera.centre + s[:, None] * d).reshape(camera.height, camera.width, 3).astype(np.float32)
    receiver = (s > 0).reshape(camera.height, camera.width)
    light = np.array([0.4, -0.3, 0.866])
    light /= np.linalg.norm(light)
    fast = np.zeros_like(receiver)
    kernels.trace_shadows(pts, receiver, light, parts.geometry(), bounding_spheres(parts),
                          shadow_boxes(camera, parts, 3, light), np.arange(4, dtype=np.int64) * PARTS_PER_PERSON, fast)
    ref = kernels.trace_shadows_reference(pts, receiver, light, parts.geometry())
    assert ref.sum() > 50
    assert (fast != ref).sum() <= 2


def test_exposure_kernel_matches_reference():
    rng = np.random.default_rng(0)
    rad = rng.uniform(0, 300, (40, 50, 3)).astype(np.float32)
    gains = np.array([1.1, 1.0, 0.9], np.float32)
    vig = vignetting_map(50, 40, 0.2)
    noise = SensorNoise(2.0, 0.05, 0.8, 0.2)
    nb = noise_bytes(np.random.default_rng(5), rad.shape)
    fast = expose(rad, gains, noise, np.random.default_rng(5), vig)
    ref = expose_reference(rad, gains, noise, nb, vig)
    assert np.abs(fast.astype(int) - ref).max() <= 1
    assert (fast != ref).mean() < 1e-3
    clean = expose(rad, gains, noise, None, vig)
    np.testing.assert_array_equal(clean, expose_reference(rad, gains, noise, None, vig))
