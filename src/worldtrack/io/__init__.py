"""Input and output at the edges: track files (and, beside them, video and frame sources).

>>> from worldtrack.io import read_tracks, TracksWriter      # doctest: +SKIP

The track-file names are imported on first use, so light modules of this package (``io.text``)
do not load NumPy.
"""

from __future__ import annotations

import importlib
from typing import Any

_TRACKS = ("MOT_COLUMNS", "TRACK_COLUMNS", "TrackTable", "TracksWriter", "read_tracks", "write_mot",
           "write_tracks")


def __getattr__(name: str) -> Any:
    if name in _TRACKS:
        value = getattr(importlib.import_module("worldtrack.io.tracks"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'worldtrack.io' has no attribute {name!r}")


__all__ = list(_TRACKS)
