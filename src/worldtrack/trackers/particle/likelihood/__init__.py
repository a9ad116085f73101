"""The likelihood of the particle tracker (seed 004): how well a particle explains one frame.

Which module holds which part:

* :mod:`.column` — the height column, eqs. 11–12 (:func:`~.column.column_counts`), and its
  likelihood ratio of the best object top (worldtrack's);
* :mod:`.top_edge` — the top edge at each particle's own height (worldtrack's);
* :mod:`.point` — the point likelihood, eq. 7 (the paper's baseline);
* :mod:`.labels` — what each camera's frame reads as: ``F > γ``, cast shadows set apart;
* :mod:`.images` — the per-frame layers: who owns a pixel (explaining away), who hides it
  (occluders);
* :mod:`.reading` — how particles read a camera's frame: the kernels' argument containers and
  per-pixel rules;
* :mod:`.camera` — :class:`~.camera.CameraLikelihood`, one camera's constants and the floor
  geometry of its columns;
* :mod:`.sums` — the likelihood multiplied over the cameras that see a particle;
* :mod:`.boxes` — the objects' image boxes and their overlaps;
* :mod:`.hidden` — columns whose lower part is hidden; :mod:`.pixel_weights` — samples weighted by
  the image length they stand for;
* :mod:`.fused` — one camera's share of the column ratio in one compiled call (the hot path);
* :mod:`.models` — the likelihoods a configuration names (``column-ratio``, ``column-count``,
  ``point``).

The labels the column reads (``F > γ``, shadows set apart) are made by
:mod:`worldtrack.foreground.shadows`.
"""

from worldtrack.trackers.particle.likelihood.camera import CameraLikelihood
from worldtrack.trackers.particle.likelihood.column import (ColumnOut, ColumnSpec, column_counts,
                                                            column_counts_reference, column_heights, column_spec)
from worldtrack.trackers.particle.likelihood.images import (NO_OCCLUDERS, Occluders, occluder_layers, owner_image,
                                                            read_codes)
from worldtrack.trackers.particle.likelihood.point import F_MAX, point_values, point_values_reference
from worldtrack.trackers.particle.likelihood.reading import CameraArgs, ReadAs, Reading
from worldtrack.trackers.particle.likelihood.sums import Sums, add_camera, close_sums
from worldtrack.trackers.particle.likelihood.top_edge import (EdgeSpec, edge_spec, top_edge_offsets, top_edge_terms,
                                                              top_edge_terms_reference)

__all__ = ["F_MAX", "NO_OCCLUDERS", "CameraArgs", "CameraLikelihood", "ColumnOut", "ColumnSpec", "EdgeSpec",
           "Occluders", "ReadAs", "Reading", "Sums", "add_camera", "close_sums", "column_counts",
           "column_counts_reference", "column_heights", "column_spec", "edge_spec", "occluder_layers", "owner_image",
           "point_values", "point_values_reference", "read_codes", "top_edge_offsets", "top_edge_terms",
           "top_edge_terms_reference"]
