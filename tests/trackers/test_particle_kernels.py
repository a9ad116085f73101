"""The particle tracker's compiled kernels against their plain references, for the per-frame images
the column kernel reads: the combined label-and-owner codes and the two nearest occluders.

Uses the small scene of ``test_particle.py``.
"""

from __future__ import annotations

import cv2
import pytest
import numpy as np

from worldtrack.trackers.particle.likelihood import (CameraLikelihood, add_camera, add_camera_reference,
                                                     column_counts_reference, occluder_layers,
                                                     occluder_layers_reference, owner_image, read_codes,
                                                     read_codes_reference, top_edge_terms_reference)
from worldtrack.trackers.particle.sampling import raster_contains

from test_particle import CAM, H, W, make_scene


def test_read_codes_agrees_with_reference():
    rng = np.random.default_rng(0)
    hit = rng.integers(0, 5, (H, W), dtype=np.uint8)          # 3 and 4 are no labels: background
    owner = rng.integers(0, 256, (H, W), dtype=np.uint8)
    codes = read_codes(hit, owner)
    np.testing.assert_array_equal(codes, read_codes_reference(hit, owner))
    np.testing.assert_array_equal(codes & 3, np.where(hit <= 2, hit, 0))
    np.testing.assert_array_equal(codes >> 2, np.minimum(owner, 63))
    assert ((owner > 63) & (codes >> 2 == 63)).sum() > 1000  # saturation exercised


def test_occluder_layers_agree_with_reference():
    """Random overlapping boxes, some out of view, with tied and undefined depths; also when an
    earlier result is reused."""
    rng = np.random.default_rng(1)
    for trial in range(20):
        n = int(rng.integers(1, 12))
        boxes = []
        for _ in range(n):
            u0, v0 = int(rng.integers(0, W)), int(rng.integers(0, H))      # clipped to the image, as boxes are
            boxes.append(None if rng.random() < 0.15 else
                         (u0, min(u0 + int(rng.integers(1, 150)), W), v0, min(v0 + int(rng.integers(1, 150)), H)))
        depths = rng.choice([1.0, 2.0, 2.5, 4.0, np.nan, np.inf], n) if trial % 2 else rng.uniform(1.0, 8.0, n)
        reused = occluder_layers((H, W), [(0, W, 0, H)] * 3, [3.0, 1.0, 2.0])
        for got in (occluder_layers((H, W), boxes, depths), occluder_layers((H, W), boxes, depths, out=reused)):
            near1, id1, near2 = got
            r1, rid, r2 = occluder_layers_reference((H, W), boxes, depths)
            np.testing.assert_array_equal(id1, rid)
            np.testing.assert_array_equal(near1, r1)
            np.testing.assert_array_equal(near2, r2)
            for me in range(-1, n):
                np.testing.assert_array_equal(got.depth_for(me), np.where(rid == me, r2, r1))
    # The test covers pixels with two layers, and ties resolved in box order.
    near1, id1, near2 = occluder_layers((H, W), [(0, 50, 0, 50), (20, 80, 20, 80), (10, 30, 10, 30)], [2.0, 2.0, 2.0])
    assert (id1[25, 25], near2[25, 25]) == (0, 2.0) and id1[60, 60] == 1 and np.isinf(near2[60, 60])


def test_column_kernel_agrees_with_reference_under_many_boxes():
    """More than 63 boxes over a pixel (the codes saturate there) and a box per filter: the kernel,
    reading the combined codes and the packed occluders, agrees with the reference."""
    cam = make_scene().cameras["cam"]
    rng = np.random.default_rng(2)
    hit = (cv2.GaussianBlur(rng.random((H, W)).astype(np.float32), (0, 0), 4) > 0.5).astype(np.uint8)
    hit[(hit == 1) & (rng.random((H, W)) < 0.2)] = 2
    boxes = [(40, 120, 30, 200), (100, 180, 0, 120), None] + [(150, 200, 60, 180)] * 70
    depths = np.concatenate([[2.0, 4.5, 3.0], rng.uniform(1.0, 6.0, 70)])
    owner = owner_image((H, W), boxes)
    assert owner.max() > 63
    n = 4000
    xy = np.column_stack([rng.uniform(-2.5, 2.5, n), rng.uniform(0.5, 6.0, n)])
    which = rng.integers(0, 4, n)
    hs = np.concatenate([[-0.2, -0.1], np.arange(20) * 0.1, [2.0, 2.1]])
    args = dict(on=2.77, off=-1.56, k_min=10, radius=0.1, below=-2.77, n_below=2, n_above=2, owner=owner,
                box=boxes[:2] + [None, boxes[3]], me=[0, 1, 2, 3], which=which, tops=rng.uniform(1.4, 2.0, n),
                top_sigma=0.1, occluders=occluder_layers((H, W), boxes, depths), margin=0.3, outside_unknown=True)
    out = CameraLikelihood(cam).column(hit, xy, hs, return_hidden=True, **args)
    ref = column_counts_reference(cam, hit, xy, hs, return_hidden=True, **args)
    for i in (0, 3, 4):                                   # counts, seen, hidden
        np.testing.assert_array_equal(out[i], ref[i])
    np.testing.assert_allclose(out[1], ref[1], rtol=0, atol=1e-9)
    assert (out[2] == ref[2]).mean() > 0.999              # ties between tops may resolve either way
    assert (out[4] > 0).sum() > 100                       # occluded samples exercised


def test_lines_of_sight_and_near_surface_agree_with_floor_rays():
    """The kernels' lines of sight equal Camera.floor_rays' (its fallback direction at the foot point
    and for NaN included), and the near-surface points ``xy − offset·along``."""
    cam = make_scene().cameras["cam"]
    cl = CameraLikelihood(cam)
    rng = np.random.default_rng(3)
    xy = np.column_stack([rng.normal(0, 3, 5000), rng.normal(2, 3, 5000)])
    xy[:3] = cam.centre[:2]                             # at the foot point
    xy[3] = np.nan
    along, _ = cam.floor_rays(xy)
    np.testing.assert_array_equal(cl.along(xy), along)
    np.testing.assert_array_equal(cl.near_surface(xy, 0.14), xy - 0.14 * along)
    assert np.array_equal(cl.along(xy[:1]), cam.floor_direction[None])


def test_add_camera_agrees_with_reference():
    rng = np.random.default_rng(4)
    n = 3000
    cameras = []
    for camera in range(3):
        lv = np.where(rng.random(n) < 0.1, -np.inf, rng.normal(0, 5, n))
        lv[:5] = -0.0
        cameras.append((rng.random(n) < 0.7, lv, rng.uniform(0, 2, n), rng.random(n) < 0.5))
    for penalty in (np.zeros(0), -rng.exponential(1.0, n)):
        states = []
        for fn in (add_camera, add_camera_reference):
            logpi, likely = np.zeros(n), np.ones(n, dtype=bool)
            n_seen, col = np.zeros(n, dtype=np.int32), np.zeros(n)
            for seen, lv, col_h, ok in cameras:           # three cameras in turn
                fn(seen, lv, penalty, 0.7, col_h, ok, logpi, likely, n_seen, col)
            states.append((logpi, likely, n_seen, col))
        for a, b in zip(*states):
            np.testing.assert_array_equal(a, b)
        assert np.isinf(states[0][0]).sum() > 100 and states[0][1].sum() > 100 and (states[0][2] == 3).sum() > 100


def test_raster_contains_agrees_with_walkable_raster():
    scene = make_scene()
    raster = scene.walkable.raster(0.01)
    rng = np.random.default_rng(5)
    xy = np.column_stack([rng.uniform(-4, 4, 20000), rng.uniform(-1, 8, 20000)])
    xy[:10] = np.nan
    got = raster_contains(raster, xy)
    np.testing.assert_array_equal(got, raster.contains(xy))
    assert 1000 < got.sum() < len(xy) - 1000


def test_bimodal_split_with_splittables_principal_is_the_same():
    """The split check reuses the principal axes that ``splittable`` computed for all clouds at once:
    the same sides (and the same None) as computing them for each cloud alone."""
    from worldtrack.trackers.particle.sampling import bimodal_split, splittable

    rng = np.random.default_rng(6)
    clouds = []
    for k in range(40):
        one = rng.normal(0, 0.1, (500, 3))
        if k % 2:                                         # two lumps side by side
            one[:250, 0] += rng.uniform(0.3, 0.9)
        clouds.append(one + [rng.uniform(-3, 3), rng.uniform(0, 6), 0])
    xyz = np.stack(clouds)
    wide, principal = splittable(xyz[:, :, :2], 0.35, 0.2, principal=True)
    np.testing.assert_array_equal(wide, splittable(xyz[:, :, :2], 0.35, 0.2))
    splits = 0
    for cloud, w, pc in zip(clouds, wide, principal):
        alone = bimodal_split(cloud[:, :2], 0.35, 0.5, 0.2)
        given = bimodal_split(cloud[:, :2], 0.35, 0.5, 0.2, principal=pc)
        assert (alone is None) == (given is None)
        if alone is not None:
            np.testing.assert_array_equal(alone, given)
            splits += 1
    assert 10 <= splits <= 20 and wide.sum() >= splits


def test_resampling_kernel_agrees_with_reference():
    """Systematic and stratified resampling (cumulative weights, normalised, points merged in one
    kernel) draw the NumPy lookup's indices: ties, zero weights and a row with one weight included."""
    from worldtrack.trackers.particle.sampling import _draw_rows, resample_reference, stratified_resample, systematic_resample

    rng = np.random.default_rng(7)
    for trial in range(30):
        f, m = int(rng.integers(1, 12)), int(rng.integers(1, 600))
        w = rng.random((f, m)) ** rng.uniform(1, 30)
        w[:, ::3] = 0.0
        w[0] = 0.0
        w[0, m // 2] = 2.5
        for resample, shape in ((systematic_resample, (f, 1)), (stratified_resample, (f, m))):
            got = resample(w, m, np.random.default_rng(trial))
            ref = resample_reference(w, np.random.default_rng(trial).random(shape), m)
            np.testing.assert_array_equal(got, ref)
            assert np.all(got[0] == m // 2) and not np.any(got[1:] % 3 == 0)
    # Points exactly on a cumulative weight (0, 1/4, 2/4, 3/4 over four equal weights) fall after it
    # (side="right"), in the kernel as in the reference; random points never test that.
    for r in (np.zeros((1, 1)), np.zeros((1, 4))):
        np.testing.assert_array_equal(_draw_rows(np.ones((1, 4)), r, 4), [[0, 1, 2, 3]])
        np.testing.assert_array_equal(resample_reference(np.ones((1, 4)), r, 4), [[0, 1, 2, 3]])


def test_take_rows_agrees_with_take_along_axis():
    from worldtrack.trackers.particle.sampling import take_rows

    rng = np.random.default_rng(8)
    idx = rng.integers(0, 50, (4, 70))
    for a in (rng.normal(size=(4, 50, 3)), rng.normal(size=(4, 50)), rng.random((4, 50)) < 0.5):
        want = np.take_along_axis(a, idx.reshape(idx.shape + (1,) * (a.ndim - 2)), axis=1)
        got = take_rows(a, idx)
        assert got.dtype == a.dtype and got.shape == want.shape
        np.testing.assert_array_equal(got, want)
    assert take_rows(np.zeros((2, 0, 3)), np.zeros((2, 0), dtype=np.int64)).shape == (2, 0, 3)


def test_columns_beside_and_boxes_apart_agree_with_numpy():
    """Where a filter learns its colours: the columns beside its centre (kernel against floor_rays),
    and which boxes overlap no other (integers against _overlaps)."""
    from worldtrack.trackers.particle import _overlaps
    from worldtrack.trackers.particle.likelihood import boxes_apart, columns_beside_reference

    cam = make_scene().cameras["cam"]
    cl = CameraLikelihood(cam)
    rng = np.random.default_rng(9)
    xy = np.column_stack([rng.uniform(-3, 3, 300), rng.uniform(0, 7, 300)])
    xy[0] = cam.centre[:2]
    spread = rng.uniform(0.05, 0.2, 300)
    for offset in (0.14, 0.0):
        got = cl.beside(xy, offset, spread)
        np.testing.assert_array_equal(got, columns_beside_reference(cam, xy, offset, spread))
    assert np.allclose(np.hypot(*(got[1::3] - got[::3]).T), spread)
    for trial in range(50):
        k = int(rng.integers(1, 15))
        u0, v0 = rng.integers(0, W - 1, k), rng.integers(0, H - 1, k)
        boxes = [None if rng.random() < 0.2 else (int(a), int(min(a + rng.integers(1, 60), W)), int(b),
                                                 int(min(b + rng.integers(1, 60), H))) for a, b in zip(u0, v0)]
        arr = np.array([(-1,) * 4 if b is None else b for b in boxes], dtype=np.int64).reshape(-1, 4)
        ov = _overlaps(boxes)
        np.fill_diagonal(ov, 0.0)
        want = np.array([b is not None for b in boxes]) & ~(ov > 0).any(axis=1)
        np.testing.assert_array_equal(boxes_apart(arr), want)
    assert boxes_apart(np.array([[0, 10, 0, 10], [10, 20, 0, 10], [5, 15, 9, 12]])).tolist() == [False, False, False]
    assert boxes_apart(np.array([[0, 10, 0, 10], [10, 20, 0, 10]])).tolist() == [True, True]   # edges touch


def test_colour_learning_kernel_agrees_with_numpy():
    from worldtrack.trackers.particle.appearance import MIN_LEARN_SAMPLES, N_BINS, ColourModel

    rng = np.random.default_rng(10)
    fast, slow = ColourModel(), ColourModel()
    for frame in range(30):
        bins = rng.integers(-1, N_BINS, (3, 6)).astype(np.int16)
        if frame % 7 == 3:
            bins[:] = -1
            bins[0, :MIN_LEARN_SAMPLES - 1] = 2                  # too few to learn from
        assert fast.learn(bins, 0.1) == slow.learn_reference(bins, 0.1)
        np.testing.assert_array_equal(fast.hist, slow.hist)
        assert fast.frames == slow.frames
    assert fast.frames > 20 and abs(fast.hist.sum() - 1) < 1e-12
    with pytest.raises(ValueError, match="below"):
        fast.learn(np.full(10, N_BINS), 0.1)


def test_order_statistic_agrees_with_partition():
    from worldtrack.trackers.particle.sampling import order_statistic

    rng = np.random.default_rng(11)
    for f, n, top in ((1, 1, 3), (4, 500, 27), (3, 37, 5), (2, 9, 5000)):      # 5000: the partition fallback
        x = rng.integers(0, top + 1, (f, n)).astype(np.int32)
        for rank in {0, n // 2, n - 1}:
            got = order_statistic(x, rank)
            assert got.dtype == x.dtype
            np.testing.assert_array_equal(got, np.partition(x, rank, axis=1)[:, rank])
    x = np.array([[5, 1, 3, 3, 0]], dtype=np.int32)
    assert order_statistic(x, 0)[0] == 0 and order_statistic(x, 2)[0] == 3 and order_statistic(x, 4)[0] == 5


def test_boxes_on_one_object_agrees_with_reference():
    """The merge's test of two filters on one object (boxes overlapping by ``merge_overlap`` in
    every camera that sees both), integers against the NumPy ratios of _overlaps."""
    from worldtrack.trackers.particle import _overlaps
    from worldtrack.trackers.particle.likelihood import boxes_on_one_object, boxes_on_one_object_reference

    rng = np.random.default_rng(12)
    found = 0
    for trial in range(60):
        c, k = int(rng.integers(1, 4)), int(rng.integers(2, 12))
        cams = []
        for _ in range(c):
            u0, v0 = rng.integers(0, 60, k), rng.integers(0, 60, k)
            cams.append([None if rng.random() < 0.2 else (int(a), int(a + rng.integers(5, 40)), int(b),
                                                         int(b + rng.integers(5, 40))) for a, b in zip(u0, v0)])
        arr = np.array([[(-1,) * 4 if b is None else b for b in cam] for cam in cams], dtype=np.int64)
        for min_overlap in (0.6, 0.3):
            got = boxes_on_one_object(arr, min_overlap)
            np.testing.assert_array_equal(got, boxes_on_one_object_reference(cams, min_overlap))
            found += got.sum()
        assert np.array_equal(boxes_on_one_object_reference([cams[0]], 0.6),
                              np.triu(~np.isnan(_overlaps(cams[0])) & (_overlaps(cams[0]) >= 0.6), 1))
    assert found > 20


def test_owner_image_agrees_with_reference_and_reused_equals_fresh():
    """The owner image (a kernel over the boxes, Python's slice rules, saturating at 255) against the
    box-by-box NumPy code, fresh and reusing the last image."""
    from worldtrack.trackers.particle.likelihood import owner_image_reference

    rng = np.random.default_rng(13)
    buf, previous = None, ()
    for trial in range(40):
        k = int(rng.integers(0, 6))
        boxes = [None if rng.random() < 0.2 else
                 (int(u), int(min(u + rng.integers(1, 90), W)), int(v), int(min(v + rng.integers(1, 90), H)))
                 for u, v in zip(rng.integers(0, W, k), rng.integers(0, H, k))]
        if trial % 5 == 4:
            boxes += [(-30, -5, 10, 400), (300, 10, -50, 20), (10, 40, -30, H)]   # slices from the end, empty
        fresh = owner_image((H, W), boxes)
        np.testing.assert_array_equal(fresh, owner_image_reference((H, W), boxes))
        buf = owner_image((H, W), boxes, buf, previous)
        previous = boxes
        np.testing.assert_array_equal(buf, fresh)
    assert buf.max() >= 1
    many = [(10, 20, 10, 20)] * 300
    np.testing.assert_array_equal(owner_image((H, W), many), owner_image_reference((H, W), many))
    assert owner_image((H, W), many)[15, 15] == 255


def test_split_sides_kernel_agrees_with_reference():
    """The end of bimodal_split (valley, sides, each side's mass) in one kernel, against NumPy."""
    from worldtrack.trackers.particle.sampling import _sides, _sides_reference

    rng = np.random.default_rng(14)
    found = 0
    for trial in range(200):
        n = int(rng.integers(8, 600))
        s = rng.normal(0, 0.1, n)
        if trial % 2:
            s[: int(rng.integers(1, n))] += rng.uniform(0.2, 0.9)
        side = np.empty(n, dtype=bool)
        for min_mass in (0.2, 0.45):
            ok = _sides(s, s.min(), 0.04, 0.05, 0.35, 0.5, min_mass, side)
            ref = _sides_reference(s, s.min(), 0.04, 0.05, 0.35, 0.5, min_mass)
            assert ok == (ref is not None)
            if ok:
                np.testing.assert_array_equal(side, ref)
                found += 1
    assert found > 30


def test_kernels_read_the_floor_columns_of_xyz():
    """near_surface and raster_contains read (N, 3) positions as their first two columns."""
    scene = make_scene()
    cl = CameraLikelihood(scene.cameras["cam"])
    rng = np.random.default_rng(15)
    xyz = np.column_stack([rng.uniform(-4, 4, 500), rng.uniform(-1, 8, 500), rng.uniform(0, 2, 500)])
    np.testing.assert_array_equal(cl.near_surface(xyz, 0.14), cl.near_surface(xyz[:, :2].copy(), 0.14))
    raster = scene.walkable.raster(0.01)
    np.testing.assert_array_equal(raster_contains(raster, xyz), raster.contains(xyz[:, :2]))


def test_gather_particles_and_principal_agree_with_numpy():
    """The resampled particles gathered in one kernel (heights drawn below the column tops) equal
    take_rows and the NumPy product; the covariance tail of _principal equals its NumPy code."""
    from worldtrack.trackers.particle.sampling import _principal, _principal_reference, gather_particles, take_rows

    rng = np.random.default_rng(16)
    f, m, n = 5, 300, 280
    parts = [rng.normal(size=(f, m, 3)), rng.normal(size=(f, m, 3)), rng.normal(size=(f, m)),
             rng.normal(size=(f, m)), rng.random((f, m)) < 0.5, rng.uniform(0, 2, (f, m))]
    idx = np.sort(rng.integers(0, m, (f, n)), axis=1)
    z = rng.random((f, n))
    for draws in (None, z):
        got = gather_particles(idx, *parts, z=draws)
        want = [take_rows(a, idx) for a in parts]
        if draws is not None:
            want[0][..., 2] = draws * want[5]
        for a, b in zip(got, want):
            assert a.dtype == b.dtype
            np.testing.assert_array_equal(a, b)
    xy = rng.normal(0, 0.3, (7, 500, 3))[:, :, :2]
    xy[3] *= 0.2                                          # a narrow cloud, not wide enough
    c, stats = _principal(xy)
    c_ref, stats_ref = _principal_reference(xy)
    np.testing.assert_array_equal(c, c_ref)
    for a, b in zip(stats, stats_ref):
        np.testing.assert_array_equal(a, b)
    from worldtrack.trackers.particle.sampling import _wide_enough, splittable
    wide = splittable(xy, 0.35, 0.2)
    np.testing.assert_array_equal(wide, _wide_enough(stats_ref[3], 0.35, 0.2))
    assert wide.sum() == 6 and not wide[3]


def test_particle_weights_agree_with_numpy_bit_for_bit():
    """Eq. 8's weights from the kernel's max and exponents against weights_reference: equal bit for bit
    for rows of filters and for one filter's row, a row of zero likelihood (-inf everywhere) weighs 1
    throughout and is resampled uniformly, and so does a row with a NaN (np.max's NaN is not finite)."""
    from worldtrack.trackers.particle.sampling import particle_weights, systematic_resample, weights_reference

    rng = np.random.default_rng(17)
    logpi = rng.normal(0, 20, (4, 300))
    logpi[logpi < -25] = -np.inf
    logpi[2] = -np.inf                                   # nothing likely: uniform weights
    for power in (0.2, 1.0):
        w = particle_weights(logpi, power)
        np.testing.assert_array_equal(w, weights_reference(logpi, power))
        np.testing.assert_array_equal(particle_weights(logpi[1], power), weights_reference(logpi[1], power))
    assert (w[2] == 1).all() and w[[0, 1, 3]].max(axis=1).tolist() == [1.0, 1.0, 1.0]
    idx = systematic_resample(w, 300, np.random.default_rng(3))
    assert len(np.unique(idx[2])) == 300 and len(np.unique(idx[0])) < 100   # uniform row vs peaked rows
    nan = logpi.copy()
    nan[0, 5] = np.nan
    np.testing.assert_array_equal(particle_weights(nan, 0.2), weights_reference(nan, 0.2))
    assert (particle_weights(nan, 0.2)[0] == 1).all()
    assert particle_weights(np.zeros((3, 0)), 0.2).shape == (3, 0)


def test_region_sizes_and_row_means_agree_with_numpy():
    from worldtrack.trackers.particle import _mean_rows
    from worldtrack.trackers.particle.sampling import region_sizes, region_sizes_reference

    rng = np.random.default_rng(18)
    sd = rng.uniform(0, 0.5, (9, 3))
    widths = rng.uniform(0.3, 0.6, 9)
    for w in (widths, np.zeros(0)):
        a, b = sd.copy(), sd.copy()
        sa, sb = np.empty(9), np.empty(9)
        region_sizes(a, w, sa)
        region_sizes_reference(b, w, sb)
        np.testing.assert_array_equal(a, b)
        np.testing.assert_array_equal(sa, sb)
        assert (a[:, :2] > sd[:, :2]).all() if len(w) else np.array_equal(a, sd)
    h = rng.normal(1.7, 0.1, (6, 500))
    np.testing.assert_array_equal(_mean_rows(h), h.mean(axis=1))


@pytest.mark.parametrize("offset", [0.14, 0.0])
def test_observe_column_equals_the_calls_one_by_one(offset):
    """One camera's share of the column likelihood in one compiled call (near surface, column kernel,
    colour penalties, sums) equals near_surface, CameraLikelihood.column, column_penalties and
    add_camera one after the other; with and without a colour image, and close_sums its NumPy code."""
    from worldtrack.trackers.particle.appearance import ColourModel, N_BINS, column_penalties, observe_column
    from worldtrack.trackers.particle.sampling import close_sums, close_sums_reference

    scene = make_scene()
    cam = scene.cameras["cam"]
    cl = CameraLikelihood(cam)
    rng = np.random.default_rng(19)
    hit = (cv2.GaussianBlur(rng.random((H, W)).astype(np.float32), (0, 0), 4) > 0.5).astype(np.uint8)
    hit[(hit == 1) & (rng.random((H, W)) < 0.2)] = 2
    image = rng.integers(0, 256, (H, W, 3)).astype(np.uint8)
    boxes = [(40, 160, 60, 240), (120, 220, 0, 150), None]
    n = 3000
    xyz = np.column_stack([rng.uniform(-3, 3, n), rng.uniform(-0.5, 6.0, n), rng.uniform(0, 2, n)])
    which = rng.integers(0, 3, n)
    models = [ColourModel(), None, ColourModel()]
    models[0].learn(rng.integers(0, N_BINS, 60), 1.0)
    heights = np.concatenate([[-0.2, -0.1], np.arange(20) * 0.1, [2.0, 2.1]])
    kw = dict(on=2.77, off=-1.56, k_min=10, radius=0.1, below=-2.77, n_below=2, n_above=2,
              owner=owner_image((H, W), boxes), box=boxes, tops=rng.uniform(1.4, 2.0, n), top_sigma=0.1,
              px_scale=[0.0, 0.3, 0.0], occluders=occluder_layers((H, W), boxes, [1.5, 2.5, 3.0]), me=[0, 1, 2],
              margin=0.3, which=which, outside_unknown=True, k_lo=[0, 4, 0])
    unlearnt = [None, None, models[2]]             # a second call: what filter 0 read before must not stay
    for colour, models in ((image, models), (image, unlearnt), (None, models)):
        state = [np.zeros(n), np.ones(n, dtype=bool), np.zeros(n, dtype=np.int32), np.zeros(n)]
        hid = np.empty(n, dtype=np.int32)
        observe_column(cl, xyz, offset, cl.column_args(hit, n, heights, **kw), hit, colour, models, 0.7, 8, *state, hid)
        surface = cl.near_surface(xyz, offset) if offset > 0 else xyz[:, :2]
        counts, ratio, top, seen, want_hid = cl.column(hit, surface, heights, return_hidden=True, **kw)
        penalty = column_penalties(cl, colour, hit, surface, models, which) if colour is not None else np.zeros(0)
        want = [np.zeros(n), np.ones(n, dtype=bool), np.zeros(n, dtype=np.int32), np.zeros(n)]
        add_camera_reference(seen, ratio, penalty, 0.7, heights[top], counts >= 8, *want)
        np.testing.assert_array_equal(hid, want_hid)
        for a, b in zip(state, want):
            np.testing.assert_array_equal(a, b)
        assert (penalty < 0).sum() > 100 if colour is not None and models[0] is not None else True
        raster = scene.walkable.raster(0.01)
        got, ref = [a.copy() for a in state], [a.copy() for a in state]
        close_sums(got[2], xyz, raster, got[0], got[1], got[3])
        close_sums_reference(ref[2], xyz, raster, ref[0], ref[1], ref[3])
        for a, b in zip(got, ref):
            np.testing.assert_array_equal(a, b)
        assert np.isinf(got[0]).sum() > 100 and got[1].sum() > 100


def test_predict_walk_is_prediction_then_height_walk():
    from worldtrack.trackers.particle.sampling import predict_state_reference, predict_walk, reflect_reference

    rng = np.random.default_rng(20)
    f, n = 3, 400
    old, v = rng.normal(0, 3, (f, n, 3)), rng.normal(0, 1.5, (f, n, 3))
    a, walk = rng.standard_normal((f, n, 3)), rng.standard_normal((f, n, 2))
    h, ha = rng.uniform(0.8, 1.9, (f, n)), rng.standard_normal((f, n))
    noise, scale = np.array([0.1, 0.1, 0.05]), np.array([0.3, 0.0, 0.2])
    v1, v2, x1, x2, h1 = v.copy(), v.copy(), np.empty_like(old), np.empty_like(old), np.empty_like(h)
    predict_walk(old, a, noise, v1, walk, scale, 2.5, 0.1, x1, h, ha, 0.2, 0.8, 1.9, h1)
    predict_state_reference(old, a, noise, v2, walk, scale, 2.5, 0.1, x2)
    np.testing.assert_array_equal(x1, x2)
    np.testing.assert_array_equal(v1, v2)
    np.testing.assert_array_equal(h1, reflect_reference(h + ha * 0.2, 0.8, 1.9))
    assert not np.array_equal(h1, h)
    h2 = h.copy()
    predict_walk(old, a, noise, v.copy(), walk, scale, 2.5, 0.1, x1, h, np.zeros(0), 0.2, 0.8, 1.9, h2)
    np.testing.assert_array_equal(h2, h)                  # no draws: the heights stay


def test_raster_blocks_answer_as_the_cells_do():
    """A walkable raster with holes and a ragged edge: with its blocks of all-walkable cells the
    look-up answers as WalkableRaster.contains, for points everywhere (and NaN)."""
    from worldtrack.scene.floor import WalkableRaster
    from worldtrack.trackers.particle.sampling import close_sums, close_sums_reference, raster_blocks

    rng = np.random.default_rng(21)
    inside = np.ones((250, 333), dtype=bool)
    inside[40:90, 100:180] = False                        # an obstacle
    inside[:, 300:] = rng.random((250, 33)) < 0.5         # a ragged edge
    raster = WalkableRaster(np.array([-1.0, 0.5]), 0.01, inside)
    blocks = raster_blocks(raster)
    assert blocks.shape == (8, 11) and 0 < blocks.sum() < blocks.size
    xy = np.column_stack([rng.uniform(-1.2, 2.5, 20000), rng.uniform(0.3, 3.2, 20000)])
    xy[:5] = np.nan
    want = raster.contains(xy)
    np.testing.assert_array_equal(raster_contains(raster, xy, blocks), want)
    assert 2000 < want.sum() < 18000
    n_seen = rng.integers(0, 3, 20000).astype(np.int32)
    a = [rng.normal(size=20000), rng.random(20000) < 0.5, rng.uniform(0, 4, 20000)]
    b = [x.copy() for x in a]
    close_sums(n_seen, xy, raster, *a, blocks)
    close_sums_reference(n_seen, xy, raster, *b)
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x, y)


def test_stacked_rows_follow_the_filters_arrays():
    """The tracking filters' per-particle arrays are kept as rows of one array between frames; the
    tracker reads that array only while every filter still holds its row, else it stacks afresh."""
    from worldtrack.trackers.particle import ParticleTracker, ParticleConfig
    from worldtrack.foreground.background import StaticBackground

    from test_particle import render
    from _render import texture

    scene = make_scene(entry=False)
    bg = texture(0)
    tracker = ParticleTracker(scene, {"cam": StaticBackground(bg, 30.0, "colour")},
                              ParticleConfig(births="none", surface_offset=0.0))
    people = [(-1.0, 3.0), (1.0, 3.5)]
    for x, y in people:
        tracker.init_track(x, y)
    rng = np.random.default_rng(22)
    for k in range(3):
        tracker.step({"cam": render(scene.camera("cam"), bg, people, rng)}, k / 10)
    fs = list(tracker.filters)
    assert len(fs) == 2
    kept = tracker._stacked(fs, "xyz")
    assert all(f.xyz.base is kept for f in fs)                      # rows of the kept array
    np.testing.assert_array_equal(kept, np.stack([f.xyz for f in fs]))
    fs[1].xyz = fs[1].xyz + 1.0                                     # a filter given a new array
    fresh = tracker._stacked(fs, "xyz")
    assert fresh is not kept
    np.testing.assert_array_equal(fresh, np.stack([f.xyz for f in fs]))
    np.testing.assert_array_equal(fresh[1], kept[1] + 1.0)
    np.testing.assert_array_equal(tracker._stacked(fs[::-1], "xyz"), np.stack([fs[1].xyz, fs[0].xyz]))  # other order


def test_learn_columns_equals_the_calls_one_by_one():
    """Colour learning in one compiled call: the same models (histograms, frames) as box_array,
    boxes_apart, beside, column_bins and ColourModel.learn one after the other; filters whose boxes
    overlap another's, or that are not learners, are not taught."""
    from worldtrack.trackers.particle.appearance import ColourModel, N_BINS, column_bins, learn_columns
    from worldtrack.trackers.particle.likelihood import boxes_apart

    cam = make_scene().cameras["cam"]
    cl = CameraLikelihood(cam)
    rng = np.random.default_rng(23)
    hit = (rng.random((H, W)) < 0.7).astype(np.uint8)
    image = rng.integers(0, 256, (H, W, 3)).astype(np.uint8)
    centres = np.array([[-2.0, 3.0], [0.0, 2.5], [0.2, 2.6], [2.0, 4.0], [1.0, 5.5], [-1.0, 5.0]])
    widths, heights = np.full(6, 0.45), np.array([1.7, 1.6, 1.8, 1.7, 1.75, 1.7])
    learners = np.array([True, True, True, True, False, True])
    old = ColourModel()
    old.learn(rng.integers(0, N_BINS, 30), 1.0)
    for trial in range(2):
        models = [ColourModel() if i % 2 else None for i in range(6)]
        models[3] = old if trial else models[3]
        ref = [None if m is None else ColourModel() for m in models]
        for a, b in zip(models, ref):                     # the same models, for the calls one by one
            if a is not None and a.hist is not None:
                b.hist, b.frames = a.hist.copy(), a.frames
        given = [m if m is not None else ColourModel() for m in models]
        taught = learn_columns(cl, image, hit, centres, widths, heights, learners, 0.05, 0.14, given, 0.1)
        boxes = cl.box_array(centres, widths, heights, 0.05)
        idx = np.flatnonzero(learners & boxes_apart(boxes))
        np.testing.assert_array_equal(np.flatnonzero(taught), idx)
        bins = column_bins(cl, image, hit, cl.beside(centres[idx], 0.14, 0.25 * widths[idx])).reshape(len(idx), -1)
        want = [r if r is not None else ColourModel() for r in ref]
        for i, b in zip(idx, bins):
            want[i].learn(b, 0.1)
        for a, b in zip(given, want):
            assert a.frames == b.frames
            assert (a.hist is None) == (b.hist is None)
            if a.hist is not None:
                np.testing.assert_array_equal(a.hist, b.hist)
        assert 1 not in idx and 2 not in idx and 4 not in idx and 3 in idx   # overlapping, not a learner
    assert old.frames == 2                                # learnt once more, blending into its histogram


def test_floor_distances_equal_floor_rays():
    cam = make_scene().cameras["cam"]
    rng = np.random.default_rng(24)
    xy = np.column_stack([rng.normal(0, 3, 3000), rng.normal(2, 3, 3000)])
    xy[0] = cam.centre[:2]
    got = CameraLikelihood(cam).distances(xy)
    np.testing.assert_array_equal(got, cam.floor_rays(xy)[1])
    assert got[0] == 0.0 and got.max() > 5


def test_bimodal_split_width_test_is_wide_enough():
    """bimodal_split's own 'wide enough' test on the principal variance it is given (one float, the
    IEEE operations of _wide_enough): a two-lump cloud is split with its own variance, and is one
    object with a variance below the limit or NaN."""
    import math
    from worldtrack.trackers.particle.sampling import _principal, _wide_enough, bimodal_split

    rng = np.random.default_rng(25)
    xy = rng.normal(0, 0.05, (500, 2))
    xy[:250, 0] += 0.8                                    # two lumps 0.8 m apart
    c, (sxx, syy, sxy, lam) = _principal(xy[None])
    row = (c[0], float(sxx[0]), float(syy[0]), float(sxy[0]), float(lam[0]))
    assert _wide_enough(lam, 0.35, 0.2)[0] and bimodal_split(xy, 0.35, 0.5, 0.2, principal=row) is not None
    limit = (0.35 * math.sqrt(0.2 * 0.8)) ** 2
    for narrow in (limit * (1 - 1e-9), 0.0, -0.0, -1.0, float("nan")):
        assert not _wide_enough(np.array([narrow]), 0.35, 0.2)[0]
        assert bimodal_split(xy, 0.35, 0.5, 0.2, principal=row[:4] + (narrow,)) is None


def test_inverse_lengths_agree_with_numpy():
    from worldtrack.trackers.particle.sampling import inverse_lengths, inverse_lengths_reference

    rng = np.random.default_rng(26)
    uv = rng.normal(300, 80, (2, 200, 2))
    uv[1, :5] = uv[0, :5]                                 # zero length
    uv[0, 5:8] = np.nan                                   # not in front of the camera
    out = np.empty(200)
    inverse_lengths(uv, 19, out)
    np.testing.assert_array_equal(out, inverse_lengths_reference(uv, 19))
    assert np.all(out[:8] == 0) and np.all(out[8:] > 0)


def _top_edge(cl, hit, xy, tops, offsets, on, off, weight, out=None, **reading):
    """CameraLikelihood.top_edge for particles read with ``reading`` (column_args' owner, box, ...)."""
    out = np.zeros(len(xy)) if out is None else out
    args = cl.column_args(hit, len(xy), np.zeros(1), on, off, **reading)
    cl.top_edge(args, xy, tops, offsets, weight, out)
    return out


def test_top_edge_kernel_agrees_with_reference():
    """Random labels (object, background, no evidence), particles in and out of view, heights up to
    where the samples leave the image; with and without lens distortion; plain, and with other
    objects' boxes (background) and nearer ones (no evidence) over the samples."""
    rng = np.random.default_rng(11)
    labels = rng.integers(0, 3, (H, W)).astype(np.uint8)
    n = 3000
    xyz = np.column_stack([rng.uniform(-4, 4, n), rng.uniform(-0.5, 8.0, n), np.zeros(n)])
    tops = rng.uniform(0.5, 4.0, n)
    offsets = np.array([-0.06, -0.03, 0.03, 0.06])
    boxes = [(40, 160, 0, 140), (120, 260, 20, 200), None, (0, W, 0, 60)]
    depths = [2.0, 5.0, 3.0, 4.0]
    which = rng.integers(0, 4, n)
    explained = dict(owner=owner_image((H, W), boxes), box=boxes, me=[0, 1, 2, 3], which=which,
                     occluders=occluder_layers((H, W), boxes, depths), margin=0.3)
    for dist in ([0, 0, 0, 0, 0], [-0.2, 0.05, 0.001, -0.002, 0]):
        cam = make_scene(cameras=(dict(CAM, distortion=dist) if any(dist) else CAM,)).cameras["cam"]
        cl = CameraLikelihood(cam)
        for reading in ({}, explained):
            out = _top_edge(cl, labels, xyz, tops, offsets, 2.5, -0.9, 0.7, out=np.full(n, 0.5), **reading)
            ref = 0.5 + top_edge_terms_reference(cam, labels, xyz, tops, offsets, 2.5, -0.9, 0.7, **reading)
            np.testing.assert_allclose(out, ref, rtol=0, atol=1e-12)
            assert len(np.unique(np.round(out, 9))) > 10       # every kind of term exercised
            assert (out == 0.5).sum() > 50                      # some particles wholly out of view
        plain = top_edge_terms_reference(cam, labels, xyz, tops, offsets, 2.5, -0.9, 0.7)
        assert (out - 0.5 != plain).sum() > 300                 # the boxes changed many particles' terms


def test_top_edge_peaks_at_the_true_height_and_depth():
    """A flat figure 0.5 m wide and 1.6 m tall facing the camera 4 m in front of it: with the place
    known the edge terms are best within a step (and a pixel) of the true height; with the height
    known, within the depth that step spans along the line of sight (0.03 m / 0.28, the head ray's
    slope). A height 0.1 m off (the column's grid) loses everything: too tall reads two misses, too
    short has object above its top."""
    cam = make_scene().cameras["cam"]
    cl = CameraLikelihood(cam)
    truth = np.array([0.0, 4.0])
    corners = np.array([[-0.25, 4.0, 0.0], [0.25, 4.0, 0.0], [0.25, 4.0, 1.6], [-0.25, 4.0, 1.6]])
    labels = np.zeros((H, W), dtype=np.uint8)
    cv2.fillConvexPoly(labels, np.round(cam.project(corners)).astype(np.int32), 1)
    offsets = np.array([-0.06, -0.03, 0.03, 0.06])
    on, off = 2.5, -0.9

    def terms(xy, tops):
        return _top_edge(cl, labels, np.asarray(xy, dtype=float), np.asarray(tops, dtype=float), offsets, on, off, 1.0)

    heights = np.arange(1.3, 1.9, 0.005)
    by_height = terms(np.repeat(truth[None], len(heights), 0), heights)
    best = heights[by_height == by_height.max()]
    assert by_height.max() == 2 * on
    assert best.min() >= 1.6 - 0.03 - 0.02 and best.max() <= 1.6 + 0.03 + 0.02
    depths = np.arange(3.0, 5.0, 0.01)
    along = terms(np.column_stack([np.zeros(len(depths)), depths]), np.full(len(depths), 1.6))
    good = depths[along == along.max()]
    assert along.max() == 2 * on and good.min() >= 4.0 - 0.15 and good.max() <= 4.0 + 0.15
    assert terms([truth], [1.7])[0] == 2 * off and terms([truth], [1.5])[0] == 0.0


def test_tracking_likelihood_adds_the_weighted_top_edge_terms():
    """ParticleTracker.likelihood with ``top_edge=True`` (tracking filters) adds ``config.top_edge``
    times the kernel's terms at the particles' own heights, with the configured offsets; without it,
    or with ``top_edge=0``, nothing."""
    from worldtrack.foreground.background import StaticBackground
    from worldtrack.trackers.particle import ParticleConfig, ParticleTracker
    from _render import texture

    scene = make_scene()
    cam = scene.cameras["cam"]
    rng = np.random.default_rng(12)
    labels = (cv2.GaussianBlur(rng.random((H, W)).astype(np.float32), (0, 0), 3) > 0.5).astype(np.uint8)
    n = 400
    xyz = np.column_stack([rng.uniform(-2.5, 2.5, n), rng.uniform(1.0, 6.0, n), np.zeros(n)])
    h = rng.uniform(1.4, 1.9, n)
    fgs = {"cam": StaticBackground(texture(0), 30.0, "colour")}
    tracker = ParticleTracker(scene, fgs, ParticleConfig(top_edge=0.7, top_edge_step=0.04, top_edge_samples=3))
    plain, _, _ = tracker.likelihood(xyz, {"cam": labels}, h=h)
    edged, _, _ = tracker.likelihood(xyz, {"cam": labels}, h=h, top_edge=True)
    on, off = np.log(0.6 / 0.05), np.log(0.4 / 0.95)
    terms = top_edge_terms_reference(cam, labels, xyz, h, [-0.12, -0.08, -0.04, 0.04, 0.08, 0.12], on, off, 0.7)
    finite = np.isfinite(plain)
    assert finite.sum() > 300 and np.count_nonzero(terms[finite]) > 100
    np.testing.assert_allclose(edged[finite], plain[finite] + terms[finite], rtol=0, atol=1e-9)
    np.testing.assert_array_equal(np.isfinite(edged), finite)
    off_tracker = ParticleTracker(scene, fgs, ParticleConfig(top_edge=0.0))
    np.testing.assert_array_equal(off_tracker.likelihood(xyz, {"cam": labels}, h=h, top_edge=True)[0], plain)
    # With another object's box over the image: raw labels by default, the column's reading with
    # top_edge_explain.
    boxes = [(0, W // 2, 0, H), None]
    owners = {"cam": owner_image((H, W), boxes)}
    second = np.ones(n, dtype=np.int64)                     # every particle is filter 1's
    for explain in (False, True):
        tr = ParticleTracker(scene, fgs, ParticleConfig(top_edge=0.7, top_edge_step=0.04, top_edge_samples=3,
                                                        top_edge_explain=explain))
        args = (xyz, {"cam": labels}, owners, {"cam": list(boxes)}, h)
        base = tr.likelihood(*args, me=[0, 1], which=second)[0]
        got = tr.likelihood(*args, me=[0, 1], which=second, top_edge=True)[0]
        reading = dict(owner=owners["cam"], box=boxes, me=[0, 1], which=second) if explain else {}
        want = top_edge_terms_reference(cam, labels, xyz, h, [-0.04, -0.08, -0.12, 0.04, 0.08, 0.12], on, off, 0.7,
                                        **reading)
        ok = np.isfinite(base)
        np.testing.assert_allclose(got[ok], base[ok] + want[ok], rtol=0, atol=1e-9)
    assert not np.allclose(want, terms)                     # the box changed the terms
