"""A tracker that has just read one frame of one person in the lab's two cameras (shared by the
search and births tests; imported as ``_ellipsoid_seen``)."""

from __future__ import annotations

import numpy as np
from _ellipsoid_scenes import ellipsoid_frames, noise_backgrounds, two_camera_scene

from worldtrack.geometry import quadric as q
from worldtrack.foreground import make_foregrounds
from worldtrack.trackers.ellipsoid import EllipsoidConfig, EllipsoidTracker
from worldtrack.trackers.ellipsoid.real import ternary_real


def one_person_seen(seed: int) -> tuple:
    """The lab's two cameras (320x240, noise backgrounds) and a default tracker that has just read
    one frame of a 1.65 x 0.4 m ellipsoid standing at (-1.0, 1.2): ``scene, person, backgrounds,
    tracker`` (foreground labels and masks set), the images and the ternary real images, per camera."""
    scene = two_camera_scene((320, 240))
    rng = np.random.default_rng(seed)
    bgs = noise_backgrounds(scene, rng)
    person = np.array([-1.0, 1.2])
    cen, rad = q.person_ellipsoid([person], 1.65, 0.4)
    tracker = EllipsoidTracker(scene, make_foregrounds(scene, bgs, "colour"), EllipsoidConfig())
    real, images = {}, {}
    for cid, frame in ellipsoid_frames(scene, bgs, cen, rad, rng, 0).items():
        images[cid] = frame.image
        labels = tracker.views[cid].foreground.labels(images[cid])
        tracker.last_labels[cid], tracker.last_masks[cid] = labels, (labels == 1).astype(np.uint8)
        real[cid] = ternary_real(labels, tracker.views[cid].ring_px)
    return scene, person, bgs, tracker, images, real
