"""The shared person map on Redis: many cameras, processes and machines, one map (paper 000 §5–6).

* :mod:`~worldtrack.map.connection` — the URL, credentials (never printed), TLS, key names, the
  scene the map belongs to;
* :mod:`~worldtrack.map.messages` — what travels: observations (worker → fusion) and map states;
* :mod:`~worldtrack.map.lease` — who owns a camera, who holds the fusion (``SET NX PX``, renewed,
  writes fenced by the lease);
* :mod:`~worldtrack.map.worker` — a worker's side: new ids from the map, the map's people put on
  its tracker's map before a step, its estimates published after;
* :mod:`~worldtrack.map.evidence` — what a worker's cameras show of a person (body points not
  hidden by obstacles or other people) and how finely they resolve the floor: the fusion's weights;
* :mod:`~worldtrack.map.fusion` — merging the estimates of one person from several workers (the
  answer to "who updates a person two workers see?"), pure;
* :mod:`~worldtrack.map.fusion_role` — the fusion on Redis: buckets, take-over, nothing skipped;
* :mod:`~worldtrack.map.replay`, :mod:`~worldtrack.map.status` — reading the map back;
* :mod:`~worldtrack.map.simulate` — observation publishers without images (benchmarks, tests).

The command line: ``worldtrack track SCENE --map redis://… --cameras …`` (a worker),
``worldtrack map status|fuse|start|reset URL``, ``worldtrack replay URL``.
"""

from worldtrack.map.config import MapConfig, map_settings

__all__ = ["MapConfig", "map_settings"]
