"""Input and output at the edges: track files (and, beside them, video and frame sources).

>>> from worldtrack.io import read_tracks, TracksWriter      # doctest: +SKIP
"""

from worldtrack.io.tracks import (MOT_COLUMNS, TRACK_COLUMNS, TrackTable, TracksWriter,
                                  read_tracks, write_mot, write_tracks)

__all__ = ["MOT_COLUMNS", "TRACK_COLUMNS", "TrackTable", "TracksWriter", "read_tracks",
           "write_mot", "write_tracks"]
