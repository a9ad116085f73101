"""Life-cycle rules every tracker shares: durations in seconds, confirming, ending, duplicates.

Rules are stated in seconds and applied per frame: :func:`frames_for` turns a duration into the
number of frames it spans at the current frame interval, so a tracker behaves the same at 7 and at
25 frames/s. Counters live on the :class:`~worldtrack.trackers.base.Person` (``tick``/``reset``),
so trackers that share a map advance them once per time stamp.
"""

from __future__ import annotations

import math
from typing import Callable, Mapping

from worldtrack.trackers.base import Person, PositionMap

#: A rule's frame count when the frame interval is not known yet (the first frame): never met.
NEVER = 2 ** 31 - 1


def frames_for(seconds: float, dt: float) -> int:
    """Frames (at least 1) a rule must hold for to last ``seconds`` at frame interval ``dt`` (s).

    At least the duration: ``⌈seconds / dt⌉`` (with a millionth of a frame of slack for time stamps
    that do not divide exactly), so 0.2 s is two frames at 10 frames/s and also at 7 frames/s,
    where one frame would last only 0.14 s. ``dt ≤ 0`` (the first frame: no interval known yet)
    gives :data:`NEVER`.

    >>> frames_for(0.3, 0.1), frames_for(0.2, 1 / 7), frames_for(1.0, 1 / 7), frames_for(0.05, 0.1)
    (3, 2, 7, 1)
    >>> frames_for(0.3, 0.3 / 2.9999999999999996), frames_for(1.0, 0.0) == NEVER
    (3, True)
    """
    if not dt > 0:
        return NEVER
    return max(1, int(math.ceil(seconds / dt - 1e-6)))


def counts_for(p: Person, name: str, t: float, condition: bool, by: int = 1) -> int:
    """Frames in a row (weighted by ``by``) that ``condition`` has held for person ``p``: counter
    ``name`` advanced (``condition``) or reset (not) at time ``t``; returns the counter."""
    if condition:
        return p.tick(name, t, by)
    p.reset(name, t)
    return 0


def younger(a: Person, b: Person) -> Person:
    """The younger of two people (born later; the larger id on a tie): the one a duplicate rule ends."""
    return b if (b.born, b.id) > (a.born, a.id) else a


def merge_duplicates(position_map: PositionMap, close: Mapping[tuple[int, int], int],
                     end: Callable[[Person], None], t: float | None = None) -> None:
    """End the younger of each pair of people that has been close for its number of frames.

    Parameters
    ----------
    position_map : PositionMap — holds each pair's frames in a row (``close_pairs``); pairs not in
        ``close`` this frame start again from 0
    close : {(id_a, id_b): frames} — the pairs close this frame (``id_a < id_b``), each with the
        frames in a row it must last (e.g. longer for a pair one behind the other)
    end : callable — ends a person (the tracker's own clean-up)
    t : float, optional — the time stamp (s). Given, a pair advances once per time stamp however
        many trackers sharing the map call this at ``t`` (the last call's pairs count); without it,
        once per call.

    A pair whose elder has just been ended (a chain of three) is left alone: it duplicates nobody.
    """
    if t is None or position_map.close_time != t:
        position_map.close_before, position_map.close_time = dict(position_map.close_pairs), t
    before = position_map.close_pairs if t is None else position_map.close_before
    counts = {pair: before.get(pair, 0) + 1 for pair in close}
    position_map.close_pairs = counts
    for (ia, ib), need in close.items():
        if counts.get((ia, ib), 0) >= need and ia in position_map and ib in position_map:
            end(younger(position_map[ia], position_map[ib]))
            counts.pop((ia, ib), None)


__all__ = ["NEVER", "counts_for", "frames_for", "merge_duplicates", "younger"]
