"""Settings of the region of interest (:mod:`worldtrack.trackers.ellipsoid.region`); a section of
:class:`~worldtrack.trackers.ellipsoid.config.EllipsoidConfig`, kept apart so the two stay light.

``area`` takes the floor polygon as numbers (a list, or the text ``"x1,y1,x2,y2,..."`` that
``--set`` gives):

>>> RegionConfig().area, RegionConfig(area="0,0, 4,0, 4,3").ring().tolist()
([], [[0.0, 0.0], [4.0, 0.0], [4.0, 3.0]])
>>> RegionConfig(area="0,0,4,0")
Traceback (most recent call last):
...
worldtrack.errors.InputError: ellipsoid.region.area: expected a floor polygon of at least 3 (x, y) points, m (x1,y1,x2,y2,...), got 4 numbers
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from pydantic import Field, field_validator

from worldtrack.config import Section


class RegionConfig(Section):
    """A region of interest on the floor: one id per visit to it."""

    path: ClassVar[str] = "ellipsoid.region"

    area: list[float] = Field(
        [], description="the region of interest, a floor polygon x1,y1,x2,y2,... m (at least 3 points); a person who "
        "was outside it for region.outside_s and steps back in is reported under a new id: one id per visit, as a "
        "count of visits or an evaluation cropped to the region numbers them ([] = off, the default; PETS 2009 with "
        "Milan's tracking area: examples/pets2009/README.md)")
    outside_s: float = Field(
        1.0, ge=0, description="... outside for at least this long, s: a person walking along the region's edge, "
        "whose place wavers across it, keeps their id")

    @field_validator("area", mode="before")
    @classmethod
    def _numbers(cls, value: Any) -> Any:
        """Accept the text ``"x1,y1,x2,y2,..."`` (``--set``) as well as a list; check the polygon."""
        if isinstance(value, str):
            parts = [s for s in value.replace(";", ",").replace(" ", ",").split(",") if s]
            try:
                value = [float(s) for s in parts]
            except ValueError:
                raise ValueError(f"expected numbers x1,y1,x2,y2,..., got {value!r}") from None
        if isinstance(value, (list, tuple)) and value and (len(value) % 2 or len(value) < 6):
            raise ValueError(f"expected a floor polygon of at least 3 (x, y) points, m (x1,y1,x2,y2,...), "
                             f"got {len(value)} numbers")
        return value

    def ring(self) -> np.ndarray:
        """The polygon as (M, 2) floor points, m (M = 0 when off)."""
        return np.asarray(self.area, float).reshape(-1, 2)


__all__ = ["RegionConfig"]
