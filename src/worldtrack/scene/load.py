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

Every problem is reported as ``file: field.path: what was expected``, quoting at most a short
excerpt of the input. The file is read by :func:`worldtrack.io.safe_yaml.read_yaml` (bounded size,
nesting and aliases; numbers as YAML 1.2 reads them; duplicate keys refused), its fields validated
by :mod:`worldtrack.scene.spec`, and the whole checked by :mod:`worldtrack.scene.checks` (cameras
that cannot see the floor are errors; one that sees none of the walkable floor is a warning, kept
in :attr:`Scene.warnings`).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from pydantic import ValidationError

from worldtrack.errors import InputError, SceneError
from worldtrack.geometry.camera import Camera, intrinsics_from_fov, look_at_rotation, normalise_projection
from worldtrack.geometry.rotation import rodrigues
from worldtrack.io.safe_yaml import read_yaml, short
from worldtrack.scene import checks
from worldtrack.scene.floor import EntryRegion, FloorPolygon, WalkableArea
from worldtrack.scene.model import Box, Patch, PersonDefaults, Scene
# The field models, under the names this module has always had.
from worldtrack.scene.spec import (BoxSpec, CameraSpec, EntryRegionSpec, FloorPolygonSpec,  # noqa: F401
                                   FloorSpec, PatchSpec, PeopleSpec, PersonSizeSpec, SceneSpec)


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
    if err["type"] in ("float_parsing", "float_type"):
        return f"expected a number, got {short(err.get('input'))}"
    if err["type"] in ("int_parsing", "int_type", "int_from_float"):
        return f"expected a whole number, got {short(err.get('input'))}"
    if err["type"] in ("string_type",):
        return f"expected text, got {short(err.get('input'))}"
    if err["type"] in ("bool_type", "bool_parsing"):
        return f"expected true or false, got {short(err.get('input'))}"
    if err["type"] in ("list_type",):
        return f"expected a list, got {short(err.get('input'))}"
    if err["type"] in ("dict_type", "model_type", "model_attributes_type"):
        return f"expected a mapping (key: value), got {short(err.get('input'))}"
    if err["type"] == "union_tag_invalid":
        tag = err.get("input", {}).get("type") if isinstance(err.get("input"), dict) else None
        return f"expected type 'box' or 'patch', got {short(tag)}"
    if err["type"] == "literal_error":
        return f"expected {err.get('ctx', {}).get('expected', 'one of the allowed values')}, got {short(err.get('input'))}"
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
    try:
        data = read_yaml(path, "scene", label=path.name, max_bytes=checks.MAX_FILE_BYTES)
    except InputError as e:
        raise SceneError([str(e)]) from None
    return scene_from_dict(data, label=path.name, source=path)


def scene_from_dict(data: Any, label: str = "scene", source: Path | None = None) -> Scene:
    """Validate a parsed scene mapping and build the :class:`Scene` (see :func:`load_scene`)."""
    if not isinstance(data, dict):
        raise SceneError([f"{label}: expected a mapping with cameras and floor, got {type(data).__name__}"])
    try:
        spec = SceneSpec.model_validate(data)
    except ValidationError as e:
        errors = e.errors()
        problems = [f"{label}: {_loc(err['loc'])}: {_message(err)}" for err in errors[:10]]
        if len(errors) > 10:
            problems.append(f"{label}: … and {len(errors) - 10} more problems")
        raise SceneError(problems) from None
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
        if not (np.all(np.isfinite(cam.centre)) and np.all(np.abs(cam.centre) <= checks.MAX_COORDINATE_M)):
            problems.append(f"{where}: camera centre {short(cam.centre.tolist())} is not within "
                            f"±{checks.MAX_COORDINATE_M:g} m (check t or P)")
            continue
        if cam.centre[2] <= 0:
            problems.append(f"{where}: camera centre at Z = {cam.centre[2]:.3f} m is at or below the floor "
                            "(expected a camera above the floor; check the sign of Z or of P)")
            continue
        problem = checks.camera_problem(cam)
        if problem:
            problems.append(f"{where}: {problem}")
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
    walkable = WalkableArea(polys, tuple(o.footprint for o in obstacles if o.blocks_walking))
    problem = checks.floor_extent_problem(walkable)
    if problem:
        problems.append(f"{label}: floor.walkable: {problem}")
    if problems:
        raise SceneError(problems)
    regions = [EntryRegion(r.name, np.asarray(r.polygon, float)) for r in spec.entry_regions]
    ppl = spec.people
    overrides = {k: (v.height or ppl.height, v.width or ppl.width) for k, v in ppl.overrides.items()}
    scene = Scene(spec.name, cameras, walkable, obstacles, regions,
                  PersonDefaults(ppl.height, ppl.width, overrides), source)
    scene.warnings.extend(f"{label}: {w}" for w in checks.scene_warnings(list(cameras.values()), walkable))
    return scene


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
