"""The per-frame layers the column kernel reads beside the labels — the owner image, the combined
label-and-owner codes and the two nearest occluders — against their plain references."""

from __future__ import annotations

import numpy as np

from worldtrack.trackers.particle.likelihood.images import (occluder_layers, occluder_layers_reference, owner_image,
                                                            owner_image_reference, read_codes, read_codes_reference)

from particle_scenes import H, W


def test_read_codes_agrees_with_reference():
    rng = np.random.default_rng(0)
    hit = rng.integers(0, 5, (H, W), dtype=np.uint8)          # 3 and 4 are no labels: background
    owner = rng.integers(0, 256, (H, W), dtype=np.uint8)
    codes = read_codes(hit, owner)
    np.testing.assert_array_equal(codes, read_codes_reference(hit, owner))
    np.testing.assert_array_equal(codes & 3, np.where(hit <= 2, hit, 0))
    np.testing.assert_array_equal(codes >> 2, np.minimum(owner, 63))
    assert ((owner > 63) & (codes >> 2 == 63)).sum() > 1000  # saturation exercised


def test_occluder_layers_keep_the_two_nearest_boxes():
    boxes = [(0, 10, 0, 10), (5, 15, 5, 15), None, (8, 12, 8, 12)]
    near1, id1, near2 = occluder_layers((20, 20), boxes, [3.0, 2.0, 1.0, 4.0])
    assert (near1[0, 0], id1[0, 0], near2[0, 0]) == (3.0, 0, np.inf)
    assert (near1[9, 9], id1[9, 9], near2[9, 9]) == (2.0, 1, 3.0)          # boxes 0, 1, 3 overlap here
    assert (near1[11, 11], id1[11, 11], near2[11, 11]) == (2.0, 1, 4.0)
    assert (near1[19, 19], id1[19, 19]) == (np.inf, -1)
    # Reused for other boxes: the old ones are cleared, the result is as if made afresh.
    reused = occluder_layers((20, 20), [(2, 6, 12, 18)], [5.0], out=occluder_layers((20, 20), boxes, [3, 2, 1, 4]))
    fresh = occluder_layers((20, 20), [(2, 6, 12, 18)], [5.0])
    for a, b in zip(reused, fresh):
        np.testing.assert_array_equal(a, b)
    depth = occluder_layers((20, 20), boxes, [3.0, 2.0, 1.0, 4.0]).depth_for(1)
    assert depth[9, 9] == 3.0 and depth[11, 11] == 4.0 and depth[0, 0] == 3.0


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


def test_owner_image_agrees_with_reference_and_reused_equals_fresh():
    """The owner image (a kernel over the boxes, Python's slice rules, saturating at 255) against the
    box-by-box NumPy code, fresh and reusing the last image."""
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
