"""A tracking filter's life: when its person is seen, when it ends (the β rule), leaving through an exit.

* The β rule (§3.2): a tracking filter ends once the share of its likely particles has stayed at or
  below β for ``tracking.end_after_s`` seconds (the paper: at once). While the share is above β the
  person is seen.
* Sharing the map: a person that another tracker's cameras saw at this or the previous time stamp is
  not ended, nor moved, by a tracker that does not see them (:func:`seen_elsewhere`): their filter
  here follows the map (the tracker seeds it afresh from the person) until its own cameras see them.
  With one tracker on the map nobody is seen elsewhere.
* Leaving through an exit (worldtrack's): a filter whose centre is in an entry region, moving at
  ≥ ``exit_speed_mps``, with its centre ``exit_lookahead_s`` ahead off the walkable floor ends at
  once — what its column reads there next is whoever stands in front of the door on the same line of
  sight — and its last box stays explained to the detection filters for ``exit_hold_s``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple, Sequence

import numpy as np

from worldtrack.scene.floor import WalkableRaster
from worldtrack.scene.model import Scene
from worldtrack.trackers.base import Person

if TYPE_CHECKING:
    from worldtrack.trackers.particle.config import ParticleConfig


def seen_elsewhere(p: Person, mine: frozenset[str]) -> bool:
    """Whether cameras other than ``mine`` (another tracker's, on a shared map) saw person ``p`` at this
    or the previous time stamp."""
    return p.prev_t is not None and p.seen_at >= p.prev_t and not set(p.seen_by) <= mine


class Verdict(NamedTuple):
    """What the β rule says of a tracking filter: whether its person goes on (``kept``), whether this
    tracker updates them (``here``: it sees them, or nobody else does), whether it sees them
    (``seen``: the share is above β)."""

    kept: bool
    here: bool
    seen: bool


#: Seen here; not seen but not for long enough to end; seen by another tracker only; ended.
SEEN, FADING, FOLLOW, END = Verdict(True, True, True), Verdict(True, True, False), Verdict(True, False, False), \
    Verdict(False, False, False)


class Exited(NamedTuple):
    """An object that left through an exit: its person (off the map) and when, seconds."""

    person: Person
    t: float


class Life:
    """The β rule and the exits of the tracking filters.

    Parameters
    ----------
    cfg : ParticleConfig — its ``tracking`` section
    scene : Scene — its entry regions
    walkable : WalkableRaster — the floor people can stand on
    """

    def __init__(self, cfg: "ParticleConfig", scene: Scene, walkable: WalkableRaster):
        self.cfg, self.scene, self.walkable = cfg.tracking, scene, walkable
        self.exited: list[Exited] = []

    def judge(self, persons: Sequence[Person], shares: Sequence[float], t: float,
              mine: frozenset[str]) -> list[Verdict]:
        """The β rule at time ``t`` (s) for ``persons`` whose filters' shares of likely particles are
        ``shares``, one :class:`Verdict` each. A person this tracker updates gets the share as their
        score."""
        beta, wait = self.cfg.beta, self.cfg.end_after_s
        out = []
        for p, share in zip(persons, shares):
            low = share <= beta
            if low and seen_elsewhere(p, mine):
                out.append(FOLLOW)
                continue
            if low:
                if p.low_since is None:
                    p.low_since = t
                if t - p.low_since >= wait:
                    out.append(END)
                    continue
            else:
                p.low_since = None
            p.score = share
            out.append(FADING if low else SEEN)
        return out

    def leaving(self, persons: Sequence[Person]) -> np.ndarray:
        """(F,) bool: whether each person is walking off the floor through an entry region: their centre
        is in one, they move at ≥ ``exit_speed_mps`` and the centre ``exit_lookahead_s`` ahead is off
        the walkable floor (nobody can be beyond the floor's edge)."""
        c = self.cfg
        if c.exit_lookahead_s <= 0 or not self.scene.entry_regions or not persons:
            return np.zeros(len(persons), dtype=bool)
        here = np.array([[p.x, p.y] for p in persons], dtype=float)
        v = np.array([[p.vx, p.vy] for p in persons], dtype=float)
        return ((np.hypot(v[:, 0], v[:, 1]) >= c.exit_speed_mps) & (self.scene.entry_region_index(here) >= 0)
                & ~self.walkable.contains(here + c.exit_lookahead_s * v))

    def exit(self, p: Person, t: float) -> None:
        """Person ``p`` left through an exit at ``t`` (s): their box stays explained for ``exit_hold_s``."""
        self.exited.append(Exited(p, t))

    def expire(self, t: float) -> None:
        """Forget the exits older than ``exit_hold_s`` at ``t`` (s)."""
        self.exited = [e for e in self.exited if t - e.t <= self.cfg.exit_hold_s]


__all__ = ["END", "FADING", "FOLLOW", "SEEN", "Exited", "Life", "Verdict", "seen_elsewhere"]
