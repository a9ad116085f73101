"""A person given a lost id back keeps the height measured under it (``height.keep_with_id``)."""

import numpy as np
import pytest
from _ellipsoid_scenes import drawn_frame, noise_backgrounds, one_camera_scene

from worldtrack.config import with_overrides
from worldtrack.foreground import make_foregrounds
from worldtrack.trackers.base import Frame, Person
from worldtrack.trackers.ellipsoid import EllipsoidConfig, EllipsoidTracker
from worldtrack.trackers.ellipsoid import height as height_module
from worldtrack.trackers.ellipsoid.config import HeightConfig
from worldtrack.trackers.ellipsoid.kept_heights import KeptHeights

FPS = 10.0


def test_the_kept_samples_come_first_and_the_last_ones_are_kept():
    kept = KeptHeights(HeightConfig(samples=6))
    kept.remember([Person(id=2, x=0.0, y=0.0, height_samples=[1.60, 1.61, 1.62, 1.59, 1.60]),
                   Person(id=-4, x=0.0, y=0.0, height_samples=[1.9, 1.9, 1.9])])   # a candidate: not kept
    back = Person(id=2, x=0.0, y=0.0, height_samples=[1.95, 1.96])
    kept.give_back(back, default_height=1.75)
    assert back.height_samples == [1.61, 1.62, 1.59, 1.60, 1.95, 1.96]   # 7 in, the oldest dropped
    assert back.height == pytest.approx(1.615)                           # their median, off the default
    other = Person(id=4, x=0.0, y=0.0, height=1.75, height_samples=[1.95])
    kept.give_back(other, default_height=1.75)                            # nothing kept for id 4
    assert other.height_samples == [1.95] and other.height == 1.75


def _height_after_a_gap(keep: bool, monkeypatch) -> tuple[list[list[int]], float, float]:
    """A person walks at 1 m/s, is not drawn for 1.5 s (frames 12–26) and walks on. Every height
    measurement reads 1.88 m before the gap and 2.02 m after it (a head joined by something in the
    background). Returns the ids per frame, the height just before the gap and at the end."""
    phase = {"after": False}
    monkeypatch.setattr(height_module, "measure_height", lambda *a, **k: 2.02 if phase["after"] else 1.88)
    scene = one_camera_scene()
    rng = np.random.default_rng(3)
    bg = noise_backgrounds(scene, rng)["cam"]
    cfg = with_overrides(EllipsoidConfig(), {"lost.keep_s": 2.0, "identity.reid_distance": 0.0,
                                             "height.samples": 8, "height.keep_with_id": keep})
    tr = EllipsoidTracker(scene, make_foregrounds(scene, {"cam": bg}, "colour"), cfg)
    ids, before = [], float("nan")
    for i in range(40):
        phase["after"] = i >= 27
        people = [] if 12 <= i < 27 else [(-2.5 + i / FPS, 1.5)]
        tracks = tr.step({"cam": Frame(drawn_frame(scene, bg, people, rng), i / FPS, i)}, i / FPS)
        ids.append([t.id for t in tracks])
        if i == 11:
            before = tr.position_map[1].height
    return ids, before, tr.position_map[1].height


def test_a_returning_person_keeps_the_height_measured_before(monkeypatch):
    ids, before, end = _height_after_a_gap(True, monkeypatch)
    assert ids[5:12] == [[1]] * 7 and [] in ids[12:27] and ids[-8:] == [[1]] * 8   # lost, and given back
    assert before == pytest.approx(1.88)
    assert end == pytest.approx(1.88)
    ids, before, end = _height_after_a_gap(False, monkeypatch)                     # measured afresh
    assert ids[-8:] == [[1]] * 8 and before == pytest.approx(1.88)
    assert end == pytest.approx(2.02)
