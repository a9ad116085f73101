"""Which height measurements a person keeps: the last ones, or those from the largest views.

A height measured in one view is the top of the head's ray above the feet's floor point; the
silhouette's ends are found to about a pixel (blur, the shoes' shadow, hair), and a pixel is
``distance / focal length`` metres — 1 cm at 4 m in a 640-px view, 5–6 cm at 25 m in PETS 2009.
People mostly come into view far away, so the tracker's first ``height.samples`` measurements
(after which it stops measuring: :func:`.height.heights_due`) are often its worst: on PETS 2009
person 3 (1.75 m) was measured 1.86–2.10 m at 30 m and 1.72–1.88 m once nearer, but the far
samples were final (issue 37).

Each sample is kept with the size (px) of the view it came from (``Person.height_px``; ``inf``
for a triangulation of several views). By default the last ``height.samples`` are kept, as
before. With ``height.prefer_large`` the tracker keeps measuring (one frame in five) and keeps the
``height.samples`` from the largest views: a new sample replaces the one from the smallest view
when its own view is larger.

>>> from worldtrack.trackers.base import Person
>>> from worldtrack.trackers.ellipsoid.config import HeightConfig
>>> p = Person(id=1, x=0.0, y=0.0)
>>> add_samples(p, [(2.00, 40.0), (1.98, 42.0), (1.78, 90.0)], HeightConfig(samples=2, prefer_large=True))
>>> p.height_samples, p.height_px
([1.98, 1.78], [42.0, 90.0])
>>> add_samples(p, [(1.76, 95.0)], HeightConfig(samples=2, prefer_large=True))
>>> p.height_samples
[1.78, 1.76]
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from worldtrack.trackers.base import Person
from worldtrack.trackers.ellipsoid.config import HeightConfig


def add_samples(p: Person, new: Sequence[tuple[float, float]], config: HeightConfig) -> None:
    """Add the height samples ``new`` [(height m, view size px), …] to ``p``: keep the last
    ``config.samples``, or with ``config.prefer_large`` those from the largest views (the newest
    first among equally large ones). Samples whose view size is unknown (lists cleared or copied
    elsewhere) count as the smallest."""
    samples, px = p.height_samples, p.height_px
    if len(px) != len(samples):
        px[:] = [0.0] * len(samples)
    samples.extend(h for h, _ in new)
    px.extend(s for _, s in new)
    n = config.samples
    if len(samples) <= n:
        return
    if not config.prefer_large:
        del samples[:-n]
        del px[:-n]
        return
    # The n largest views; among equals the newest (a stable sort of the reversed order).
    order = np.argsort(-np.asarray(px[::-1], dtype=float), kind="stable")[:n]
    keep = np.sort(len(px) - 1 - order)
    samples[:] = [samples[i] for i in keep]
    px[:] = [px[i] for i in keep]


__all__ = ["add_samples"]
