"""Ellipsoid analysis-by-synthesis tracking (paper 000: Kato, Nakazawa & Inokuchi, 1999).

Each person is an ellipsoid standing on the floor. For every person in turn, 9 candidate places
(−s, 0, +s along the floor-projected viewing direction and its perpendicular) are drawn into the
joint simulated image of everybody, compared with the ternary foreground image by
``E = Σ sim·real / Σ |sim|`` (eq. 5), and the best is kept; K rounds a frame.

Where each step of the paper is:

==========================================  ==================================================
paper 000                                   module
==========================================  ==================================================
the ellipse of an ellipsoid (appendix)      :mod:`.forms` (``ellipse_forms``)
ternary real image, the −1 ring (§4)        :mod:`.real` (``ternary_real``)
eq. 5, E = Σ sim·real / Σ|sim| (§4)         :mod:`.score` (``score_candidates``), :mod:`.pixels`
several people in one image (§5)            :mod:`.joint` (``JointImage``)
9 candidates × K rounds (§5)                :mod:`.match` (``run_rounds``, ``rounds_python``)
capture mode, E > 0.7 (§5.2)                :mod:`.life` (``LifeCycle``, ``EVIDENCE``)
unmeasurable: head and feet hidden (Tab. 2)  :mod:`.support` (``flag_unmeasurable``)
s = 50 mm, K = 3, 5 px ring (§6)            :mod:`.config` (``EllipsoidConfig.paper``)
==========================================  ==================================================

and worldtrack's additions: births from unexplained foreground (:mod:`.births`), searches along
lines of sight (:mod:`.search`; for a place one camera cannot see, :mod:`.cross_view`), support of
each track (:mod:`.support`), measured heights (:mod:`.height`), depth from the feet or the top of the head (:mod:`.feet`), the warm start
(:mod:`.warm_start`), the per-camera state (:mod:`.cameras`), the
kernels' typed arguments (:mod:`.args`), and the tracker that runs the steps in order
(:mod:`.tracker`).

Example
-------
>>> import numpy as np
>>> from worldtrack.trackers.ellipsoid import EllipsoidTracker
>>> from worldtrack.foreground.background import StaticBackground
>>> from worldtrack.geometry import quadric
>>> from worldtrack.scene import scene_from_dict
>>> scene = scene_from_dict({"cameras": [{"id": "cam", "image_size": [160, 120], "position": [-1.0, -1.74, 2.64],
...                          "look_at": [-1.0, 0.9, 0.68], "hfov_deg": 60}],
...                          "floor": {"walkable": [{"outer": [[-4, -1.5], [2, -1.5], [2, 5], [-4, 5]]}]}})
>>> cam = scene.cameras["cam"]
>>> background = np.full((120, 160, 3), 110, np.uint8)
>>> frame = background.copy()
>>> centre, radii = quadric.person_ellipsoid([[-1.0, 1.2]], 1.65, 0.4)
>>> frame[quadric.ellipse_mask(quadric.ellipsoid_conics(cam.P, centre, radii)[0], (120, 160))] = 30
>>> ellipsoids = EllipsoidTracker(scene, {"cam": StaticBackground(background)})
>>> tracks = [ellipsoids.step({"cam": frame}, i / 10) for i in range(3)][-1]
>>> [(t.id, round(t.x, 1), round(t.y, 1)) for t in tracks]
[(1, -1.0, 1.2)]
"""

from __future__ import annotations

from typing import Any

from worldtrack.trackers.ellipsoid.config import EllipsoidConfig

__all__ = ["EllipsoidConfig", "EllipsoidTracker"]


def __getattr__(name: str) -> Any:
    # The tracker compiles kernels: imported when first asked for, so that reading the config
    # (the command line's --help, --print-config) stays light.
    if name == "EllipsoidTracker":
        from worldtrack.trackers.ellipsoid.tracker import EllipsoidTracker
        return EllipsoidTracker
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
