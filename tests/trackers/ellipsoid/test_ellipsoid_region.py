"""One id per visit to a region of interest (:mod:`worldtrack.trackers.ellipsoid.region`)."""

import numpy as np
import pytest
from _ellipsoid_scenes import drawn_frame, noise_backgrounds, one_camera_scene

from worldtrack.config import with_overrides
from worldtrack.errors import InputError
from worldtrack.foreground import make_foregrounds
from worldtrack.trackers.base import Frame, Track
from worldtrack.trackers.ellipsoid import EllipsoidConfig, EllipsoidTracker
from worldtrack.trackers.ellipsoid.region import RegionVisits
from worldtrack.trackers.ellipsoid.region_config import RegionConfig

FPS = 10.0
SQUARE = [0, 0, 4, 0, 4, 3, 0, 3]


def _ids(visits: RegionVisits, walk, pid: int) -> list[int]:
    return [visits.relabel([Track(pid, x, y)], t)[0].id for t, x, y in walk]


def test_a_new_id_only_after_the_time_outside():
    visits = RegionVisits(RegionConfig(area=SQUARE, outside_s=1.0))
    # In, out for 0.5 s (wavering at the edge), in, out for 1 s, in: one new id, at the second return.
    walk = [(0.0, 1, 1), (0.1, 1, 3.2), (0.6, 1, 3.2), (0.7, 1, 2.9), (1.0, 5, 1), (2.0, 5, 1), (2.1, 3.5, 1)]
    assert _ids(visits, walk, 5) == [1, 1, 1, 1, 1, 1, 2]
    # Another person, and the first one given back by the map later in the same visit: ids stay apart.
    assert [tr.id for tr in visits.relabel([Track(8, 1, 1), Track(5, 2, 2)], 3.0)] == [3, 2]
    # Off (no area): the map's ids as they are.
    assert _ids(RegionVisits(RegionConfig()), walk, 5) == [5] * len(walk)


def test_the_area_is_checked_and_read_from_text():
    assert RegionConfig(area="0,0 4,0 4,3").ring().shape == (3, 2)
    for bad in ("0,0,4,0", "0,0,4,0,4", "a,b,c,d,e,f"):
        with pytest.raises(InputError, match="ellipsoid.region.area"):
            with_overrides(EllipsoidConfig(), {"region.area": bad})


def _walk_out_and_back(area: list[float]) -> list[list[int]]:
    """Ids per frame: a person in view walks along x at 1 m/s from -2.5 to -0.5 m and back at y = 2 m."""
    scene = one_camera_scene()
    rng = np.random.default_rng(3)
    bg = noise_backgrounds(scene, rng)["cam"]
    tr = EllipsoidTracker(scene, make_foregrounds(scene, {"cam": bg}, "colour"),
                          with_overrides(EllipsoidConfig(), {"region.area": area}))
    ids = []
    for i in range(41):
        x = -2.5 + min(i, 40 - i) / FPS
        tracks = tr.step({"cam": Frame(drawn_frame(scene, bg, [(x, 2.0)], rng), i / FPS, i)}, i / FPS)
        ids.append([t.id for t in tracks])
    return ids


def test_the_tracker_reports_a_person_back_in_the_region_under_a_new_id():
    # The region ends at x = -1.8 m: the person is outside from about frame 7 to 33 (2.6 s).
    inside_left = [-4, -1.5, -1.8, -1.5, -1.8, 5, -4, 5]
    ids = _walk_out_and_back(inside_left)
    assert ids[2] == [1] and ids[30] == [1] and ids[-3:] == [[2]] * 3
    assert _walk_out_and_back([])[-3:] == [[1]] * 3          # off: one id throughout
