"""A person's height measurements stay with their id when a lost track is given back.

A confirmed track that ends (behind a post, in a group) and is confirmed again moments later
gets its id back (:mod:`.reentry`, :mod:`.identity`), but as a new
:class:`~worldtrack.trackers.base.Person`: the height measured before is gone and is measured
again from scratch, from whatever the next views show. On PETS 2009 person 1 (1.64 m) was
measured 1.57–1.64 m walking away from the camera; their track ended behind the lamp post, the
id came back, and the new samples — taken beside the flapping barrier tape, which joins the top
of their head — made them 1.82 m, 0.2 m too near along the line of sight for the rest of the
video (issue 37).

With ``ellipsoid.height.keep_with_id`` the tracker remembers each confirmed id's samples and a
person given an id back starts from them: the new samples join the old ones and the median of the
last ``height.samples`` is the height, as for a person never lost. When the id went to somebody
else (a wrong return), their own samples outvote the old ones as they come in.

>>> from worldtrack.trackers.base import Person
>>> from worldtrack.trackers.ellipsoid.config import HeightConfig
>>> kept = KeptHeights(HeightConfig(samples=5))
>>> before = Person(id=3, x=0.0, y=0.0, height=1.56, height_samples=[1.56, 1.57, 1.55, 1.57])
>>> kept.remember([before])
>>> back = Person(id=3, x=1.0, y=0.0, height_samples=[1.95, 1.93])   # just given id 3 back
>>> kept.give_back(back, default_height=1.65)
>>> back.height_samples, back.height
([1.57, 1.55, 1.57, 1.95, 1.93], 1.57)
"""

from __future__ import annotations

from typing import Iterable

from worldtrack.trackers.base import Person
from worldtrack.trackers.ellipsoid.config import HeightConfig
from worldtrack.trackers.ellipsoid.height_sigma import height_estimate
from worldtrack.trackers.ellipsoid.height_views import add_samples


class KeptHeights:
    """Each confirmed id's height samples (m), kept after its track ends.

    Parameters
    ----------
    config : HeightConfig — ``samples`` (how many are kept) and the estimate's settings
    """

    def __init__(self, config: HeightConfig) -> None:
        self.config = config
        self._by_id: dict[int, tuple[list[float], list[float]]] = {}

    def remember(self, people: Iterable[Person]) -> None:
        """After a step: note the samples of every confirmed person (positive id) on the map."""
        for p in people:
            if p.id > 0 and p.height_samples:
                self._by_id[p.id] = (p.height_samples, p.height_px)

    def give_back(self, p: Person, default_height: float) -> None:
        """``p`` was just given a known id: the samples kept for it come first, ``p``'s own after
        them; the last ``samples`` are kept and ``p.height`` is their estimate
        (:func:`.height_sigma.height_estimate` against ``default_height``, m)."""
        old, old_px = self._by_id.get(p.id, ([], []))
        if not old or old is p.height_samples:
            return
        px = [*_sizes(old, old_px), *_sizes(p.height_samples, p.height_px)]
        samples = list(old) + list(p.height_samples)
        p.height_samples, p.height_px = [], []
        # As if measured in that order: the oldest go first when there are more than ``samples``
        # (or, with ``prefer_large``, those from the smallest views, :mod:`.height_views`); measuring
        # stops once that many are in (:func:`.height.heights_due`), so the returning person's height
        # is the one measured before, plus what was measured since.
        add_samples(p, list(zip(samples, px)), self.config)
        if len(p.height_samples) >= 3:
            p.height = height_estimate(p.height_samples, default_height, self.config)


def _sizes(samples: list[float], px: list[float]) -> list[float]:
    """The view sizes of ``samples``: ``px``, or 0 (unknown) for each when the lists disagree."""
    return list(px) if len(px) == len(samples) else [0.0] * len(samples)


__all__ = ["KeptHeights"]
