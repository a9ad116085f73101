"""One person, or two on one line of sight? Render both and keep the one the image agrees with.

From one camera, a short person with somebody farther away behind them makes one silhouette whose
top is the *farther* person's head. Read as one person it gives a height that is wrong but
plausible (2.05 m for 1.69 m), the tall ellipse then explains the farther head, and that person
is never born (issue 37). Paper 000 decides such questions by analysis by synthesis: draw each
explanation into the simulated image and score it against the real one with eq. 5.

:func:`compare_on_ray` does that for one tracked person ``k``, everybody drawn as a body and a head
(:mod:`.head_body`: the tracker's single ellipse is wider than a head at the top, so a short
ellipse plus anything small on top would beat it on a lone tall person):

- **one**: the person alone, at their height or shorter, as wide as drawn or narrower: the best E;
- **two**: the same, plus a second person whose head top is the top of the silhouette
  (:meth:`RaySplitter.candidates`: on that pixel's ray, 1.2–4 m farther, 1.45–1.95 m tall).

Both are scored on one sampled window, only on its rows above ``band_m`` under the person's top:
there the heads' sizes tell one from two, below it the body's shape (which no ellipsoid matches)
would decide. "Two" has more freedom, so it must win by ``margin``. A person behind a nearer one
predicts no pixels where the nearer one stands, so a mostly hidden second person is not evidence
against "two" (absence of evidence is not evidence of absence).

:class:`RaySplitter` runs it every frame on the confirmed people no tracked person covers and, when
"two" wins ``held`` frames in a row at about the same place, gives the person the shorter height
and puts the second person on the map, confirmed and flagged :data:`BEHIND` (a person put behind
another is not that person's young duplicate; see :mod:`.life`). Opt-in (``split.enabled``):
measured, it loses on the line-of-sight scenario (issue 37; figures in ``config.py``'s
description and the issue's notes).

>>> from worldtrack.trackers.ellipsoid.config import SplitConfig
>>> SplitConfig().enabled, SplitConfig().margin, SplitConfig().band_m
(False, 0.05, 0.25)
"""

from __future__ import annotations

from collections import deque
from typing import Callable, Mapping, NamedTuple, Sequence

import numpy as np

from worldtrack.trackers.base import Person, PositionMap
from worldtrack.trackers.ellipsoid.cameras import CameraView
from worldtrack.trackers.ellipsoid.encounters import covered_in_some_view
from worldtrack.trackers.ellipsoid.forms import ellipse_crop, owner_crop
from worldtrack.trackers.ellipsoid.head_body import parts_box, person_masks, sample_window, window_score
from worldtrack.trackers.ellipsoid.joint import JointImage
from worldtrack.trackers.ellipsoid.two_on_ray import silhouette_ratio

#: Pixels of the window both hypotheses are scored on (sampled on a stride).
WINDOW_PIXELS = 3000
#: Heights tried above the one whose head top is the silhouette's top pixel, m.
TOP_SLACK_M = (0.0, 0.03, 0.06)
#: Tests kept in :attr:`RaySplitter.log`.
LOG_TESTS = 10000
#: Widths tried for the first person, as shares of the width the tracker draws them with.
NEAR_WIDTHS = (0.6, 0.8, 1.0)
#: Flag of a person put on the map by the two-hypothesis test (not a young duplicate; :mod:`.life`).
BEHIND = "behind"


class Verdict(NamedTuple):
    """The two explanations of one person's silhouette, and the best of each.

    Attributes
    ----------
    e_one, e_two : float — best E of "one person" and of "two on the ray" (−inf: none drawn)
    near_height : float — the person's height in the best "two", m
    far_xy : (2,) — the second person's floor place in the best "two", m
    far_height : float — their height, m
    """

    e_one: float
    e_two: float
    near_height: float
    far_xy: np.ndarray
    far_height: float

    @property
    def gain(self) -> float:
        """E of "two" minus E of "one"."""
        return self.e_two - self.e_one


def compare_on_ray(joint: JointImage, k: int, near_heights: Sequence[float], far_people: np.ndarray,
                   band_m: float = 0.0) -> Verdict:
    """Score "person ``k`` alone" against "person ``k`` and one of ``far_people``", everybody
    drawn as a body and a head (:mod:`.head_body`), everybody else where ``joint`` has them.

    Parameters
    ----------
    joint : JointImage — everybody this frame (person ``k`` at their current place)
    k : int — the person
    near_heights : heights to try for person ``k``, m
    far_people : (J, 3) — places (x, y) and heights of the second person to try, m
    band_m : score only the window's rows above the point this far below the tallest first person's
        top, m (0: the whole window)

    Returns
    -------
    Verdict — E summed over the cameras that draw person ``k`` (Σ num / Σ den), each on one sampled
    window holding every hypothesis
    """
    # The first person's shape: each height, as wide as the tracker draws them or narrower (seen
    # from the side a body is ~0.25 m deep, not 0.4 m wide: else a second person "fits" a narrow top).
    w = float(joint.people.widths[k])
    shapes = [(h, f * w) for h in near_heights for f in NEAR_WIDTHS]
    hs_near = np.array([h for h, _ in shapes])
    far = [(f[:2], float(f[2])) for f in np.asarray(far_people, float).reshape(-1, 3)]
    n1, n2 = np.zeros(len(hs_near)), np.zeros((len(hs_near), len(far)))
    d1, d2 = np.zeros_like(n1), np.zeros_like(n2)
    xy_k = joint.xy[k]
    draw = joint.settings.draw
    for cid in joint.cids:
        cam = joint.views[cid].args
        box = _window(cam, [(xy_k, hs_near.max(), w)] + [(xy, h, w) for xy, h in far], draw)
        if box is None:
            continue
        if band_m > 0:  # only the top of the silhouette: heads, not the body's shape, tell one from two
            bottom = joint.views[cid].camera.project(np.array([[xy_k[0], xy_k[1], hs_near.max() - band_m]]))[0, 1]
            box = (box[0], box[1], box[2], int(min(box[3], max(box[2] + 1, np.ceil(bottom)))))
        win = sample_window(cam, joint.real[cid], box, WINDOW_PIXELS)
        o_in, o_ring = np.zeros(len(win.u), bool), np.zeros(len(win.u), bool)
        for i in range(len(joint.xy)):
            if i != k:
                a, b = person_masks(cam, win, joint.xy[i], joint.people.heights[i], joint.people.widths[i], draw)
                o_in, o_ring = o_in | a, o_ring | b
        far_masks = [person_masks(cam, win, xy, h, w, draw) for xy, h in far]
        for i, (h, wn) in enumerate(shapes):
            a, b = person_masks(cam, win, xy_k, h, wn, draw)
            a, b = a | o_in, b | o_ring
            num, den = window_score(win.real, a, b)
            n1[i] += num
            d1[i] += den
            for j, (fa, fb) in enumerate(far_masks):
                num, den = window_score(win.real, a | fa, b | fb)
                n2[i, j] += num
                d2[i, j] += den
    with np.errstate(invalid="ignore", divide="ignore"):
        e1 = np.where(d1 > 0, n1 / np.maximum(d1, 1e-12), -np.inf)
        e2 = np.where(d2 > 0, n2 / np.maximum(d2, 1e-12), -np.inf)
    if not far or not np.isfinite(e2).any():
        return Verdict(float(e1.max()), -np.inf, float(hs_near[0]), xy_k.copy(), float("nan"))
    i, j = np.unravel_index(int(np.argmax(e2)), e2.shape)
    return Verdict(float(e1.max()), float(e2[i, j]), float(hs_near[i]), far[j][0].copy(), float(far[j][1]))


def _window(cam, people: list, draw) -> tuple[int, int, int, int] | None:
    """Union of the body-and-head boxes of ``people`` [(xy, height, width)], inside the image."""
    boxes = [b for b in (parts_box(cam, xy, h, w, draw) for xy, h, w in people) if b is not None]
    if not boxes:
        return None
    b = np.array(boxes)
    u0, u1 = max(int(b[:, 0].min()), 0), min(int(b[:, 1].max()), cam.width)
    v0, v1 = max(int(b[:, 2].min()), 0), min(int(b[:, 3].max()), cam.height)
    return (u0, u1, v0, v1) if u0 < u1 and v0 < v1 else None


def head_ratio(view: CameraView, labels: np.ndarray, people: tuple[np.ndarray, np.ndarray, np.ndarray], k: int,
               tallest_m: float) -> tuple[float, np.ndarray | None]:
    """:func:`~.two_on_ray.silhouette_ratio` of person ``k`` of ``people`` (xy (N, 2), heights, widths),
    read as a height is (:mod:`.height`): in the ellipse of the tallest plausible person with its ring, on
    the pixels nobody else's ellipse covers: ~1 for one person, below when the top is somebody farther;
    nan when not measurable. Also the silhouette's top pixel (2,) (None when not measurable)."""
    xy, hs, ws = people
    _, ring, box, valid, _ = view.forms(xy, np.full(len(xy), tallest_m), 1.25 * ws)
    b = box[k]
    if not valid[k] or b[0] >= b[1] or b[2] >= b[3]:
        return float("nan"), None
    down = view.down_direction(np.array([(b[0] + b[1]) / 2, (b[2] + b[3]) / 2]))
    if down is None:
        return float("nan"), None
    grid, dist = view.grid, view.camera.has_distortion
    owner = owner_crop(b, view.forms(xy, hs, ws), grid, dist)
    region = ellipse_crop(ring[k], b, grid, dist) & ((owner == k) | (owner == -1))
    ratio, top, _ = silhouette_ratio(view, labels, region, tuple(int(x) for x in b), down)
    return ratio, top


class RaySplitter:
    """Each frame, ask of every confirmed person whether they are two on one line of sight.

    Parameters
    ----------
    config : SplitConfig (``ellipsoid.split``)
    min_separation_m : a second person is never put this close to anybody else, m
    walkable : callable — (M, 2) floor points → (M,) bool
    width_m : the second person's width, m
    height_range_m : (min, max) plausible heights, m (``ellipsoid.height.range_m``)
    """

    def __init__(self, config, min_separation_m: float, walkable: Callable[[np.ndarray], np.ndarray],
                 width_m: float, height_range_m: tuple[float, float]):
        self.config = config
        self.height_range_m = height_range_m
        self.min_separation_m = min_separation_m
        self.walkable = walkable
        self.width_m = width_m
        #: Person id → (frames in a row "two" won, the second person's place at the last win).
        self.wins: dict[int, tuple[int, np.ndarray]] = {}
        #: The last ``LOG_TESTS`` tests made: (time, person id, their place (2,), Verdict), for benchmarks
        #: and pictures (bounded: a long video must not grow it).
        self.log: deque[tuple[float, int, np.ndarray, Verdict]] = deque(maxlen=LOG_TESTS)
        #: The tests that put a second person on the map (same rows).
        self.splits: list[tuple[float, int, np.ndarray, Verdict]] = []

    def candidates(self, joint: JointImage, labels: Mapping[str, np.ndarray], k: int) -> np.ndarray:
        """(J, 3) second people (x, y, height) whose head top is the top of person ``k``'s silhouette
        in the first camera that shows it: on that pixel's ray, ``behind_m`` farther than ``k``, of a
        plausible height, walkable and clear of everybody (but ``k``) by ``min_separation_m``; none
        when the head on top is not too small for ``k`` (``head_ratio``)."""
        cfg = self.config
        people = (joint.xy, joint.people.heights, joint.people.widths)
        lo, hi = cfg.far_min_m, cfg.far_max_m
        for cid in (c for c in joint.cids if c in labels):
            ratio, top = head_ratio(joint.views[cid], labels[cid], people, k, self.height_range_m[1])
            if top is None or not (cfg.head_ratio <= 0 or ratio < cfg.head_ratio):
                continue
            cam = joint.views[cid].camera
            heights = np.arange(lo, hi + 1e-9, cfg.step_m)
            xy = np.array([cam.backproject(top[None], h)[0][:2] for h in heights])
            behind = np.hypot(*(xy - cam.centre[:2]).T) - np.hypot(*(joint.xy[k] - cam.centre[:2]))
            ok = np.isfinite(xy).all(axis=1) & (behind >= cfg.behind_min_m) & (behind <= cfg.behind_max_m)
            ok[ok] &= self.walkable(xy[ok])
            for i in range(len(joint.xy)):
                if i != k:  # somebody there already (perhaps misplaced along the ray): not a second person
                    ok &= np.hypot(*(xy - joint.xy[i]).T) >= max(cfg.clear_m, self.min_separation_m)
            # The top found is the mean of the highest pixels, a little below the head's top: try taller too.
            found = np.column_stack([xy, heights])[ok]
            return np.vstack([found + [0.0, 0.0, dh] for dh in TOP_SLACK_M])
        return np.zeros((0, 3))

    def split(self, joint: JointImage, labels: Mapping[str, np.ndarray], people: Sequence[Person],
              position_map: PositionMap, t: float, confirm: Callable[[Person], None]) -> list[Person]:
        """Test the confirmed people of ``joint`` (drawn in the order of ``people``; ``labels`` the
        cameras' foreground labels); returns the second people put on the map (confirmed through
        ``confirm``) this frame."""
        cfg = self.config
        lo = self.height_range_m[0]
        # Only people no tracked one covers much (as for heights): with a known person in front, the
        # silhouette's top and shape belong to several people already drawn.
        covered = covered_in_some_view(people, joint.views, self.height_range_m[1])
        born = []
        for k, p in enumerate(people):
            far = self.candidates(joint, labels, k) if p.confirmed and p.mode == "tracking" \
                and BEHIND not in p.flags and not covered[k] else np.zeros((0, 3))
            if not len(far):
                self.wins.pop(p.id, None)
                continue
            near = [p.height] + [h for h in np.arange(p.height - cfg.shorter_step_m, lo - 1e-9, -cfg.shorter_step_m)]
            v = compare_on_ray(joint, k, near, far, cfg.band_m)
            self.log.append((t, p.id, joint.xy[k].copy(), v))
            if not (v.gain > cfg.margin and v.near_height < p.height):
                self.wins.pop(p.id, None)
                continue
            n, last = self.wins.get(p.id, (0, v.far_xy))
            n = n + 1 if np.hypot(*(v.far_xy - last)) < cfg.same_place_m else 1
            self.wins[p.id] = (n, v.far_xy)
            if n < cfg.held:
                continue
            self.wins.pop(p.id, None)
            p.height = v.near_height
            p.height_samples.clear()
            q = position_map.add(float(v.far_xy[0]), float(v.far_xy[1]), v.far_height, self.width_m,
                                 mode="capture", time=t, tentative=True)
            q.flags.add(BEHIND)
            q.height_samples.append(v.far_height)
            confirm(q)
            born.append(q)
            self.splits.append(self.log[-1])
        return born


__all__ = ["BEHIND", "RaySplitter", "Verdict", "compare_on_ray", "head_ratio"]
