"""The likelihood summed over cameras — one camera's share added, the particles no camera sees or off
the floor closed — and the fused one-call observation of the column ratio, against the readable
steps one by one."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from worldtrack.scene.floor import WalkableRaster
from worldtrack.trackers.particle.appearance import ColourModel, N_BINS, column_penalties
from worldtrack.trackers.particle.floor import raster_blocks, raster_contains
from worldtrack.trackers.particle.likelihood import CameraLikelihood, Sums, occluder_layers, owner_image
from worldtrack.trackers.particle.likelihood.fused import observe_column
from worldtrack.trackers.particle.likelihood.sums import (add_camera, add_camera_reference, close_sums,
                                                          close_sums_reference)

from particle_scenes import RING_HEIGHTS, H, W, column, column_parts, make_scene


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


def test_raster_blocks_answer_as_the_cells_do():
    """A walkable raster with holes and a ragged edge: with its blocks of all-walkable cells the
    look-up answers as WalkableRaster.contains, for points everywhere (and NaN); close_sums with them
    as its NumPy code."""
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


def test_raster_contains_agrees_with_walkable_raster():
    scene = make_scene()
    raster = scene.walkable.raster(0.01)
    rng = np.random.default_rng(5)
    xy = np.column_stack([rng.uniform(-4, 4, 20000), rng.uniform(-1, 8, 20000)])
    xy[:10] = np.nan
    got = raster_contains(raster, xy)
    np.testing.assert_array_equal(got, raster.contains(xy))
    assert 1000 < got.sum() < len(xy) - 1000


@pytest.mark.parametrize("offset", [0.14, 0.0])
def test_observe_column_equals_the_calls_one_by_one(offset):
    """One camera's share of the column likelihood in one compiled call (near surface, column kernel,
    colour penalties, sums) equals near_surface, CameraLikelihood.column, column_penalties and
    add_camera one after the other; with and without a colour image, and close_sums its NumPy code."""
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
    kw = dict(on=2.77, off=-1.56, k_min=10, radius=0.1, below=-2.77, n_below=2, n_above=2,
              owner=owner_image((H, W), boxes), box=boxes, tops=rng.uniform(1.4, 2.0, n), top_sigma=0.1,
              px_scale=[0.0, 0.3, 0.0], occluders=occluder_layers((H, W), boxes, [1.5, 2.5, 3.0]), me=[0, 1, 2],
              margin=0.3, which=which, outside_unknown=True, k_lo=[0, 4, 0])
    spec, read, tops = column_parts(RING_HEIGHTS, **kw)
    unlearnt = [None, None, models[2]]             # a second call: what filter 0 read before must not stay
    for colour, models in ((image, models), (image, unlearnt), (None, models)):
        state = Sums.start(n)
        hid = np.empty(n, dtype=np.int32)
        observe_column(cl, xyz, offset, spec, cl.reading(hit, n, read, tops), hit, colour, models, 0.7, 8, state, hid)
        surface = cl.near_surface(xyz, offset) if offset > 0 else xyz[:, :2]
        counts, ratio, top, seen, want_hid = column(cl, hit, surface, RING_HEIGHTS, **kw)
        penalty = column_penalties(cl, colour, hit, surface, models, which) if colour is not None else np.zeros(0)
        want = Sums.start(n)
        add_camera_reference(seen, ratio, penalty, 0.7, RING_HEIGHTS[top], counts >= 8, *want)
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
