"""One rendered frame of the line-of-sight room and a person put on its camera's line of sight
(shared by the feet and depth tests; imported as ``_line_of_sight``)."""

from __future__ import annotations

import numpy as np

from worldtrack.experiment import synthetic_tracker
from worldtrack.synth import make_scenario


def line_of_sight_frame() -> tuple:
    """One rendered frame of the line-of-sight room (320x240, one camera 2.5-3 m high, people
    5-10 m away): the tracker, its foreground labels, the instance image and the truth of the
    person seen best (head and feet in view, most pixels)."""
    sc = make_scenario("line-of-sight", size=(320, 240), frames=1, seed=7, floor_clothes=0)
    bundle = next(iter(sc.frames()))
    tracker = synthetic_tracker(sc, "ellipsoid")
    view = bundle.views["cam"]
    labels = tracker.views["cam"].foreground.labels(view.image)
    whole = [g for g in bundle.gt if g["head_cam"] and g["feet_cam"]]
    best = max(whole, key=lambda g: np.count_nonzero(view.instance == g["id"]))
    return tracker, labels, view.instance, best


def misplaced(tracker, truth, along_m):
    """A tracked person ``along_m`` metres beyond the truth along the camera's line of sight, with
    the true height; and the truth's floor point."""
    cam = tracker.scene.cameras["cam"]
    xy = np.array([truth["x"], truth["y"]])
    ray = (xy - cam.centre[:2]) / np.hypot(*(xy - cam.centre[:2]))
    start = xy + along_m * ray
    return tracker.fresh().position_map.add(float(start[0]), float(start[1]), truth["height"], 0.45,
                                            mode="tracking", time=0.0), xy


def anchored_shift(tracker, labels, truth, before, after) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Anchor the same person, put 0.6 m beyond the truth along the line of sight, to the feet
    with the ``FeetConfig`` ``before`` and then ``after`` (each must move them): the shift of the
    placed floor point from one to the other (2,) m, the line of sight's floor direction (2,) and
    the truth's floor point (2,) m."""
    from worldtrack.trackers.ellipsoid.config import HeightConfig
    from worldtrack.trackers.ellipsoid.feet import anchor_to_feet

    placed = []
    for config in (before, after):
        p, xy = misplaced(tracker, truth, 0.6)
        assert anchor_to_feet([p], tracker.views, {"cam": labels}, tracker.walkable, config, HeightConfig()) == 1
        placed.append(np.array([p.x, p.y]))
    cam = tracker.scene.cameras["cam"]
    ray = (xy - cam.centre[:2]) / np.hypot(*(xy - cam.centre[:2]))
    return placed[1] - placed[0], ray, xy
