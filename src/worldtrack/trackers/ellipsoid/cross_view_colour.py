"""Whether the camera that did not show a track shows *this* person at the place the search along
another camera's line of sight (:mod:`.cross_view`) would move them to.

:mod:`.cross_view` moves a track some camera B cannot see along the seeing camera A's ray to
where B shows somebody. What B shows there is *a* person, not necessarily this one: in a crowd
it is often a neighbour, and the search pulls a right track onto them (issue 37, crowd 10 dev
seed 36). This module measures B's colours at the candidate place — the foreground pixels the
person's ellipse alone would own there, everybody else where they are, the identity module's
upper- and lower-body histograms (:func:`.colours.colours_of`) — and compares them with the
person's own colour model (:mod:`.identity`): B's model if it has learnt one, else the mean of
the distances to the other cameras' models. The move is allowed only when that distance is at
most ``max_distance`` (Bhattacharyya, mean of the body parts) and no other tracked person's
model is nearer to those colours. A person without a model yet, or a place where the camera gives
too few of their pixels, is not moved — or, with ``veto_only``, moved as without the test.

>>> from worldtrack.trackers.ellipsoid.colours import HIST_BINS, Colours
>>> a = np.zeros(HIST_BINS, np.float32); a[0, 0, 0] = 1
>>> b = np.zeros(HIST_BINS, np.float32); b[1, 0, 0] = 1
>>> model_distance(Colours([a, a]), {"c1": Colours([a, a]), "c2": Colours([b, b])}, "c1")
0.0
>>> model_distance(Colours([a, a]), {"c2": Colours([b, b])}, "c1")
1.0
"""

from __future__ import annotations

from typing import Mapping, NamedTuple, Sequence

import numpy as np

from worldtrack.trackers.base import Person
from worldtrack.trackers.ellipsoid.cameras import CameraView
from worldtrack.trackers.ellipsoid.colours import Colours, colours_of, look


class _Figure(NamedTuple):
    """What :func:`.colours.look` reads of a person: an id, a floor place (m), a size (m)."""

    id: int
    x: float
    y: float
    height: float
    width: float


def model_distance(seen: Colours, model: Mapping[str, Colours], cid: str) -> float | None:
    """Colour distance of ``seen`` (measured in camera ``cid``) to a person's ``model`` (by
    camera): to ``model[cid]`` when there is one, else the mean over the other cameras' models;
    None when the model is empty."""
    if cid in model:
        return seen.distance(model[cid])
    if not model:
        return None
    return float(np.mean([seen.distance(m) for m in model.values()]))


def colours_at(view: CameraView, image: np.ndarray, labels: np.ndarray, figures: Sequence[_Figure], k: int,
               xy: np.ndarray, min_pixels: int) -> Colours | None:
    """Colours camera ``view`` shows for person ``k`` of ``figures`` moved to ``xy`` (2,) m,
    everybody else where they are; None when too few pixels are theirs alone."""
    moved = list(figures)
    moved[k] = moved[k]._replace(x=float(xy[0]), y=float(xy[1]))
    sight = look(view, moved)
    return colours_of(view, image, labels, sight, [k], min_pixels).get(k)


class ColourCheck:
    """The colour test of a cross-view move, for one frame.

    Parameters
    ----------
    people : the people the joint image holds, in its order
    models : the identity module's colour models, by person then camera
    views, images, labels : the cameras, their BGR images and foreground labels, by id
    min_pixels : a body part gives colours only with this many pixels the person owns
    max_distance : the largest colour distance of an allowed move
    veto_only : the colours only refuse: a person without a model, or a place where no camera
        gives enough of their pixels, may move (as without the test)
    """

    def __init__(self, people: Sequence[Person], models: Mapping[Person, Mapping[str, Colours]],
                 views: Mapping[str, CameraView], images: Mapping[str, np.ndarray],
                 labels: Mapping[str, np.ndarray], min_pixels: int, max_distance: float, veto_only: bool = False):
        self.people, self.models = list(people), models
        self.veto_only = veto_only
        self.views, self.images, self.labels = views, images, labels
        self.min_pixels, self.max_distance = min_pixels, max_distance
        self.refused = 0

    def __call__(self, joint, k: int, unseeing: Sequence[str], xy: np.ndarray) -> bool:
        """Whether person ``k`` of ``joint`` (a :class:`.joint.JointImage`, everybody where they
        are now) may move to ``xy`` (2,) m: some camera of ``unseeing`` shows colours there that
        are theirs (see the module)."""
        figures = [_Figure(i, float(x), float(y), float(h), float(w)) for i, ((x, y), h, w)
                   in enumerate(zip(joint.xy, joint.people.heights, joint.people.widths))]
        model = self.models.get(self.people[k]) if k < len(self.people) else None
        ok, measured = False, False
        if model:
            others = [self.models.get(p) for i, p in enumerate(self.people) if i != k]
            for cid in unseeing:
                if cid not in self.images or cid not in self.labels:
                    continue
                seen = colours_at(self.views[cid], self.images[cid], self.labels[cid], figures, k, xy,
                                  self.min_pixels)
                if seen is None:
                    continue
                measured = True
                mine = model_distance(seen, model, cid)
                theirs = [d for m in others if m for d in [model_distance(seen, m, cid)] if d is not None]
                if mine is not None and mine <= self.max_distance and all(mine < d for d in theirs):
                    ok = True
                    break
        ok = ok or (self.veto_only and not measured)
        self.refused += not ok
        return ok


__all__ = ["ColourCheck", "colours_at", "model_distance"]
