"""Floor: point-in-area, holes, obstacle footprints, distance field, entry regions."""

import numpy as np
from matplotlib.path import Path as MplPath

from worldtrack.scene.floor import (EntryRegion, FloorPolygon, WalkableArea, entry_region_index,
                                    points_in_polygon, polygon_area)


def test_points_in_polygon_agrees_with_matplotlib_on_a_concave_polygon():
    ring = np.array([[0, 0], [4, 0], [4, 3], [2, 1.5], [0, 3]], float)
    rng = np.random.default_rng(0)
    pts = rng.uniform(-1, 5, (5000, 2))
    ours = points_in_polygon(pts, ring)
    ref = MplPath(ring).contains_points(pts)
    # Only points within a hair of an edge may differ.
    assert (ours != ref).sum() <= 2
    assert abs(ours.mean() - 9 / 36) < 0.02  # polygon area 9 m² in a 36 m² box


def test_holes_and_blocking_footprints_are_not_walkable():
    room = FloorPolygon(np.array([[0, 0], [6, 0], [6, 4], [0, 4]], float),
                        holes=(np.array([[1, 1], [2, 1], [2, 2], [1, 2]], float),))
    desk = np.array([[4, 1], [5, 1], [5, 3], [4, 3]], float)
    area = WalkableArea((room,), (desk,))
    pts = np.array([[0.5, 0.5], [1.5, 1.5], [4.5, 2.0], [7.0, 1.0], [3.0, 3.0]])
    assert area.contains(pts).tolist() == [True, False, False, False, True]
    assert area.on_floor(pts).tolist() == [True, False, True, False, True]
    assert area.area == 24 - 1


def test_distance_field_measures_walls_and_obstacles():
    room = FloorPolygon(np.array([[0, 0], [4, 0], [4, 4], [0, 4]], float))
    desk = np.array([[3, 1.5], [3.5, 1.5], [3.5, 2.5], [3, 2.5]], float)
    partition = np.array([[1, 3], [1, 4], [1, 4], [1, 3]], float)  # a vertical patch: a segment
    field = WalkableArea((room,), (desk, partition)).distance_field(0.02)
    d = field.sample([[1.0, 1.0], [2.0, 2.0], [2.5, 2.0], [-0.5, 2.0], [1.3, 3.5]])
    assert abs(d[0] - 1.0) < 0.03          # 1 m from two walls
    assert abs(d[1] - 1.0) < 0.03          # 1 m from the desk's west face (x = 3)
    assert abs(d[2] - 0.5) < 0.03
    assert abs(d[3] + 0.5) < 0.03          # outside: negative
    assert abs(d[4] - 0.3) < 0.03          # the thin partition counts
    g = field.gradient([[0.5, 2.0]])[0]
    assert g[0] > 0.9 and abs(g[1]) < 0.1  # moving away from the west wall increases clearance


def test_entry_region_index_and_area():
    regs = [EntryRegion("door", np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)),
            EntryRegion("gate", np.array([[5, 5], [6, 5], [6, 6], [5, 6]], float))]
    idx = entry_region_index(regs, [[0.5, 0.5], [5.5, 5.2], [3, 3]])
    assert idx.tolist() == [0, 1, -1]
    assert polygon_area([[0, 0], [2, 0], [2, 3], [0, 3]]) == 6.0
