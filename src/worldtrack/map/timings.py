"""Where a worker's time goes: one row per step, for finding what makes the map late."""

from __future__ import annotations

from typing import Sequence


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


__all__ = ["StepTimings"]
