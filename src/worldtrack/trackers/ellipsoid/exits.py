"""Did a lost person walk out of the cameras' view? Then no id is given back by place alone.

The *lost* state (:mod:`.reentry`) gives a track's id back to a newcomer who stands where the lost
person could have walked to: right for a person who comes out from behind a pole or another person.
At the image's edge it is wrong more often than right: whoever enters there a moment after somebody
left is as likely a stranger (PETS 2009, issue 37: a man leaving the view at its lower left and
another entering 2.9 m away 2.6 s later shared one id for 195 frames). A track whose last place,
where the evidence last held it, is cut by the image border in every camera (less than
``lost.border_share`` of the person's ellipse inside any image) is filed as *left the view*; its id
can come back only by colour (:mod:`.identity`, which asks for a close colour match and a margin).

On by default (``lost.border_share`` = 0.9; 0 turns it off). Measured at 0.9 (issue 37, one session): PETS 2009 S2.L1 start
frames 0–2, IDF1 0.796 → 0.828, against the whole-view ids 0.906 → 0.949, switches 2.3 → 1.0, MOTA
0.927 → 0.926, mean error 0.251 → 0.251 m (start frames 0–7: IDF1 0.811 → 0.830, error 0.253 →
0.255 m); no decision changed on crowd 10's held-out seeds 140–199, the one-camera line-of-sight
seeds 100–109 or ``paper_kato``.

>>> from worldtrack.scene import scene_from_dict
>>> from worldtrack.trackers.ellipsoid.args import DrawArgs
>>> from worldtrack.trackers.ellipsoid.cameras import camera_view
>>> scene = scene_from_dict({"cameras": [{"id": "c", "image_size": [160, 120], "position": [0.0, 0, 3],
...                                       "look_at": [0.0, 5, 0], "hfov_deg": 60}],
...                         "floor": {"walkable": [{"outer": [[-5, 0], [5, 0], [5, 9], [-5, 9]]}]}})
>>> view = camera_view(scene, "c", None, 5.0, DrawArgs(0.1, 0.0))
>>> in_image_share(view, np.array([0.0, 5.0]), 1.75, 0.5) > 0.95        # in the middle of the image
True
>>> round(in_image_share(view, np.array([3.0, 5.0]), 1.75, 0.5), 2)      # a third past the right edge
0.64
"""

from __future__ import annotations

from typing import Iterable

import numpy as np

from worldtrack.trackers.ellipsoid.cameras import CameraView
from worldtrack.trackers.ellipsoid.forms import ellipse_crop


def in_image_share(view: CameraView, xy: np.ndarray, height: float, width: float) -> float:
    """Share of a person's ellipse at ``xy`` (2,) m that falls inside ``view``'s image (obstacles
    do not count: a person behind a pole is still in view); 0 behind the camera."""
    inner, _, box, valid, _ = view.forms(np.asarray(xy, float)[None], np.array([height]), np.array([width]))
    det = inner[0, 2] * inner[0, 4] - inner[0, 3] ** 2
    u0, u1, v0, v1 = box[0]
    if not valid[0] or det <= 0 or u0 >= u1 or v0 >= v1:
        return 0.0
    area = np.pi / np.sqrt(det)
    inside = ellipse_crop(inner[0], box[0], view.grid, view.args.has_dist).sum()
    return float(min(inside / area, 1.0))


def left_the_view(views: Iterable[CameraView], xy: np.ndarray, height: float, width: float, share: float) -> bool:
    """Whether a person at ``xy`` (2,) m is cut by the image border in every camera of ``views``:
    less than ``share`` of their ellipse inside any image."""
    return all(in_image_share(v, xy, height, width) < share for v in views)


__all__ = ["in_image_share", "left_the_view"]
