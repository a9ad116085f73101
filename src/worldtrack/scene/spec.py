"""The scene file's fields as pydantic models: types, shapes, units and limits, field by field.

Strict types: a number must be written as a number (``"1.5"`` and ``true`` are not numbers), an
image size as whole pixels. Every number must be finite, every count and coordinate within the
limits of :mod:`worldtrack.scene.checks`, every polygon simple (holes inside their outer ring).
:mod:`worldtrack.scene.load` turns a validated :class:`SceneSpec` into a :class:`Scene`.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal, Union

import numpy as np
from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, field_validator, model_validator

from worldtrack.scene import checks
from worldtrack.scene.floor import polygon_area


def _text(value: Any) -> Any:
    """Names and ids: a number written bare (``id: 1``) is taken as its text; anything else as is."""
    return str(value) if isinstance(value, int) and not isinstance(value, bool) else value


Name = Annotated[str, BeforeValidator(_text)]


def _finite(values: list[float], what: str = "numbers") -> None:
    if not all(math.isfinite(x) for x in values):
        raise ValueError(f"expected finite {what}, got NaN or infinity")


def _bounded(values: list[float]) -> None:
    _finite(values)
    if any(abs(x) > checks.MAX_COORDINATE_M for x in values):
        raise ValueError(f"expected metres within ±{checks.MAX_COORDINATE_M:g}, got "
                         f"{max(values, key=abs):.4g} (coordinates are metres: were they millimetres?)")


def _matrix(value: list[list[float]], rows: int, cols: int) -> list[list[float]]:
    if len(value) != rows or any(len(r) != cols for r in value):
        lens = sorted({len(r) for r in value})
        got = f"{len(value)}x{lens[0]}" if len(lens) == 1 else f"{len(value)} rows of lengths {lens}"
        raise ValueError(f"expected {rows}x{cols} matrix, got {got}")
    _finite([x for r in value for x in r])
    return value


def _vector(value: list[float], n: int, what: str = "values") -> list[float]:
    if len(value) != n:
        raise ValueError(f"expected {n} {what}, got {len(value)}")
    _finite(value)
    return value


def _ring(value: list[list[float]]) -> list[list[float]]:
    if len(value) > checks.MAX_VERTICES:
        raise ValueError(f"expected at most {checks.MAX_VERTICES} vertices, got {len(value)}")
    if any(len(p) != 2 for p in value):
        raise ValueError("expected [x, y] points")
    if len(value) < 3:
        raise ValueError(f"expected a polygon of at least 3 points, got {len(value)}")
    _bounded([x for p in value for x in p])
    a = np.asarray(value, dtype=float)
    repeat = np.flatnonzero(np.all(a == np.roll(a, 1, axis=0), axis=1))
    if repeat.size:
        k = int(repeat[0])
        raise ValueError(f"vertex {k + 1} repeats vertex {(k - 1) % len(a) + 1}")
    if polygon_area(value) < 1e-6:
        raise ValueError("expected a polygon with non-zero area")
    problem = checks.polygon_problem(value)
    if problem:
        raise ValueError(problem)
    return value


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True)


class CameraSpec(_Strict):
    id: Name
    image_size: list[int]
    P: list[list[float]] | None = None
    K: list[list[float]] | None = None
    R: list[list[float]] | None = None
    rvec: list[float] | None = None
    t: list[float] | None = None
    position: list[float] | None = None
    look_at: list[float] | None = None
    hfov_deg: float | None = None
    distortion: list[float] | None = None

    @field_validator("id")
    @classmethod
    def _id(cls, v: str) -> str:
        problem = checks.camera_id_problem(v)
        if problem:
            raise ValueError(problem)
        return v

    @field_validator("image_size")
    @classmethod
    def _size(cls, v: list[int]) -> list[int]:
        if len(v) != 2 or min(v) <= 0 or max(v) > checks.MAX_IMAGE_SIDE:
            raise ValueError(f"expected [width, height] in pixels, each 1 to {checks.MAX_IMAGE_SIDE}, got {v}")
        return v

    @field_validator("P")
    @classmethod
    def _p(cls, v):
        return None if v is None else _matrix(v, 3, 4)

    @field_validator("K", "R")
    @classmethod
    def _k(cls, v):
        return None if v is None else _matrix(v, 3, 3)

    @field_validator("t", "position", "look_at")
    @classmethod
    def _v3(cls, v):
        if v is None:
            return None
        _vector(v, 3)
        _bounded(v)
        return v

    @field_validator("rvec")
    @classmethod
    def _rvec(cls, v):
        return None if v is None else _vector(v, 3)

    @field_validator("distortion")
    @classmethod
    def _dist(cls, v):
        if v is not None:
            if not 1 <= len(v) <= 5:
                raise ValueError(f"expected 1 to 5 coefficients (k1, k2, p1, p2, k3), got {len(v)}")
            _finite(v, "coefficients")
        return v

    @field_validator("hfov_deg")
    @classmethod
    def _fov(cls, v):
        if v is not None and not (math.isfinite(v) and 0 < v < 180):
            raise ValueError(f"expected degrees in (0, 180), got {v}")
        return v

    @model_validator(mode="after")
    def _one_pose(self) -> "CameraSpec":
        forms = {
            "P": self.P is not None,
            "K/R/t": self.t is not None or self.R is not None or self.rvec is not None,
            "position/look_at": self.position is not None or self.look_at is not None,
        }
        given = [k for k, v in forms.items() if v]
        if len(given) != 1:
            raise ValueError("expected exactly one pose: P, or K + R (or rvec) + t, or position + look_at"
                             + (f"; got {' and '.join(given)}" if given else "; got none"))
        if given[0] == "K/R/t":
            if self.t is None or (self.R is None) == (self.rvec is None):
                raise ValueError("expected t and one of R or rvec")
            if self.K is None and self.hfov_deg is None:
                raise ValueError("expected K or hfov_deg with R/t")
        if given[0] == "position/look_at":
            if self.position is None or self.look_at is None:
                raise ValueError("expected both position and look_at")
            if self.K is None and self.hfov_deg is None:
                raise ValueError("expected K or hfov_deg with position/look_at")
        if given[0] == "P" and (self.K is not None or self.hfov_deg is not None):
            raise ValueError("P already holds the intrinsics: give P alone, not with K or hfov_deg")
        return self


class FloorPolygonSpec(_Strict):
    outer: list[list[float]]
    holes: list[list[list[float]]] = Field(default_factory=list)

    @field_validator("outer")
    @classmethod
    def _outer(cls, v):
        return _ring(v)

    @field_validator("holes")
    @classmethod
    def _holes(cls, v):
        if len(v) > checks.MAX_POLYGONS:
            raise ValueError(f"expected at most {checks.MAX_POLYGONS} holes, got {len(v)}")
        return [_ring(h) for h in v]

    @model_validator(mode="after")
    def _holes_inside(self) -> "FloorPolygonSpec":
        for k, hole in enumerate(self.holes):
            problem = checks.hole_problem(self.outer, hole)
            if problem:
                raise ValueError(f"holes[{k}]: {problem}")
        if polygon_area(self.outer) - sum(polygon_area(h) for h in self.holes) <= 1e-6:
            raise ValueError("expected holes smaller than the outer polygon (no walkable area left)")
        return self


class FloorSpec(_Strict):
    walkable: list[FloorPolygonSpec]

    @field_validator("walkable")
    @classmethod
    def _nonempty(cls, v):
        if not v:
            raise ValueError("expected at least one polygon")
        if len(v) > checks.MAX_POLYGONS:
            raise ValueError(f"expected at most {checks.MAX_POLYGONS} polygons, got {len(v)}")
        return v


class BoxSpec(_Strict):
    name: Name
    type: Literal["box"]
    centre: list[float]
    size: list[float]
    yaw_deg: float = 0.0
    blocks_walking: bool = True

    @field_validator("centre")
    @classmethod
    def _c(cls, v):
        _vector(v, 3)
        _bounded(v)
        return v

    @field_validator("size")
    @classmethod
    def _s(cls, v):
        _vector(v, 3)
        _bounded(v)
        if min(v) <= 0:
            raise ValueError(f"expected positive sizes in metres, got {v}")
        return v

    @field_validator("yaw_deg")
    @classmethod
    def _yaw(cls, v):
        if not math.isfinite(v):
            raise ValueError(f"expected finite degrees, got {v}")
        return v


class PatchSpec(_Strict):
    name: Name
    type: Literal["patch"]
    corners: list[list[float]]
    blocks_walking: bool = True

    @field_validator("corners")
    @classmethod
    def _corners(cls, v):
        _matrix(v, 4, 3)
        _bounded([x for r in v for x in r])
        q = np.asarray(v, dtype=float)
        n = np.cross(q[1] - q[0], q[2] - q[0])
        if np.linalg.norm(n) < 1e-9:
            raise ValueError("expected 4 corners spanning a rectangle, got collinear points")
        n /= np.linalg.norm(n)
        if abs((q[3] - q[0]) @ n) > 0.01:
            raise ValueError("expected 4 coplanar corners (within 1 cm)")
        return v


ObstacleSpec = Annotated[Union[BoxSpec, PatchSpec], Field(discriminator="type")]


class EntryRegionSpec(_Strict):
    name: Name
    polygon: list[list[float]]

    @field_validator("polygon")
    @classmethod
    def _poly(cls, v):
        return _ring(v)


def _person_size(v: float | None) -> float | None:
    if v is not None and not (math.isfinite(v) and 0 < v < 3):
        raise ValueError(f"expected metres in (0, 3), got {v}")
    return v


class PersonSizeSpec(_Strict):
    height: float | None = None
    width: float | None = None

    @field_validator("height", "width")
    @classmethod
    def _pos(cls, v):
        return _person_size(v)


class PeopleSpec(_Strict):
    height: float = 1.65
    width: float = 0.40
    overrides: dict[int, PersonSizeSpec] = Field(default_factory=dict)

    @field_validator("height", "width")
    @classmethod
    def _pos(cls, v):
        return _person_size(v)

    @field_validator("overrides")
    @classmethod
    def _ids(cls, v):
        bad = [k for k in v if k < 1]
        if bad:
            raise ValueError(f"expected track ids from 1, got {bad[0]}")
        return v


class SceneSpec(_Strict):
    name: Name = "scene"
    cameras: list[CameraSpec]
    floor: FloorSpec
    obstacles: list[ObstacleSpec] = Field(default_factory=list)
    entry_regions: list[EntryRegionSpec] = Field(default_factory=list)
    people: PeopleSpec = Field(default_factory=PeopleSpec)

    @field_validator("cameras")
    @classmethod
    def _cams(cls, v):
        if not v:
            raise ValueError("expected at least one camera")
        if len(v) > checks.MAX_CAMERAS:
            raise ValueError(f"expected at most {checks.MAX_CAMERAS} cameras, got {len(v)}")
        return v

    @field_validator("obstacles")
    @classmethod
    def _obstacles(cls, v):
        if len(v) > checks.MAX_OBSTACLES:
            raise ValueError(f"expected at most {checks.MAX_OBSTACLES} obstacles, got {len(v)}")
        return v

    @field_validator("entry_regions")
    @classmethod
    def _regions(cls, v):
        if len(v) > checks.MAX_ENTRY_REGIONS:
            raise ValueError(f"expected at most {checks.MAX_ENTRY_REGIONS} entry regions, got {len(v)}")
        return v


__all__ = ["BoxSpec", "CameraSpec", "EntryRegionSpec", "FloorPolygonSpec", "FloorSpec", "ObstacleSpec",
           "PatchSpec", "PeopleSpec", "PersonSizeSpec", "SceneSpec"]
