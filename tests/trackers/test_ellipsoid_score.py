"""The candidate-scoring kernel against its plain NumPy reference, and eq. 5 on ideal images."""

from pathlib import Path

import numpy as np
import pytest

from worldtrack.geometry import quadric as q
from worldtrack.scene import load_scene
from worldtrack.trackers.ellipsoid.score import (ellipse_forms, score_candidates, score_candidates_reference,
                                                 ternary_real, ternary_real_reference)

LAB = Path(__file__).parents[2] / "examples" / "scenes" / "kato_lab.yaml"


@pytest.fixture(scope="module")
def lab():
    return load_scene(LAB)


def person_mask(cam, xy, height, width):
    cen, rad = q.person_ellipsoid([xy], height, width)
    C = q.ellipsoid_conics(cam.P, cen, rad)[0]
    grid = cam.ideal_pixel_grid if cam.has_distortion else None
    return q.ellipse_mask(C, (cam.height, cam.width), ideal_grid=grid).astype(np.uint8)


def kernel(cam, occ, real, use_ring, cand, others, ring, target, count_unexplained=False, ring_fraction=0.0):
    args = (cam.P, cam.K, cam.dist, cam.has_distortion, cam.width, cam.height)
    h = np.full(len(cand), 1.65)
    w = np.full(len(cand), 0.40)
    ci, cr, cb, cv = ellipse_forms(*args, cand, h, w, float(ring), 0.1, ring_fraction)
    oi, orr, ob, ov = ellipse_forms(*args, others, np.full(len(others), 1.65), np.full(len(others), 0.4),
                                    float(ring), 0.1, ring_fraction)
    cd = np.hypot(*(cand - cam.centre[:2]).T)
    od = np.hypot(*(others - cam.centre[:2]).T)
    grid = cam.ideal_pixel_grid if cam.has_distortion else np.zeros((1, 1, 2), np.float32)
    return score_candidates(grid, cam.has_distortion, occ, real, use_ring, ci, cr, cb, cd, cv,
                            oi, orr, ob, od, ov, target, count_unexplained)


@pytest.mark.parametrize("cam_id", ["cam1", "cam2"])
def test_kernel_equals_reference(lab, cam_id):
    cam = lab.cameras[cam_id]
    occ = lab.occlusion(cam_id).floor_distance
    rng = np.random.default_rng(7)
    for trial in range(6):
        truth = np.array([rng.uniform(-2, 0), rng.uniform(0, 2.8)])
        mask = person_mask(cam, truth, rng.uniform(1.5, 1.9), rng.uniform(0.35, 0.5))
        mask[rng.random(mask.shape) < 0.05] ^= 1
        real = ternary_real(mask, 5)
        start = truth + rng.normal(0, 0.1, 2)
        offsets = np.array([(i, j) for i in (-1, 0, 1) for j in (-1, 0, 1)]) * 0.05
        cand = start + offsets
        others = np.array([[rng.uniform(-2, 0), rng.uniform(0, 2.8)] for _ in range(2)])
        for use_ring, target, unexplained, frac in [
                (True, 0, False, 0.0), (False, 0, False, 0.0), (True, 250, False, 0.0), (False, 250, False, 0.0),
                (True, 0, True, 0.0), (True, 250, True, 0.0), (True, 0, True, 0.3), (True, 250, False, 0.5)]:
                num, den, _ = kernel(cam, occ, real, use_ring, cand, others, 5, target, unexplained, frac)
                rn, rd = score_candidates_reference(cam.P, cam, occ, real, use_ring, cand, 1.65, 0.40, 5,
                                                    others, 1.65, 0.40, target_pixels=target,
                                                    count_unexplained=unexplained, ring_fraction=frac)
                np.testing.assert_array_equal(num, rn)
                np.testing.assert_array_equal(den, rd)


def test_exact_silhouette_scores_one_and_wins(lab):
    cam = lab.cameras["cam1"]
    occ = np.full((cam.height, cam.width), np.inf, np.float32)
    truth = np.array([-1.0, 1.0])
    real = ternary_real(person_mask(cam, truth, 1.65, 0.40), 5)
    cand = truth + np.array([(i, j) for i in (-1, 0, 1) for j in (-1, 0, 1)]) * 0.05
    num, den, n_in = kernel(cam, occ, real, True, cand, np.zeros((0, 2)), 5, 0)
    e = num / den
    assert np.argmax(e) == 4
    assert e[4] > 0.97  # the ternary images coincide up to the ring's approximation of a dilation
    assert np.all(e[np.arange(9) != 4] < e[4] - 0.02)
    assert n_in[4] == person_mask(cam, truth, 1.65, 0.40).sum()


def test_ring_rejects_an_ellipse_inside_a_big_blob(lab):
    # The paper's Fig. 2: with a binary score an ellipse lying inside a larger blob scores 1;
    # the −1 ring makes the matching outline win.
    cam = lab.cameras["cam1"]
    occ = np.full((cam.height, cam.width), np.inf, np.float32)
    truth = np.array([-1.0, 1.0])
    big = person_mask(cam, truth, 1.9, 0.8)
    inner_candidate = np.array([truth, truth])
    real = ternary_real(big, 5)
    num_b, den_b, _ = kernel(cam, occ, real, False, inner_candidate, np.zeros((0, 2)), 5, 0)
    assert num_b[0] / den_b[0] == 1.0           # binary (capture mode): a perfect score inside the blob
    num_t, den_t, _ = kernel(cam, occ, real, True, inner_candidate, np.zeros((0, 2)), 5, 0)
    assert num_t[0] / den_t[0] < 0.8            # ternary: the ring falls on foreground and costs


@pytest.mark.parametrize("ring", [1, 5, 20])
def test_ternary_real_dilating_the_foreground_box_equals_the_whole_frame(ring):
    rng = np.random.default_rng(ring)
    for trial in range(12):
        H, W = rng.integers(20, 130), rng.integers(20, 170)
        labels = np.zeros((H, W), np.uint8)
        if trial == 0:
            pass                                                         # no foreground at all
        elif trial % 3 == 0:
            labels[rng.random((H, W)) < 0.01] = 1                        # scattered pixels
        else:
            for _ in range(rng.integers(1, 4)):
                y, x = rng.integers(0, H), rng.integers(0, W)
                labels[y:y + rng.integers(1, 25), x:x + rng.integers(1, 25)] = 1
        if trial % 2:
            labels[0, rng.integers(0, W)] = labels[rng.integers(0, H), W - 1] = 1   # blobs on the border
        labels[rng.random((H, W)) < 0.05] = 2                            # unsure pixels stay 0
        out = ternary_real(labels, ring)
        np.testing.assert_array_equal(out, ternary_real_reference(labels, ring))
        assert out.dtype == np.int8 and (out == -1).any() == (labels == 1).any()


def test_obstacle_hides_the_lower_body(lab):
    cam = lab.cameras["cam1"]
    occ = lab.occlusion("cam1").floor_distance
    behind_desk = np.array([[-1.0, 2.9]])   # the lab's desk is at y 2.1…2.7
    args = (cam.P, cam.K, cam.dist, cam.has_distortion, cam.width, cam.height)
    _, _, box, valid = ellipse_forms(*args, behind_desk, np.array([1.65]), np.array([0.4]), 5.0, 0.1)
    assert valid[0]
    full = np.ones((cam.height, cam.width), np.int8)
    free = np.full_like(occ, np.inf)
    _, _, n_free = kernel(cam, free, full, True, behind_desk, np.zeros((0, 2)), 5, 0)
    _, _, n_occ = kernel(cam, occ, full, True, behind_desk, np.zeros((0, 2)), 5, 0)
    assert 0 < n_occ[0] < 0.85 * n_free[0]


@pytest.mark.parametrize("cam_id", ["cam1", "cam2"])
def test_ellipse_crop_equals_the_conic_mask(lab, cam_id):
    from worldtrack.trackers.ellipsoid.score import ellipse_crop
    cam = lab.cameras[cam_id]
    args = (cam.P, cam.K, cam.dist, cam.has_distortion, cam.width, cam.height)
    xy = np.array([[-1.0, 1.0], [-0.5, 2.0]])
    inner, _, box, valid = ellipse_forms(*args, xy, np.full(2, 1.65), np.full(2, 0.4), 5.0, 0.1)
    grid = cam.ideal_pixel_grid if cam.has_distortion else np.zeros((1, 1, 2), np.float32)
    cen, rad = q.person_ellipsoid(xy, 1.65, 0.4)
    centre, axes, angle = q.ellipse_parameters(q.ellipsoid_conics(cam.P, cen, rad))
    if cam.has_distortion:
        u, v = grid[..., 0].astype(float), grid[..., 1].astype(float)
    else:
        v, u = np.mgrid[0:cam.height, 0:cam.width].astype(float)
    for k in range(2):
        crop = ellipse_crop(inner[k], box[k], grid, cam.has_distortion)
        full = person_mask(cam, xy[k], 1.65, 0.4).astype(bool)
        u0, u1, v0, v1 = box[k]
        assert (crop != full[v0:v1, u0:u1]).sum() <= 2       # float32 grid vs float64 at the edge
        assert crop.sum() == pytest.approx(full.sum(), abs=2)  # the box holds the whole ellipse
        # ... and the whole ring ellipse, semi-axes + 5 px, drawn independently of the kernel.
        du, dv = u - centre[k, 0], v - centre[k, 1]
        ca, sa = np.cos(angle[k]), np.sin(angle[k])
        ring = ((du * ca + dv * sa) / (axes[k, 0] + 5)) ** 2 + ((dv * ca - du * sa) / (axes[k, 1] + 5)) ** 2 < 1
        assert ring.sum() > full.sum() and ring[v0:v1, u0:u1].sum() == ring.sum()


@pytest.mark.parametrize("cam_id", ["cam1", "cam2"])
def test_owner_crop_equals_the_owner_map_and_the_masks(lab, cam_id):
    from worldtrack.trackers.ellipsoid.score import owner_crop, owner_map
    cam = lab.cameras[cam_id]
    args = (cam.P, cam.K, cam.dist, cam.has_distortion, cam.width, cam.height)
    xy = np.array([[-1.0, 1.0], [-0.8, 1.2], [-0.5, 2.0]])    # the first two overlap in both views
    inner, ring, box, valid = ellipse_forms(*args, xy, np.full(3, 1.65), np.full(3, 0.4), 5.0, 0.1)
    grid = cam.ideal_pixel_grid if cam.has_distortion else np.zeros((1, 1, 2), np.float32)
    full = owner_map(cam.height, cam.width, inner, box, valid, grid, cam.has_distortion)
    # The reference, from independently drawn silhouettes: who covers each pixel.
    masks = np.stack([person_mask(cam, p, 1.65, 0.4).astype(bool) for p in xy])
    expected = np.where(masks.sum(0) > 1, -2, np.where(masks.any(0), masks.argmax(0), -1))
    assert (full != expected).sum() <= 6                     # float32 grid vs float64 at the edges
    assert (full == -2).sum() > 20                            # the overlap is there to be found
    for k in range(3):
        u0, u1, v0, v1 = box[k]
        np.testing.assert_array_equal(owner_crop(box[k], inner, box, valid, grid, cam.has_distortion),
                                      full[v0:v1, u0:u1])
    window = np.array([box[0, 0], box[1, 1], box[1, 2], box[0, 3]])   # spans parts of both boxes
    np.testing.assert_array_equal(owner_crop(window, inner, box, valid, grid, cam.has_distortion),
                                  full[window[2]:window[3], window[0]:window[1]])


def test_kernel_equals_reference_in_a_crowd_behind_the_desk(lab):
    # The pinhole kernel sums each row by intervals; rows where the desk hides part of a
    # candidate fall back to pixel by pixel. Both against the reference, with many overlapping
    # neighbours (their ellipses and rings cut every row into pieces).
    cam = lab.cameras["cam1"]
    occ = lab.occlusion("cam1").floor_distance
    rng = np.random.default_rng(11)
    for trial in range(4):
        truth = np.array([rng.uniform(-1.5, -0.5), rng.uniform(2.3, 3.2)])   # around the desk's back edge
        mask = np.zeros((cam.height, cam.width), np.uint8)
        others = truth + rng.uniform(-0.7, 0.7, (6, 2))
        for p in [truth, *others[:3]]:
            mask |= person_mask(cam, p, rng.uniform(1.5, 1.9), rng.uniform(0.35, 0.5))
        mask[rng.random(mask.shape) < 0.05] ^= 1
        real = ternary_real(mask, 3)
        cand = truth + rng.normal(0, 0.1, 2) + np.array([(i, j) for i in (-1, 0, 1) for j in (-1, 0, 1)]) * 0.1
        for use_ring, target, unexplained in [(True, 0, True), (True, 120, False), (False, 0, True), (True, 60, True)]:
            num, den, _ = kernel(cam, occ, real, use_ring, cand, others, 3, target, unexplained)
            rn, rd = score_candidates_reference(cam.P, cam, occ, real, use_ring, cand, 1.65, 0.40, 3,
                                                others, 1.65, 0.40, target_pixels=target,
                                                count_unexplained=unexplained)
            np.testing.assert_array_equal(num, rn)
            np.testing.assert_array_equal(den, rd)


@pytest.mark.parametrize("radius", [0, 1, 2, 7, 26])
def test_within_l1_equals_the_iterated_cross_dilation(radius):
    from worldtrack.trackers.ellipsoid.score import within_l1, within_l1_reference
    rng = np.random.default_rng(radius)
    for trial in range(8):
        H, W = int(rng.integers(1, 90)), int(rng.integers(1, 120))
        fg = (rng.random((H, W)) < rng.choice([0.0, 0.002, 0.02, 0.3])).astype(np.uint8)
        if trial % 2:
            fg[0, rng.integers(0, W)] = fg[rng.integers(0, H), W - 1] = 1    # on the border
        out = within_l1(fg, radius)
        np.testing.assert_array_equal(out, within_l1_reference(fg, radius))
        assert out.dtype == np.uint8 and out.shape == (H, W)
    # One pixel: exactly the diamond |du| + |dv| <= radius around it.
    fg = np.zeros((61, 61), np.uint8)
    fg[30, 30] = 1
    v, u = np.mgrid[0:61, 0:61]
    np.testing.assert_array_equal(within_l1(fg, radius), (np.abs(u - 30) + np.abs(v - 30) <= radius).astype(np.uint8))
