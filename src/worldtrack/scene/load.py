"""Scene files: YAML in metres, validated field by field, and written back.

Format (every key optional unless stated; unknown keys are errors)::

    name: kato-lab
    cameras:                                   # required, at least one
      - id: cam1                               # required
        image_size: [640, 480]                 # required, [width, height] px
        # exactly one of the three poses:
        P: [[...4], [...4], [...4]]            #   a 3x4 projection matrix
        K: [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]   # or K (or hfov_deg) and
        R: [[...3] x3]                         #   R (or rvec) + t, world → camera
        t: [tx, ty, tz]
        position: [x, y, z]                    #   or position + look_at (+ K or hfov_deg)
        look_at: [x, y, z]
        hfov_deg: 60
        distortion: [k1, k2, p1, p2, k3]       # OpenCV order, optional
    floor:                                     # required
      walkable:
        - outer: [[x, y], ...]                 # ≥ 3 vertices
          holes: [[[x, y], ...], ...]
    obstacles:
      - {name: desk, type: box, centre: [x, y, z], size: [sx, sy, sz], yaw_deg: 0}
      - {name: screen, type: patch, corners: [[x, y, z] x4]}
    entry_regions:
      - {name: door, polygon: [[x, y], ...]}
    people: {height: 1.65, width: 0.40, overrides: {3: {height: 1.80}}}

Every problem is reported as ``file: field.path: what was expected``.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any, Literal, Union

import numpy as np
import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from worldtrack.errors import SceneError
from worldtrack.geometry.camera import Camera, intrinsics_from_fov, look_at_rotation, normalise_projection
from worldtrack.geometry.rotation import rodrigues
from worldtrack.scene.floor import EntryRegion, FloorPolygon, WalkableArea, polygon_area
from worldtrack.scene.model import Box, Patch, PersonDefaults, Scene

Number = float
Point2 = list[Number]
Point3 = list[Number]


def _shape_of(value: Any) -> str:
    a = np.asarray(value, dtype=object)
    if a.ndim == 0:
        return "a scalar"
    if a.ndim == 1:
        return f"{a.shape[0]} values"
    return "x".join(str(s) for s in a.shape)


def _matrix(value: list[list[float]], rows: int, cols: int) -> list[list[float]]:
    if len(value) != rows or any(len(r) != cols for r in value):
        lens = sorted({len(r) for r in value})
        got = f"{len(value)}x{lens[0]}" if len(lens) == 1 else f"{len(value)} rows of lengths {lens}"
        raise ValueError(f"expected {rows}x{cols} matrix, got {got}")
    if not all(math.isfinite(x) for r in value for x in r):
        raise ValueError("expected finite numbers, got NaN or infinity")
    return value


def _vector(value: list[float], n: int, what: str = "values") -> list[float]:
    if len(value) != n:
        raise ValueError(f"expected {n} {what}, got {len(value)}")
    if not all(math.isfinite(x) for x in value):
        raise ValueError("expected finite numbers, got NaN or infinity")
    return value


def _ring(value: list[list[float]]) -> list[list[float]]:
    if any(len(p) != 2 for p in value):
        raise ValueError("expected [x, y] points")
    if len(value) < 3:
        raise ValueError(f"expected a polygon of at least 3 points, got {len(value)}")
    if polygon_area(value) < 1e-6:
        raise ValueError("expected a polygon with non-zero area")
    return value


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=False)


class CameraSpec(_Strict):
    id: str
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

    @field_validator("image_size")
    @classmethod
    def _size(cls, v: list[int]) -> list[int]:
        if len(v) != 2 or min(v) <= 0:
            raise ValueError(f"expected [width, height] in pixels, got {v}")
        return v

    @field_validator("P")
    @classmethod
    def _p(cls, v):
        return None if v is None else _matrix(v, 3, 4)

    @field_validator("K", "R")
    @classmethod
    def _k(cls, v):
        return None if v is None else _matrix(v, 3, 3)

    @field_validator("t", "rvec", "position", "look_at")
    @classmethod
    def _v3(cls, v):
        return None if v is None else _vector(v, 3)

    @field_validator("distortion")
    @classmethod
    def _dist(cls, v):
        if v is not None and not 1 <= len(v) <= 5:
            raise ValueError(f"expected 1 to 5 coefficients (k1, k2, p1, p2, k3), got {len(v)}")
        return v

    @field_validator("hfov_deg")
    @classmethod
    def _fov(cls, v):
        if v is not None and not 0 < v < 180:
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
        return [_ring(h) for h in v]


class FloorSpec(_Strict):
    walkable: list[FloorPolygonSpec]

    @field_validator("walkable")
    @classmethod
    def _nonempty(cls, v):
        if not v:
            raise ValueError("expected at least one polygon")
        return v


class BoxSpec(_Strict):
    name: str
    type: Literal["box"]
    centre: list[float]
    size: list[float]
    yaw_deg: float = 0.0
    blocks_walking: bool = True

    @field_validator("centre")
    @classmethod
    def _c(cls, v):
        return _vector(v, 3)

    @field_validator("size")
    @classmethod
    def _s(cls, v):
        _vector(v, 3)
        if min(v) <= 0:
            raise ValueError(f"expected positive sizes in metres, got {v}")
        return v


class PatchSpec(_Strict):
    name: str
    type: Literal["patch"]
    corners: list[list[float]]
    blocks_walking: bool = True

    @field_validator("corners")
    @classmethod
    def _corners(cls, v):
        _matrix(v, 4, 3)
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
    name: str
    polygon: list[list[float]]

    @field_validator("polygon")
    @classmethod
    def _poly(cls, v):
        return _ring(v)


class PersonSizeSpec(_Strict):
    height: float | None = None
    width: float | None = None


class PeopleSpec(_Strict):
    height: float = 1.65
    width: float = 0.40
    overrides: dict[int, PersonSizeSpec] = Field(default_factory=dict)

    @field_validator("height", "width")
    @classmethod
    def _pos(cls, v):
        if not 0 < v < 3:
            raise ValueError(f"expected metres in (0, 3), got {v}")
        return v


class SceneSpec(_Strict):
    name: str = "scene"
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
        return v


# ---------------------------------------------------------------------------- loading

def _loc(loc: tuple) -> str:
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        elif part in ("box", "patch"):  # discriminated-union tag, not a field
            continue
        else:
            out += ("." if out else "") + str(part)
    return out or "(top level)"


def _message(err: dict) -> str:
    msg = err["msg"]
    for prefix in ("Value error, ", "Assertion failed, "):
        if msg.startswith(prefix):
            msg = msg[len(prefix):]
    if err["type"] == "extra_forbidden":
        return "unknown key (not part of the scene format)"
    if err["type"] == "missing":
        return "required field is missing"
    if err["type"] in ("float_parsing", "float_type", "int_parsing", "int_type"):
        return f"expected a number, got {err.get('input')!r}"
    if err["type"] in ("list_type",):
        return f"expected a list, got {err.get('input')!r}"
    if err["type"] == "union_tag_invalid":
        return f"expected type 'box' or 'patch', got {err.get('input', {}).get('type')!r}"
    if err["type"] == "union_tag_not_found":
        return "expected a 'type' of 'box' or 'patch'"
    return msg


def load_scene(path: str | Path) -> Scene:
    """Read and validate a scene file.

    Raises
    ------
    SceneError
        Listing every problem as ``file: field.path: what was expected``.
    """
    path = Path(path)
    label = path.name
    try:
        text = path.read_text()
    except FileNotFoundError:
        raise SceneError([f"{path}: no such file"]) from None
    except OSError as e:
        raise SceneError([f"{path}: cannot read ({e.strerror})"]) from None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        where = f"line {mark.line + 1}: " if mark is not None else ""
        raise SceneError([f"{label}: {where}not valid YAML ({getattr(e, 'problem', e)})"]) from None
    return scene_from_dict(data, label=label, source=path)


def scene_from_dict(data: Any, label: str = "scene", source: Path | None = None) -> Scene:
    """Validate a parsed scene mapping and build the :class:`Scene` (see :func:`load_scene`)."""
    if not isinstance(data, dict):
        raise SceneError([f"{label}: expected a mapping with cameras and floor, got {type(data).__name__}"])
    try:
        spec = SceneSpec.model_validate(data)
    except ValidationError as e:
        raise SceneError([f"{label}: {_loc(err['loc'])}: {_message(err)}" for err in e.errors()]) from None
    problems: list[str] = []
    cameras: dict[str, Camera] = {}
    for i, cs in enumerate(spec.cameras):
        where = f"{label}: cameras[{i}]"
        if cs.id in cameras:
            problems.append(f"{where}.id: expected a unique id, {cs.id!r} is used twice")
            continue
        try:
            cam = _build_camera(cs)
        except ValueError as e:
            problems.append(f"{where}: {e}")
            continue
        if cam.centre[2] <= 0:
            problems.append(f"{where}: camera centre at Z = {cam.centre[2]:.3f} m is at or below the floor "
                            "(expected a camera above the floor; check the sign of Z or of P)")
            continue
        cameras[cs.id] = cam
    polys = tuple(FloorPolygon(np.asarray(p.outer, float), tuple(np.asarray(h, float) for h in p.holes))
                  for p in spec.floor.walkable)
    obstacles = []
    for ob in spec.obstacles:
        if isinstance(ob, BoxSpec):
            obstacles.append(Box(ob.name, np.asarray(ob.centre, float), np.asarray(ob.size, float),
                                 math.radians(ob.yaw_deg), ob.blocks_walking))
        else:
            obstacles.append(Patch(ob.name, np.asarray(ob.corners, float), ob.blocks_walking))
    names = [o.name for o in obstacles]
    for i, n in enumerate(names):
        if names.index(n) != i:
            problems.append(f"{label}: obstacles[{i}].name: expected a unique name, {n!r} is used twice")
    if problems:
        raise SceneError(problems)
    walkable = WalkableArea(polys, tuple(o.footprint for o in obstacles if o.blocks_walking))
    regions = [EntryRegion(r.name, np.asarray(r.polygon, float)) for r in spec.entry_regions]
    ppl = spec.people
    overrides = {k: (v.height or ppl.height, v.width or ppl.width) for k, v in ppl.overrides.items()}
    return Scene(spec.name, cameras, walkable, obstacles, regions,
                 PersonDefaults(ppl.height, ppl.width, overrides), source)


def _build_camera(cs: CameraSpec) -> Camera:
    w, h = cs.image_size
    if cs.P is not None:
        try:
            normalise_projection(cs.P)
        except ValueError as e:
            raise ValueError(f"P: {e}") from None
        return Camera.from_projection(cs.id, w, h, cs.P, cs.distortion)
    K = np.asarray(cs.K, float) if cs.K is not None else intrinsics_from_fov(w, h, cs.hfov_deg)
    if cs.position is not None:
        pos, target = np.asarray(cs.position, float), np.asarray(cs.look_at, float)
        if np.linalg.norm(target - pos) < 1e-9:
            raise ValueError("look_at: expected a point different from position")
        R = look_at_rotation(pos, target)
        t = -R @ pos
    else:
        R = np.asarray(cs.R, float) if cs.R is not None else rodrigues(cs.rvec)
        t = np.asarray(cs.t, float)
    try:
        return Camera(cs.id, w, h, K, R, t, cs.distortion)
    except ValueError as e:
        field = "K" if "K =" in str(e) else "R" if "rotation" in str(e) else "distortion"
        raise ValueError(f"{field}: {e}") from None


# ---------------------------------------------------------------------------- writing

def _r(x: Any, nd: int = 9) -> Any:
    a = np.asarray(x, dtype=float)
    return np.round(a, nd).tolist() if a.ndim else round(float(a), nd)


def camera_to_dict(cam: Camera) -> dict:
    """A camera block for a scene file (K, R, t and distortion)."""
    d = {"id": cam.id, "image_size": [cam.width, cam.height], "K": _r(cam.K), "R": _r(cam.R), "t": _r(cam.t)}
    if cam.has_distortion:
        d["distortion"] = _r(cam.dist)
    return d


def scene_to_dict(scene: Scene) -> dict:
    """The scene as a mapping that :func:`scene_from_dict` reads back to the same scene."""
    obstacles = []
    for o in scene.obstacles:
        if isinstance(o, Box):
            obstacles.append({"name": o.name, "type": "box", "centre": _r(o.centre), "size": _r(o.size),
                              "yaw_deg": _r(math.degrees(o.yaw)), "blocks_walking": o.blocks_walking})
        else:
            obstacles.append({"name": o.name, "type": "patch", "corners": _r(o.corners),
                              "blocks_walking": o.blocks_walking})
    people: dict[str, Any] = {"height": scene.people.height, "width": scene.people.width}
    if scene.people.overrides:
        people["overrides"] = {int(k): {"height": v[0], "width": v[1]} for k, v in scene.people.overrides.items()}
    return {
        "name": scene.name,
        "cameras": [camera_to_dict(c) for c in scene.cameras.values()],
        "floor": {"walkable": [{"outer": _r(p.outer), **({"holes": [_r(h) for h in p.holes]} if p.holes else {})}
                               for p in scene.walkable.polygons]},
        "obstacles": obstacles,
        "entry_regions": [{"name": r.name, "polygon": _r(r.polygon)} for r in scene.entry_regions],
        "people": people,
    }


def dump_scene(scene: Scene, path: str | Path) -> None:
    """Write a scene file that :func:`load_scene` reads back."""
    Path(path).write_text(yaml.safe_dump(scene_to_dict(scene), sort_keys=False, default_flow_style=None))
