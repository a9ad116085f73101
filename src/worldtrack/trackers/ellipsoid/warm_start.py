"""Warm start: begin on the first frame with the people the first frames show.

People already in view on the first frame would otherwise be missed until confirmed in capture
mode and placed from a few crowded frames (in the 10-person crowd the first 5 frames held 1 in 4
of all misses). So the first ``warm_start.frames`` frames are tracked forwards by a fresh tracker,
then backwards (time mirrored) by another that starts from the people the first confirmed, with
their sizes and height measurements; the tracker then starts from the people the backward pass
holds on the first frame, velocities turned round. Skipped (:func:`frames_wanted` 0) for
foregrounds that learn from every frame they see (MOG2/KNN would learn the first frames three
times), for trackers with people put on the map by hand or sharing their map with other
trackers, and once a tracker has stepped.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Mapping, Sequence

if TYPE_CHECKING:
    from worldtrack.trackers.ellipsoid.tracker import EllipsoidTracker


def frames_wanted(tracker: "EllipsoidTracker") -> int:
    """Frames the tracker's warm start wants before its first step (0: none)."""
    n = tracker.config.warm_start.frames
    if n < 2 or tracker.frames_stepped > 0 or len(tracker.position_map) > 0:
        return 0
    if set(tracker.position_map.cameras) - set(tracker.views):
        return 0  # a map shared with other trackers: its people are not this tracker's to start
    if any(view.foreground.learns for view in tracker.views.values()):
        return 0  # the model would learn the first frames three times, once backwards
    return n


def warm_start(tracker: "EllipsoidTracker", frames: Sequence[tuple[float, Mapping[str, object]]]) -> None:
    """Put on ``tracker``'s map the people the first ``frames`` show, as on the first frame.

    Parameters
    ----------
    tracker : EllipsoidTracker — not yet stepped (:func:`frames_wanted` > 0)
    frames : sequence of ``(t, {camera_id: Frame or image})`` — the first frames, in order (times
        in seconds); they must then be given to ``tracker.step`` as usual, from the first
    """
    if not frames_wanted(tracker) or len(frames) < 2:
        return
    ahead = tracker.fresh()
    for t, views in frames:
        ahead.step(views, t)
    back = tracker.fresh()
    t_end = frames[-1][0]
    adopt(back, ahead, t_end)
    for t, views in reversed(frames):
        back.step(views, 2 * t_end - t)
    adopt(tracker, back, frames[0][0])


def adopt(tracker: "EllipsoidTracker", other: "EllipsoidTracker", t: float) -> None:
    """Put ``other``'s confirmed people on ``tracker``'s map as tracked, at time ``t``, walking the
    other way (a pass in mirrored time hands over): same ids, sizes, height measurements and colour models; and
    the frame interval ``other`` has seen (durations on ``tracker``'s first frame count in it)."""
    for p in other.position_map:
        if not p.confirmed:
            continue
        new = tracker.position_map.add(p.x, p.y, p.height, p.width, mode="tracking", time=t, track_id=p.id)
        new.vx, new.vy = -p.vx, -p.vy
        new.height_samples = list(p.height_samples)
        new.height_tries = p.height_tries
        if p in other.identity.models:
            tracker.identity.models[new] = dict(other.identity.models[p])
    tracker.frame_interval = other.frame_interval


__all__ = ["adopt", "frames_wanted", "warm_start"]
