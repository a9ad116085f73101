"""Eq. 5: the candidate-scoring kernel against its plain NumPy reference, and on ideal images."""

import numpy as np
import pytest
from _ellipsoid_scenes import lab_scene, person_mask

from worldtrack.trackers.ellipsoid.args import DrawArgs, Forms, People, ScoreArgs, camera_args
from worldtrack.trackers.ellipsoid.forms import person_forms
from worldtrack.trackers.ellipsoid.real import ternary_real
from worldtrack.trackers.ellipsoid.score import score_camera, score_candidates, score_candidates_reference


@pytest.fixture(scope="module")
def lab():
    return lab_scene()


def kernel(cam, occ, real, use_ring, cand, others, ring, target, count_unexplained=False, ring_fraction=0.0):
    """Draw candidates and others with the compiled forms, score them with the compiled kernel."""
    args = camera_args(cam, float(ring), occ)
    draw = DrawArgs(0.1, ring_fraction)
    c = person_forms(args, cand, np.full(len(cand), 1.65), np.full(len(cand), 0.40), draw)
    o = person_forms(args, others, np.full(len(others), 1.65), np.full(len(others), 0.4), draw)
    return score_candidates(args, real, c, o, ScoreArgs(use_ring, target, count_unexplained))


def reference(cam, occ, real, use_ring, cand, others, ring, target, count_unexplained=False, ring_fraction=0.0):
    return score_candidates_reference(cam, real, People(cand, 1.65, 0.40), People(others, 1.65, 0.40), ring,
                                      ScoreArgs(use_ring, target, count_unexplained), DrawArgs(0.1, ring_fraction),
                                      occ)


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
                rn, rd = reference(cam, occ, real, use_ring, cand, others, 5, target, unexplained, frac)
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


def test_obstacle_hides_the_lower_body(lab):
    cam = lab.cameras["cam1"]
    occ = lab.occlusion("cam1").floor_distance
    behind_desk = np.array([[-1.0, 2.9]])   # the lab's desk is at y 2.1…2.7
    f = person_forms(camera_args(cam, 5.0, occ), behind_desk, np.array([1.65]), np.array([0.4]), DrawArgs(0.1, 0.0))
    assert f.valid[0]
    full = np.ones((cam.height, cam.width), np.int8)
    free = np.full_like(occ, np.inf)
    _, _, n_free = kernel(cam, free, full, True, behind_desk, np.zeros((0, 2)), 5, 0)
    _, _, n_occ = kernel(cam, occ, full, True, behind_desk, np.zeros((0, 2)), 5, 0)
    assert 0 < n_occ[0] < 0.85 * n_free[0]


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
            rn, rd = reference(cam, occ, real, use_ring, cand, others, 3, target, unexplained)
            np.testing.assert_array_equal(num, rn)
            np.testing.assert_array_equal(den, rd)


def test_score_camera_leaves_the_moved_person_out_of_the_joint_image(lab):
    # score_camera draws the candidates itself and scores them against everybody but ``skip``:
    # the same sums as score_candidates with that person's forms marked invalid.
    cam = lab.cameras["cam1"]
    occ = lab.occlusion("cam1").floor_distance
    args, draw = camera_args(cam, 5.0, occ), DrawArgs(0.1, 2.0)
    people = np.array([[-1.0, 1.0], [-0.7, 1.3], [-1.4, 2.0]])
    everyone = person_forms(args, people, np.full(3, 1.65), np.full(3, 0.4), draw)
    real = ternary_real(sum(person_mask(cam, p, 1.65, 0.4) for p in people).clip(0, 1).astype(np.uint8), 5)
    cand = people[1] + np.array([(i, j) for i in (-1, 0, 1) for j in (-1, 0, 1)]) * 0.05
    opts = ScoreArgs(True, 400, True)
    num, den, ci, cr, cb, cv, cd = score_camera(args, real, cand, np.full(9, 1.65), np.full(9, 0.4), draw, everyone, 1,
                                                opts)
    valid = everyone.valid.copy()
    valid[1] = False
    others = Forms(everyone.inner, everyone.ring, everyone.box, valid, everyone.dist)
    rn, rd, _ = score_candidates(args, real, Forms(ci, cr, cb, cv, cd), others, opts)
    np.testing.assert_array_equal(num, rn)
    np.testing.assert_array_equal(den, rd)
    assert np.argmax(num / den) == 4                    # the person's own place fits best
    assert everyone.valid[1]                            # the caller's forms are left alone
