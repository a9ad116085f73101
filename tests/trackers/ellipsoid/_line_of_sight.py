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
