"""The life cycle of a person: capture mode, confirmation, following, and the ways a track ends.

Paper 000 §5.2: a person found entering starts in *capture mode* (matched without the −1 ring, so
the ellipse can slide into the blob) and is tracked once E > 0.7. worldtrack adds when tracks end
— evidence gone for ``end.lost_after_s``, out of every view for ``end.leave_after_s``, a duplicate
— and, with the symmetric score, confirmation on support held for ``confirm.held_s``. How E and the
support are judged depends on the score (``ellipsoid.score.kind``): a component from
:data:`EVIDENCE`. Durations are seconds, turned into frames at the real frame interval
(:func:`~worldtrack.trackers.lifecycle.frames_for`).

All per-person state lives on the :class:`~worldtrack.trackers.base.Person` in the shared map:
counters ``held``, ``low``, ``unseen`` and ``age`` advance once per time stamp, so several trackers
on one map count each frame once, and a tracker judges only the people its cameras show or that no
camera on the map shows (see :class:`~.tracker.EllipsoidTracker`).

>>> from worldtrack.trackers.ellipsoid.config import EllipsoidConfig
>>> rule = EVIDENCE["paper"](EllipsoidConfig())
>>> m = Measures(e=0.75, visible=300.0, support=0.9, own_share=1.0, seen_share=0.8, evidence=0.9, views=1)
>>> rule.capture_ok(m), rule.failing(m, young=False, several_cameras=False)
(True, (False, 1))
"""

from __future__ import annotations

import math
from typing import Callable, NamedTuple, Protocol, Sequence

import numpy as np

from worldtrack.registry import Registry
from worldtrack.trackers.base import Person, PositionMap
from worldtrack.trackers.ellipsoid.config import EllipsoidConfig
from worldtrack.trackers.ellipsoid.ray_velocity import damped_velocity
from worldtrack.trackers.ellipsoid.support import MIN_OWN_PIXELS, Support
from worldtrack.trackers.lifecycle import counts_for, frames_for, merge_duplicates


class Measures(NamedTuple):
    """One person's evidence this frame: E, and the :class:`~.support.Support` values."""

    e: float
    visible: float
    support: float
    own_share: float
    seen_share: float
    evidence: float
    views: int


class Evidence(Protocol):
    """How a score's evidence confirms and keeps people."""

    #: Whether the capture tests are held over frames (``confirm.held_s``) or decide at once.
    counts_held: bool

    def capture_ok(self, m: Measures) -> bool:
        """A captured person passes this frame's tests."""
        ...

    def confirms_at_once(self, m: Measures) -> bool:
        """Evidence strong enough to confirm without held frames (given :meth:`capture_ok`)."""
        ...

    def failing(self, m: Measures, young: bool, several_cameras: bool) -> tuple[bool, int]:
        """Whether a tracked person's evidence fails this frame, and how many frames that counts."""
        ...

    def weak_ok(self, m: Measures) -> bool:
        """A captured person below the capture E passes this frame's tests for a long hold
        (``confirm.weak_threshold``)."""
        ...


#: :class:`Evidence` rules by score name (``ellipsoid.score.kind``).
EVIDENCE: Registry[type] = Registry("ellipsoid.score.kind")


@EVIDENCE.register("paper")
class PaperEvidence:
    """Eq. 5 alone: confirmed when E > ``confirm.capture_threshold`` (0.7), failing below
    ``end.keep_score``."""

    counts_held = False

    def __init__(self, config: EllipsoidConfig):
        self.capture_threshold = config.confirm.capture_threshold
        self.keep_score = config.end.keep_score

    def capture_ok(self, m: Measures) -> bool:
        return m.e > self.capture_threshold

    def confirms_at_once(self, m: Measures) -> bool:
        return True

    def failing(self, m: Measures, young: bool, several_cameras: bool) -> tuple[bool, int]:
        return m.e < self.keep_score, 1

    def weak_ok(self, m: Measures) -> bool:
        return False


@EVIDENCE.register("symmetric")
class SupportEvidence:
    """The symmetric score: a person is their own foreground. Confirmed after the capture tests
    (E, support, own share, seen share) hold for ``confirm.held_s`` — at once with the paper's E
    or with ``confirm.views`` cameras agreeing; failing on low support or evidence, or as a
    duplicate inside somebody else's silhouette; an empty track counts double."""

    counts_held = True

    def __init__(self, config: EllipsoidConfig):
        self.confirm = config.confirm
        self.support = config.support

    def capture_ok(self, m: Measures) -> bool:
        s = self.support
        return (m.e > self.confirm.symmetric_threshold and m.support >= s.min_support
                and not m.own_share < s.min_own_share and m.seen_share >= s.min_seen_share)

    def confirms_at_once(self, m: Measures) -> bool:
        # Strong evidence (the paper's own threshold), or a person several cameras agree on (a
        # ghost is rarely one in two views).
        views = self.confirm.views
        return m.e > self.confirm.capture_threshold or (views > 0 and m.views >= views)

    def failing(self, m: Measures, young: bool, several_cameras: bool) -> tuple[bool, int]:
        s = self.support
        low = m.support < s.min_support or m.evidence < s.min_evidence
        # A young track living inside someone else's silhouette duplicates them. So does one of any
        # age that at most one of several cameras shows: a person who walks behind somebody in one
        # view is still seen in another.
        if m.own_share < s.min_own_share and (young or (several_cameras and m.views <= 1)):
            low = True
        # Own pixels that are nearly all floor: a ghost, or a track that lost its person.
        empty = m.support < s.empty_support
        return low, (2 if empty else 1)

    def weak_ok(self, m: Measures) -> bool:
        # E held low by a body the foreground labels only in part (a shirt taken for shadow, legs
        # behind a table) while two cameras show the person's own pixels, mostly foreground.
        c, s = self.confirm, self.support
        return (c.weak_threshold > 0 and m.e > c.weak_threshold and m.views >= 2 and m.support >= c.weak_support
                and not m.own_share < s.min_own_share and m.seen_share >= s.min_seen_share)


class LifeCycle:
    """Confirms, follows and ends one tracker's people on the shared map.

    Parameters
    ----------
    config : EllipsoidConfig
    position_map : PositionMap
    several_cameras : bool — the tracker has two cameras or more
    promote : callable — gives a confirmed candidate its public id and size
    """

    def __init__(self, config: EllipsoidConfig, position_map: PositionMap, several_cameras: bool,
                 promote: Callable[[Person], None]):
        self.config = config
        self.position_map = position_map
        self.several_cameras = several_cameras
        self.promote = promote
        self.evidence: Evidence = EVIDENCE[config.score.kind](config)
        #: Whether an unseen person is kept a while longer (``crowd.coast_behind_obstacles_s``, :mod:`.coast`).
        self.coasting: Callable[[Person], bool] = lambda p: False
        #: The floor ray (2,) of the one camera that showed a person, whose velocity gain along it is
        #: ``match.velocity_along_ray`` of the rest (:mod:`.ray_velocity`); None: the same gain.
        self.velocity_ray: Callable[[Person], np.ndarray | None] = lambda p: None
        #: (A line of sight (2,), the velocity gain's share along it) from how well E places a person
        #: there (``match.velocity_sure_sigma_m``, :func:`.ray_velocity.flat_ray`); None: no damping.
        self.velocity_flat: Callable[[Person], tuple[np.ndarray, float] | None] = lambda p: None

    def end(self, p: Person) -> None:
        """Take person ``p`` off the map (if still there)."""
        if self.position_map.get(p.id) is p:
            self.position_map.remove(p.id)

    def update(self, people: Sequence[Person], scores: Sequence[tuple[float, float]], support: Support,
               n_before: int, t: float, dt: float, interval: float) -> list[Person]:
        """Judge each of ``people`` on this frame's evidence; returns those still on the map.

        ``scores[k]`` is person ``k``'s (E, denominator), ``support`` its measures; the first
        ``n_before`` people were on the map before this frame (the rest were just proposed);
        ``dt`` the time since the last frame (0 on the first), ``interval`` the frame interval (s)
        durations are counted in.
        """
        cfg = self.config
        frames = (frames_for(cfg.end.lost_after_s, interval), frames_for(cfg.end.leave_after_s, interval),
                  frames_for(cfg.confirm.held_s, interval),
                  frames_for(cfg.confirm.weak_held_s, interval) if cfg.confirm.weak_threshold > 0 else 0)
        kept = []
        for k, p in enumerate(people):
            m = Measures(scores[k][0], support.visible[k], support.support[k], support.own_share[k],
                         support.seen_share[k], support.evidence[k], int(support.views[k]))
            p.support, p.own_share, p.score = m.support, m.own_share, m.e
            p.tick("age", t)
            seen = m.visible >= MIN_OWN_PIXELS
            counts_for(p, "unseen", t, not seen)
            if seen:
                p.mark_seen(t, support.seen_by[k])
            if p.mode == "tracking" and k < n_before and dt > 0 and p.once("velocity", t):
                self._update_velocity(p, dt)
            if self._judge(p, m, t, frames):
                kept.append(p)
        return kept

    def _judge(self, p: Person, m: Measures, t: float, frames: tuple[int, ...]) -> bool:
        """Capture or follow ``p``; False when it ends. ``frames``: lost, leave, held and, optionally,
        weakly held (0 or left out: off), in frames."""
        lost_after, leave_after, held_frames, *weak = frames
        weak_frames = weak[0] if weak else 0
        if p.mode == "capture":
            if self._near_confirmed(p, self.config.births.min_separation_m):
                self.end(p)  # slid onto somebody already tracked
                return False
            ok = self.evidence.capture_ok(m)
            if self.evidence.counts_held:
                # Held on foreground for several frames: a person, not a flicker.
                held = counts_for(p, "held", t, ok)
                # Or a long hold of weaker evidence in two views (``confirm.weak_threshold``).
                weak = counts_for(p, "weak", t, ok or self.evidence.weak_ok(m)) if weak_frames > 0 else 0
                confirmed = held >= held_frames or (ok and self.evidence.confirms_at_once(m)) \
                    or (weak_frames > 0 and weak >= weak_frames)
            else:
                confirmed = ok
            if confirmed:
                self._confirm(p, t)
            elif t - p.born > self.config.confirm.within_s:
                self.end(p)
                return False
        else:
            # A person the two-hypothesis test put behind another is hidden by them, not their duplicate.
            young = t - p.born < self.config.end.young_s and "behind" not in p.flags
            low, by = self.evidence.failing(m, young, self.several_cameras)
            if counts_for(p, "low", t, low, by) >= lost_after:
                self.end(p)
                return False
        if p.count("unseen") >= leave_after and not self.coasting(p):
            self.end(p)
            return False
        return True

    def _confirm(self, p: Person, t: float) -> None:
        p.reset("held", t)
        self.promote(p)
        p.mode = "tracking"
        p.confirmed = True
        p.vx = p.vy = 0.0  # capture moves are sliding into the blob, not walking
        p.reset("low", t)

    def _update_velocity(self, p: Person, dt: float) -> None:
        """Smoothed floor velocity from the move since the last time stamp, clipped to a running
        person's speed (``match.max_speed_mps``)."""
        a = self.config.match.velocity_smoothing
        vx = (1 - a) * p.vx + a * (p.x - p.prev_x) / dt
        vy = (1 - a) * p.vy + a * (p.y - p.prev_y) / dt
        ray, share = self.velocity_ray(p), self.config.match.velocity_along_ray
        flat = self.velocity_flat(p)
        if flat is not None and (ray is None or flat[1] < share):
            ray, share = flat  # the smaller share of the two
        if ray is not None:
            moved = np.array([p.x - p.prev_x, p.y - p.prev_y]) / dt
            v = damped_velocity(np.array([p.vx, p.vy]), moved, a, share, ray)
            vx, vy = float(v[0]), float(v[1])
        speed = math.hypot(vx, vy)
        scale = min(1.0, self.config.match.max_speed_mps / speed) if speed > 0 else 1.0
        p.vx, p.vy = vx * scale, vy * scale

    def _near_confirmed(self, p: Person, distance: float) -> bool:
        return any(o is not p and o.confirmed and math.hypot(o.x - p.x, o.y - p.y) < distance
                   for o in self.position_map)

    def merge_duplicates(self, t: float, interval: float) -> None:
        """End the younger of two people closer than ``end.merge_distance_m`` for
        ``end.merge_after_s`` (every pair on the map, counted once per time stamp)."""
        people = list(self.position_map)
        need = frames_for(self.config.end.merge_after_s, interval)
        close = {}
        for i in range(len(people)):
            for j in range(i + 1, len(people)):
                a, b = people[i], people[j]
                if math.hypot(a.x - b.x, a.y - b.y) < self.config.end.merge_distance_m:
                    close[(min(a.id, b.id), max(a.id, b.id))] = need
        merge_duplicates(self.position_map, close, self.end, t)


__all__ = ["EVIDENCE", "Evidence", "LifeCycle", "Measures", "PaperEvidence", "SupportEvidence"]
