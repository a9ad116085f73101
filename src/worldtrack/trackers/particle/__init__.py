"""The particle tracker (seed 004): one 3-D particle filter per object, the height-column likelihood.

Where each step of the paper is:

===============================  ============================================================
step                              module
===============================  ============================================================
prediction, eqs. 1–2              :mod:`.motion` (velocity models by name, the heights' walk)
height column, eqs. 11–12         :mod:`.likelihood.column` (the kernel and its reference)
point likelihood, eq. 7           :mod:`.likelihood.point`
top edge (worldtrack's)           :mod:`.likelihood.top_edge`
the likelihoods by name           :mod:`.likelihood.models` (column-ratio, column-count, point)
per-frame images, owners,         :mod:`.likelihood.labels`, :mod:`.likelihood.images`,
occluders                         :mod:`worldtrack.foreground.shadows` (cast shadows)
the camera wrapper, boxes         :mod:`.likelihood.camera`, :mod:`.likelihood.boxes`
weights and resampling, eq. 8     :mod:`.resample`
object region, eqs. 9–10          :mod:`.region`
detection filters, §3.2           :mod:`.detection`, :mod:`.floor`
a filter's end (β), exits         :mod:`.life`
split and merge (§6's problem)    :mod:`.split`, :mod:`.merge`
explaining away                   :mod:`.explain`, :mod:`.observe`
appearance                        :mod:`.appearance`, :mod:`.colour`
configuration                     :mod:`.config`
the tracker                       :mod:`.tracker`, its working representation :mod:`.cloud`
===============================  ============================================================

Example
-------
>>> import numpy as np
>>> from worldtrack.foreground.background import StaticBackground
>>> from worldtrack.scene import scene_from_dict
>>> scene = scene_from_dict({"name": "room", "floor": {"walkable": [{"outer": [[-2, 0.5], [2, 0.5], [2, 5], [-2, 5]]}]},
...     "cameras": [{"id": "cam", "image_size": [160, 120], "position": [0, -1, 3], "look_at": [0, 3, 0.5],
...                  "hfov_deg": 70}]})
>>> empty = np.full((120, 160, 3), 90, np.uint8)
>>> tracker = ParticleTracker(scene, {"cam": StaticBackground(empty, 30.0, "colour")},
...                           ParticleConfig().replace(seed=1))
>>> tracker.step({"cam": empty}, 0.0)          # nobody there
[]
>>> tracker.init_track(0.5, 3.0).id             # or put a person on the map by hand
1
"""

from worldtrack.trackers.particle.config import ParticleConfig
from worldtrack.trackers.particle.likelihood.boxes import image_box, image_boxes
from worldtrack.trackers.particle.tracker import ParticleTracker

__all__ = ["ParticleConfig", "ParticleTracker", "image_box", "image_boxes"]
