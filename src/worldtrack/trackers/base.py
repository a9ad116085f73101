"""What every tracker shares: frames in, tracks out, the tracker protocol.

* :class:`Frame` — one camera's image (and depth or disparity) at one time: what sources yield and
  trackers read.
* :class:`Tracker` — the protocol callers use; :class:`TrackerBase` gives the defaults;
  :func:`warm_started` feeds a tracker its warm-start frames.
* The people — :class:`~worldtrack.trackers.people.Person`,
  :class:`~worldtrack.trackers.people.PositionMap` and the output record
  :class:`~worldtrack.trackers.people.Track` — live in :mod:`worldtrack.trackers.people` and are
  re-exported here.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Iterable, Iterator, Mapping, Protocol, Sequence

import numpy as np

from worldtrack.trackers.people import MODES, Person, PositionMap, Track


@dataclass
class Frame:
    """One camera's image at one time.

    Attributes
    ----------
    image : (H, W, 3) uint8 — BGR (OpenCV order)
    t : float — time stamp, seconds
    index : int — frame number from 0
    depth : (H, W) float32 or None — metres along the optical axis (RGB-D sensors)
    disparity : (H, W) float32 or None — pixels (stereo)
    meta : dict — e.g. white-balance gains
    """

    image: np.ndarray
    t: float
    index: int
    depth: np.ndarray | None = None
    disparity: np.ndarray | None = None
    meta: dict = field(default_factory=dict)


def frame_image(frame: object) -> np.ndarray:
    """The image of a :class:`Frame`, or ``frame`` itself if it is an image array already."""
    return frame.image if isinstance(frame, Frame) or hasattr(frame, "image") else frame  # type: ignore[return-value]


class Tracker(Protocol):
    """What the command line, the pipeline and the sinks use of a tracker.

    Attributes
    ----------
    position_map : PositionMap — the people, shared between trackers if given at construction
    extra_columns : tuple of str — ``tracks.csv`` columns besides the standard ones
    warm_start_frames : int — frames :meth:`warm_start` wants before the first :meth:`step` (0: none)
    """

    position_map: PositionMap
    extra_columns: tuple[str, ...]

    @property
    def warm_start_frames(self) -> int: ...

    def step(self, frames: Mapping[str, Frame], t: float) -> list[Track]:
        """Update with ``frames`` (``{camera_id: Frame}``) taken at time ``t`` (s); return the
        confirmed people's tracks."""
        ...

    def warm_start(self, frames: Sequence[tuple[float, Mapping[str, Frame]]]) -> None:
        """Look at the first frames before :meth:`step` sees them (e.g. to start on frame 0 with the
        people already in view)."""
        ...

    def init_track(self, x: float, y: float, track_id: int | None = None, t: float = 0.0) -> Track:
        """Put a person on the map by hand (``worldtrack track --init ID,X,Y``)."""
        ...

    def overlay(self, camera_id: str) -> "Overlay":
        """What an annotated video of ``camera_id`` may draw besides the tracks."""
        ...


@dataclass
class Overlay:
    """Per camera, what a tracker can show in an annotated frame besides the tracks.

    Attributes
    ----------
    mask : (H, W) uint8 or None — this frame's foreground (1) as the tracker read it
    ring_px : int or None — width (px) of the −1 ring of the ellipsoid tracker's ternary images
    """

    mask: np.ndarray | None = None
    ring_px: int | None = None


class TrackerBase:
    """Defaults of the :class:`Tracker` protocol: no warm start, no hand-placed people, the
    foreground masks of the last frame in :attr:`last_masks`."""

    extra_columns: tuple[str, ...] = ("sigma",)
    position_map: PositionMap
    last_masks: Mapping[str, np.ndarray] = MappingProxyType({})   # a tracker sets its own dict

    @property
    def warm_start_frames(self) -> int:
        return 0

    def warm_start(self, frames: Sequence[tuple[float, Mapping[str, Frame]]]) -> None:
        return None

    def init_track(self, x: float, y: float, track_id: int | None = None, t: float = 0.0) -> Track:
        from worldtrack.errors import InputError
        raise InputError(f"--init: the {type(self).__name__} starts tracks by itself")

    def overlay(self, camera_id: str) -> Overlay:
        return Overlay(mask=self.last_masks.get(camera_id))


def warm_started(tracker: Tracker, items: Iterable[tuple[int, float, Mapping[str, Frame]]]
                 ) -> Iterator[tuple[int, float, Mapping[str, Frame]]]:
    """The frames ``items`` unchanged, after the tracker's warm start on the first ones.

    A tracker that wants one (:attr:`Tracker.warm_start_frames` > 0) gets
    ``warm_start([(t, frames), ...])`` with up to that many first items before the first is
    yielded; any other tracker gets the items as they come.

    Parameters
    ----------
    tracker : Tracker
    items : iterable of ``(index, t, {camera_id: Frame})`` (e.g. a ``VideoSource``)

    Yields
    ------
    the same items, in order. An error met while reading the first items (a corrupt frame) is
    raised after the items read before it, which are warmed on and yielded first, so nothing
    readable is lost.
    """
    n = int(tracker.warm_start_frames or 0)
    it = iter(items)
    if n <= 0:
        yield from it
        return
    head: list = []
    error: BaseException | None = None
    try:
        for item in it:
            head.append(item)
            if len(head) >= n:
                break
    except BaseException as e:     # raised below, once the frames read before it are through
        error = e
    tracker.warm_start([(t, frames) for _, t, frames in head])
    yield from head
    if error is not None:
        raise error
    yield from it


__all__ = ["MODES", "Frame", "Overlay", "Person", "PositionMap", "Track", "Tracker", "TrackerBase",
           "frame_image", "warm_started"]
