"""The map's clock: the epoch at which video files played as cameras start, and where a worker's
time goes (one row per step, for finding what makes the map late)."""

from __future__ import annotations

import math
import time
from typing import Any, Callable, Sequence

from worldtrack.map.messages import bucket_index


class StepTimings:
    """Where a worker's time goes, one CSV row per step (``map_timings.csv`` in its output folder):
    the capture time and the wall-clock times (s) at which the step began (the frame reached the
    tracker), the map was read, the tracker had stepped, the observations were made and published.

    >>> import io
    >>> out = io.StringIO()
    >>> StepTimings(out).write([10.0, 10.004, 10.005, 10.012, 10.013, 10.015])
    >>> out.getvalue().splitlines()[1]
    '10.000000,4.0,1.0,7.0,1.0,2.0,15.0'
    """

    HEADER = "capture_t,wait_ms,sync_ms,track_ms,observe_ms,publish_ms,total_ms"

    def __init__(self, stream):
        self.stream = stream
        stream.write(self.HEADER + "\n")

    def write(self, marks: Sequence[float]) -> None:
        t, *ts = marks
        parts = [(b - a) * 1000 for a, b in zip([t, *ts], ts)]
        self.stream.write(f"{t:.6f}," + ",".join(f"{v:.1f}" for v in parts) + f",{(ts[-1] - t) * 1000:.1f}\n")


def set_epoch(client: Any, keys: Any, lead_s: float, bucket_s: float, clock: Callable[[], float] = time.time,
              only_if_unset: bool = False) -> float:
    """Set the map's epoch to :func:`epoch_after` ``(clock(), lead_s, bucket_s)`` (frame ``i`` of
    every file then plays at ``epoch + i / fps``); returns the map's epoch."""
    client.set(keys.epoch, repr(epoch_after(clock(), lead_s, bucket_s)), nx=only_if_unset)
    return float(client.get(keys.epoch))


def map_epoch(client: Any, keys: Any, bucket_s: float, clock: Callable[[], float] = time.time, lead_s: float = 0.5,
              wait: bool = False, poll_s: float = 0.05) -> float:
    """The map's epoch (s): when video files played as cameras have their frame 0. Set by the first
    worker to ask (``lead_s`` s from ``clock()``, :func:`set_epoch`), or with ``wait`` by ``worldtrack
    map start`` (polled every ``poll_s`` s until it is set)."""
    if not wait:
        set_epoch(client, keys, lead_s, bucket_s, clock, only_if_unset=True)
    while True:
        value = client.get(keys.epoch)
        if value is not None:
            return float(value)
        time.sleep(poll_s)


def epoch_after(now: float, lead_s: float, bucket_s: float) -> float:
    """An epoch ``lead_s`` (to 1 s more) after ``now`` (s), in the middle of a time bucket (frame
    ``i`` of every file, at ``epoch + i / fps``, then falls in bucket ``i`` when fps is ``1 / bucket_s``).

    It is a whole second plus a multiple of 1/1024 s, the same fraction for every start when the
    bucket divides a second: the capture times ``epoch + i / fps`` then round the same way whatever
    the second, and a batch run repeats byte for byte (with the epoch at any instant, the
    differences of those times — the trackers' time steps — differ in their last bits).

    >>> e = [epoch_after(now, 0.5, 0.1) for now in (1.8e9 + 0.3, 1.8e9 + 7.91)]
    >>> [x - 1.8e9 for x in e]
    [1.0498046875, 9.0498046875]
    >>> e[0] + 3 / 10 - e[0] == e[1] + 3 / 10 - e[1]
    True
    """
    start = math.ceil(now + lead_s)
    middle = (bucket_index(start, bucket_s) + 0.5) * bucket_s - start
    return start + round(middle * 1024) / 1024


__all__ = ["StepTimings", "epoch_after", "map_epoch", "set_epoch"]
