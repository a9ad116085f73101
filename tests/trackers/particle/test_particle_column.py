"""The height column (eqs. 11–12) and its likelihood ratio: the compiled kernel against its NumPy
reference, each particle read with its own filter's box, explaining away and occlusion, and the
paper's Fig. 5 argument (the column tells depth where the point cannot)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from worldtrack.foreground.background import StaticBackground
from worldtrack.trackers.particle.likelihood import (CameraLikelihood, column_spec, occluder_layers, owner_image,
                                                     point_values_reference)
from worldtrack.trackers.particle.likelihood.boxes import image_box

from particle_scenes import hit_image, thresholded_difference  # noqa: E402
from particle_scenes import (CAM, DISTORTION, HEIGHT, RING_HEIGHTS, H, W, WIDTH, column, column_reference,
                             make_scene, render, texture)


def _labels(rng):
    """Smooth random object blobs with a fifth of their pixels "no evidence" (shadows)."""
    hit = (cv2.GaussianBlur(rng.random((H, W)).astype(np.float32), (0, 0), 4) > 0.5).astype(np.uint8)
    hit[(hit == 1) & (rng.random((H, W)) < 0.2)] = 2
    return hit


def _assert_agree(out, ref, hidden=False):
    """Counts and seen exactly, the ratio to 1e-9, the best top but for ties (equal scores up to rounding)."""
    for i in (0, 3, 4) if hidden else (0, 3):
        np.testing.assert_array_equal(out[i], ref[i])
    np.testing.assert_allclose(out[1], ref[1], rtol=0, atol=1e-9)
    assert (out[2] == ref[2]).mean() > 0.999


@pytest.mark.parametrize("dist", [None, DISTORTION])
@pytest.mark.parametrize("radius", [0.0, 0.1])
@pytest.mark.parametrize("px_scale", [0.0, 0.25])
def test_column_kernel_agrees_with_reference(dist, radius, px_scale):
    spec = dict(CAM, distortion=dist) if dist else CAM
    cam = make_scene(cameras=(spec,)).cameras["cam"]
    rng = np.random.default_rng(1)
    hit = _labels(rng)
    xy = np.column_stack([rng.uniform(-3.5, 3.5, 3000), rng.uniform(-1.5, 7.0, 3000)])
    tops = rng.uniform(1.4, 2.0, len(xy))
    boxes = [(40, 120, 30, 200), (100, 180, 0, 120), None]
    owner = owner_image((H, W), boxes)
    occluders = occluder_layers((H, W), boxes, [2.0, 4.5, 3.0])
    cl = CameraLikelihood(cam)
    for box, n_above, sigma, me in ((None, 2, 0.0, -1), (boxes[0], 2, 0.1, 0), (None, 0, 0.05, -1),
                                    (boxes[1], 2, 0.1, 1)):
        hs = RING_HEIGHTS if n_above else RING_HEIGHTS[:-2]
        args = dict(on=2.77, off=-1.56, k_min=10, radius=radius, below=-2.77, n_below=2, n_above=n_above,
                    owner=owner, box=box, tops=tops, top_sigma=sigma, px_scale=px_scale,
                    occluders=occluders if me >= 0 else None, me=me, margin=0.3)
        out = column(cl, hit, xy, hs, **args)
        _assert_agree(out, column_reference(cam, hit, xy, hs, **args))
        assert out.seen.sum() > 1000 and out.counts.max() > 10  # the test exercises real hits


def test_column_kernel_agrees_with_reference_under_many_boxes():
    """More than 63 boxes over a pixel (the codes saturate there) and a box per filter: the kernel,
    reading the combined codes and the packed occluders, agrees with the reference."""
    cam = make_scene().cameras["cam"]
    rng = np.random.default_rng(2)
    hit = _labels(rng)
    boxes = [(40, 120, 30, 200), (100, 180, 0, 120), None] + [(150, 200, 60, 180)] * 70
    depths = np.concatenate([[2.0, 4.5, 3.0], rng.uniform(1.0, 6.0, 70)])
    owner = owner_image((H, W), boxes)
    assert owner.max() > 63
    n = 4000
    xy = np.column_stack([rng.uniform(-2.5, 2.5, n), rng.uniform(0.5, 6.0, n)])
    which = rng.integers(0, 4, n)
    args = dict(on=2.77, off=-1.56, k_min=10, radius=0.1, below=-2.77, n_below=2, n_above=2, owner=owner,
                box=boxes[:2] + [None, boxes[3]], me=[0, 1, 2, 3], which=which, tops=rng.uniform(1.4, 2.0, n),
                top_sigma=0.1, occluders=occluder_layers((H, W), boxes, depths), margin=0.3, outside_unknown=True)
    out = column(CameraLikelihood(cam), hit, xy, RING_HEIGHTS, **args)
    _assert_agree(out, column_reference(cam, hit, xy, RING_HEIGHTS, **args), hidden=True)
    assert (out.hidden > 0).sum() > 100                   # occluded samples exercised


def test_kernels_read_each_particle_with_its_own_filters_box():
    """The particles of three filters in one call (interleaved): each particle reads with its own
    filter's box and occluder index — the same as one call per filter, and as the references."""
    cam = make_scene().cameras["cam"]
    rng = np.random.default_rng(4)
    hit = _labels(rng)
    F = thresholded_difference(rng.uniform(0, 100, (H, W)).astype(np.float32), 30.0)
    boxes = [(40, 120, 30, 200), (100, 180, 0, 120), None]
    owner = owner_image((H, W), boxes)
    occluders = occluder_layers((H, W), boxes, [2.0, 4.5, 3.0])
    n = 3000
    xy = np.column_stack([rng.uniform(-2.5, 2.5, n), rng.uniform(0.5, 6.0, n)])
    xyz = np.column_stack([xy, rng.uniform(0.0, 2.0, n)])
    which = rng.integers(0, 3, n)
    args = dict(on=2.77, off=-1.56, k_min=10, radius=0.1, below=-2.77, n_below=2, n_above=2, owner=owner,
                tops=rng.uniform(1.4, 2.0, n), top_sigma=0.1, occluders=occluders, margin=0.3)
    cl = CameraLikelihood(cam)
    batched = column(cl, hit, xy, RING_HEIGHTS, box=boxes, me=[0, 1, 2], which=which, **args)
    one_by_one = [np.zeros_like(a) for a in batched]
    point, point_one = cl.point(F, xyz, owner, boxes, which), [np.zeros(n), np.zeros(n, dtype=bool)]
    for f in range(3):
        sel = which == f
        part = column(cl, hit, xy[sel], RING_HEIGHTS, box=boxes[f], me=f, **{**args, "tops": args["tops"][sel]})
        for a, b in zip(one_by_one, part):
            a[sel] = b
        for a, b in zip(point_one, cl.point(F, xyz[sel], owner, boxes[f])):
            a[sel] = b
    for a, b in zip(batched, one_by_one):
        np.testing.assert_array_equal(a, b)
    for a, b in zip(point, point_one):
        np.testing.assert_array_equal(a, b)
    reference = column_reference(cam, hit, xy, RING_HEIGHTS, box=boxes, me=[0, 1, 2], which=which, **args)
    for i in (0, 3):                                                    # counts, seen
        np.testing.assert_array_equal(batched[i], reference[i])
    np.testing.assert_allclose(batched[1], reference[1], rtol=0, atol=1e-9)
    for a, b in zip(point, point_values_reference(cam, F, xyz, owner, boxes, which)):
        np.testing.assert_array_equal(a, b)
    # The boxes matter: read with the wrong filters' boxes, many particles score otherwise.
    wrong = column(cl, hit, xy, RING_HEIGHTS, box=boxes, me=[0, 1, 2], which=(which + 1) % 3, **args)
    assert (wrong[1] != batched[1]).sum() > 100
    assert (cl.point(F, xyz, owner, boxes, (which + 1) % 3)[0] != point[0]).sum() > 100


def test_a_person_behind_another_is_occluded_not_background():
    """A column standing behind a nearer tracked person reads that person's box as no evidence; in
    front of (or beside) it, the box still reads background (explained by the other person)."""
    scene = make_scene(entry=False)
    cam = scene.cameras["cam"]
    cl = CameraLikelihood(cam)
    near, far = np.array([0.0, 2.0]), np.array([0.0, 4.0])      # on one line of sight of the camera
    # The far person's image: only its head shows above the near person's box.
    hit = np.zeros((H, W), np.uint8)
    far_box = image_box(cam, *far, WIDTH, HEIGHT, 0.0)
    near_box = image_box(cam, *near, WIDTH, HEIGHT, 0.05)
    hit[far_box[2]:far_box[3], far_box[0]:far_box[1]] = 1
    hit[near_box[2]:near_box[3], near_box[0]:near_box[1]] = 1
    boxes = [near_box, far_box]
    owner = owner_image((H, W), boxes)
    depth = [float(np.hypot(*(p - cam.centre[:2]))) for p in (near, far)]
    args = dict(on=2.77, off=-1.56, k_min=10, radius=0.0, below=-2.77, n_below=2, n_above=2, owner=owner)
    plain = column(cl, hit, far[None], RING_HEIGHTS, box=far_box, **args)
    occluded = column(cl, hit, far[None], RING_HEIGHTS, box=far_box, occluders=occluder_layers((H, W), boxes, depth),
                      me=1, margin=0.3, **args)
    # Behind the near person every hidden sample cost `off` before; now it costs nothing.
    assert occluded.ratio[0] > plain.ratio[0] + 5 * 1.56
    # Every sample up to the person's 1.7 m counts (hits, or no evidence behind the near person).
    assert occluded.counts[0] == 18 and plain.counts[0] < 18
    # The near person's column does not gain from the far person's box (it is farther, so explained).
    a = column(cl, hit, near[None], RING_HEIGHTS, box=near_box, **args)
    b = column(cl, hit, near[None], RING_HEIGHTS, box=near_box, occluders=occluder_layers((H, W), boxes, depth), me=0,
               margin=0.3, **args)
    assert a.ratio[0] == b.ratio[0]


def test_column_tells_the_person_from_a_point_on_the_same_line_of_sight():
    """A particle inside the person and one on the floor behind it, on the same line of sight, project
    to the same pixel: the point likelihood (eq. 7) cannot tell them apart, the column (eq. 11) can."""
    scene = make_scene(entry=False)
    cam = scene.cameras["cam"]
    bg = texture(0)
    img = render(cam, bg, [(0.0, 3.0)], np.random.default_rng(0))
    F = StaticBackground(bg, 30.0, "colour").difference(img)
    inside = np.array([0.0, 3.0, 0.85])
    ray = inside - cam.centre
    behind = cam.centre + ray * (cam.centre[2] / -ray[2])               # where the ray meets the floor
    assert behind[2] == pytest.approx(0.0, abs=1e-9) and np.hypot(*(behind[:2] - inside[:2])) > 1.0
    np.testing.assert_allclose(cam.project([inside]), cam.project([behind]), atol=1e-6)

    point = CameraLikelihood(cam).point(thresholded_difference(F, 30.0), np.array([inside, behind]))[0]
    assert point[0] == point[1] > 0

    spec = column_spec(np.arange(20) * 0.1, 2.77, -1.56, 8)
    counts, ratio, _, _, _ = CameraLikelihood(cam).column(hit_image(F, 30.0), np.array([inside[:2], behind[:2]]), spec)
    assert counts[0] >= 16 and counts[1] <= counts[0] - 6
    assert ratio[0] > ratio[1] + 10
