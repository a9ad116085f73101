"""Generated scene files: a valid random room, then one mutation from a catalogue.

Each mutation says what the result is: ``valid`` ones (other line endings, a byte-order mark,
YAML anchors, ``[0640, 0480]``, a camera looking away from the floor) must be accepted and read
as meant; ``invalid`` ones (every class of issue 38: non-UTF-8, NaN/inf/huge numbers, huge or
self-intersecting floors, holes bigger than the floor, absurd image sizes, negative heights,
cameras looking at the sky or named ``a=b``, YAML 1.1 surprises, duplicate keys, deep nesting,
alias bombs) must be refused; ``either`` ones (cuts, byte flips, inserted bytes) may go either
way, but never with a traceback.
"""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any, Callable

import numpy as np
import yaml

from fuzz_runner import Case


def base_scene(rng: np.random.Generator) -> dict[str, Any]:
    """A valid room: a rectangular floor, 1-3 cameras above its corners looking in, maybe a desk."""
    w, h = (round(float(v), 2) for v in rng.uniform(3, 30, 2))
    cams = []
    for k in range(int(rng.integers(1, 4))):
        cx, cy = [(-0.5, -0.5), (round(w + 0.5, 2), -0.5), (round(w + 0.5, 2), round(h + 0.5, 2))][k]
        size = [[640, 480], [320, 240], [480, 360]][int(rng.integers(3))]
        cam = {"id": f"cam{k + 1}", "image_size": size, "position": [cx, cy, round(float(rng.uniform(2.5, 5)), 2)],
               "look_at": [float(w / 2), float(h / 2), 0.0], "hfov_deg": round(float(rng.uniform(50, 90)), 1)}
        if rng.random() < 0.3:
            cam["distortion"] = [round(float(rng.uniform(-0.2, 0)), 3), 0.0, 0.0, 0.0, 0.0]
        cams.append(cam)
    scene = {"name": f"room-{int(rng.integers(1000))}", "cameras": cams,
             "floor": {"walkable": [{"outer": [[0.0, 0.0], [float(w), 0.0], [float(w), float(h)], [0.0, float(h)]]}]},
             "entry_regions": [{"name": "door", "polygon": [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]}],
             "people": {"height": 1.7, "width": 0.4}}
    if rng.random() < 0.6:
        scene["obstacles"] = [{"name": "desk", "type": "box", "centre": [float(w / 2), float(h / 2), 0.37],
                               "size": [1.2, 0.6, 0.74], "yaw_deg": round(float(rng.uniform(0, 90)), 1)}]
    return scene


def dump(scene: dict) -> bytes:
    return yaml.safe_dump(scene, sort_keys=False, default_flow_style=None).encode()


def _cam(scene: dict, rng: np.random.Generator) -> dict:
    return scene["cameras"][int(rng.integers(len(scene["cameras"])))]


# --------------------------------------------------------------------------------------------
# Mutations: (scene dict, rng) -> bytes. Grouped by what the result must be.
# --------------------------------------------------------------------------------------------

def _set(path: str, value: Any) -> Callable[[dict, np.random.Generator], bytes]:
    """A mutation that sets one field (``cameras.*.x`` picks a random camera)."""
    def mutate(scene: dict, rng: np.random.Generator) -> bytes:
        target: Any = scene
        parts = path.split(".")
        for part in parts[:-1]:
            if part == "*":
                target = target[int(rng.integers(len(target)))]
            elif part.isdigit():
                target = target[int(part)]
            else:
                target = target.setdefault(part, {})
        last = parts[-1]
        target[int(last) if last.isdigit() else last] = value(rng) if callable(value) else value
        return dump(scene)
    return mutate


def _vertex(value: float) -> Callable[[dict, np.random.Generator], bytes]:
    def mutate(scene: dict, rng: np.random.Generator) -> bytes:
        outer = scene["floor"]["walkable"][0]["outer"]
        outer[int(rng.integers(len(outer)))][int(rng.integers(2))] = value
        return dump(scene)
    return mutate


def _text(edit: Callable[[str, np.random.Generator], str]) -> Callable[[dict, np.random.Generator], bytes]:
    return lambda scene, rng: edit(dump(scene).decode(), rng).encode()


def _scale_floor(factor: float) -> Callable[[dict, np.random.Generator], bytes]:
    def mutate(scene: dict, rng: np.random.Generator) -> bytes:
        ring = scene["floor"]["walkable"][0]["outer"]
        scene["floor"]["walkable"][0]["outer"] = [[x * factor, y * factor] for x, y in ring]
        return dump(scene)
    return mutate


def _many_vertices(scene: dict, rng: np.random.Generator) -> bytes:
    t = np.linspace(0, 2 * np.pi, 20_000, endpoint=False)
    scene["floor"]["walkable"][0]["outer"] = np.column_stack([5 + 4 * np.cos(t), 5 + 4 * np.sin(t)]).round(4).tolist()
    return dump(scene)


def _bowtie(scene: dict, rng: np.random.Generator) -> bytes:
    """Edges 1 and 3 cross, with an area that is not zero (a lopsided bow tie)."""
    (x0, y0), _, (x1, y1), _ = scene["floor"]["walkable"][0]["outer"]
    scene["floor"]["walkable"][0]["outer"] = [[x0, y0], [x1, y1], [x1, y0], [x0, round(y0 + 0.5 * (y1 - y0), 2)]]
    return dump(scene)


def _hole(kind: str) -> Callable[[dict, np.random.Generator], bytes]:
    def mutate(scene: dict, rng: np.random.Generator) -> bytes:
        (x0, y0), _, (x1, y1), _ = scene["floor"]["walkable"][0]["outer"]
        if kind == "bigger":
            hole = [[x0 - 1000, y0 - 1000], [x1 + 1000, y0 - 1000], [x1 + 1000, y1 + 1000], [x0 - 1000, y1 + 1000]]
        else:   # outside
            hole = [[x1 + 1, y0], [x1 + 2, y0], [x1 + 2, y0 + 1], [x1 + 1, y0 + 1]]
        scene["floor"]["walkable"][0]["holes"] = [hole]
        return dump(scene)
    return mutate


def _camera_at(where: str) -> Callable[[dict, np.random.Generator], bytes]:
    def mutate(scene: dict, rng: np.random.Generator) -> bytes:
        cam = _cam(scene, rng)
        x, y, z = cam["position"]
        if where == "sky":
            cam["look_at"] = [x + 1.0, y + 1.0, z + 5.0]
        elif where == "away":           # at the floor plane, far outside the room
            cam["look_at"] = [x - 60.0 if x < 1 else x + 60.0, y - 60.0 if y < 1 else y + 60.0, 0.0]
            cam["hfov_deg"] = 30.0
        else:                           # underground
            cam["position"] = [x, y, -1.0]
        return dump(scene)
    return mutate


def _octal_size(scene: dict, rng: np.random.Generator) -> bytes:
    cam = scene["cameras"][0]
    cam["image_size"] = [640, 480]
    return dump(scene).decode().replace("image_size: [640, 480]", "image_size: [0640, 0480]", 1).encode()


def _anchors(scene: dict, rng: np.random.Generator) -> bytes:
    """The people's default height given once (&h) and reused (*h) by an override."""
    scene = {k: v for k, v in scene.items() if k != "people"}
    return dump(scene) + b"people:\n  height: &h 1.72\n  width: 0.4\n  overrides:\n    2: {height: *h}\n"


def _deep(scene: dict, rng: np.random.Generator) -> bytes:
    return dump(scene) + b"extra: " + b"[" * 1000 + b"]" * 1000 + b"\n"


def _bomb(scene: dict, rng: np.random.Generator) -> bytes:
    lines = ['a0: &a0 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
    for k in range(1, 9):
        lines.append(f"a{k}: &a{k} [" + ", ".join([f"*a{k - 1}"] * 9) + "]")
    return dump(scene) + ("\n".join(lines) + "\nname: *a8\n").encode()


def _duplicate_key(scene: dict, rng: np.random.Generator) -> bytes:
    return dump(scene) + b"name: again\n"


def _non_utf8(scene: dict, rng: np.random.Generator) -> bytes:
    data = dump(scene)
    k = data.index(b"\n") + 1
    return data[:k] + b"# caf\xe9 \xff\xfe\n" + data[k:]


def _truncate(scene: dict, rng: np.random.Generator) -> bytes:
    data = dump(scene)
    return data[: int(rng.integers(len(data)))]


def _flip(scene: dict, rng: np.random.Generator) -> bytes:
    data = bytearray(dump(scene))
    for k in rng.integers(len(data), size=int(rng.integers(1, 6))):
        data[k] = int(rng.integers(256))
    return bytes(data)


def _swap_number(scene: dict, rng: np.random.Generator) -> bytes:
    """Replace one number of the file by an odd one (negative, zero, huge, tiny, 1:30, NaN…)."""
    text = dump(scene).decode()
    import re
    spans = [m.span() for m in re.finditer(r"-?\d+(\.\d+)?", text)]
    a, b = spans[int(rng.integers(len(spans)))]
    new = ["-1", "0", "1e300", "1e-300", "1:30", ".nan", "-.inf", "0x10", "1_000", "true", "'7'"][int(rng.integers(11))]
    return (text[:a] + new + text[b:]).encode()


VALID: dict[str, Callable] = {
    "as-is": lambda s, r: dump(s),
    "crlf": _text(lambda t, r: t.replace("\n", "\r\n")),
    "byte-order-mark": lambda s, r: b"\xef\xbb\xbf" + dump(s),
    "comments": _text(lambda t, r: "# a room\n" + t.replace("\n", "  # note\n", 3)),
    "octal-looking-size": _octal_size,
    "anchors": _anchors,
    "camera-sees-no-floor": _camera_at("away"),
    "numeric-camera-id": _set("cameras.0.id", 7),
}
INVALID: dict[str, Callable] = {
    "non-utf8": _non_utf8,
    "nan-vertex": _vertex(float("nan")), "inf-vertex": _vertex(float("inf")), "huge-vertex": _vertex(1e300),
    "nan-distortion": _set("cameras.*.distortion", [float("nan"), 0.0, 0.0, 0.0, 0.0]),
    "inf-distortion": _set("cameras.*.distortion", [0.1, float("inf")]),
    "nan-yaw": _set("obstacles", [{"name": "desk", "type": "box", "centre": [1, 1, 0.4], "size": [1, 1, 0.8],
                                   "yaw_deg": float("nan")}]),
    "nan-entry": _set("entry_regions.0.polygon.1", [float("nan"), 0.0]),
    "nan-position": _set("cameras.*.position", [float("nan"), 0.0, 3.0]),
    "floor-1e4": _scale_floor(1e4), "floor-mm": _scale_floor(1000.0),
    "20000-vertices": _many_vertices, "self-intersecting-floor": _bowtie,
    "hole-bigger-than-floor": _hole("bigger"), "hole-outside-floor": _hole("outside"),
    "size-1e9": _set("cameras.*.image_size", [10 ** 9, 480]), "size-bool": _set("cameras.*.image_size", [True, 480]),
    "size-float": _set("cameras.*.image_size", [640.5, 480]), "size-negative": _set("cameras.*.image_size", [-640, 480]),
    "negative-height": _set("people.height", -1.7),
    "negative-override": _set("people.overrides", {3: {"height": -1.0}}),
    "camera-looks-at-sky": _camera_at("sky"), "camera-underground": _camera_at("underground"),
    "camera-id-a=b": _set("cameras.*.id", "a=b"), "camera-id-space": _set("cameras.*.id", "cam 1"),
    "camera-id-empty": _set("cameras.*.id", ""),
    "sexagesimal-fov": _text(lambda t, r: t.replace("hfov_deg: ", "hfov_deg: 1:", 1) if "hfov_deg: " in t else t + "x: 1"),
    "duplicate-key": _duplicate_key, "deep-nesting": _deep, "alias-bomb": _bomb,
    "missing-floor": lambda s, r: dump({k: v for k, v in s.items() if k != "floor"}),
    "control-character": _text(lambda t, r: t.replace("\n", "\n\x1b[31m", 1)),   # a terminal colour code
    "unknown-key": _set("colour", "red"), "string-for-list": _set("cameras.*.position", "1, 2, 3"),
    "100-cameras": lambda s, r: dump({**s, "cameras": [dict(s["cameras"][0], id=f"c{k}") for k in range(100)]}),
}
EITHER: dict[str, Callable] = {"truncate": _truncate, "byte-flips": _flip, "odd-number": _swap_number}


def _check_octal(path: Path, outcome=None) -> str | None:
    from worldtrack.scene import load_scene
    cam = load_scene(path).cameras["cam1"]
    return None if (cam.width, cam.height) == (640, 480) else f"image size {cam.width}x{cam.height}"


def _check_anchors(path: Path, outcome=None) -> str | None:
    from worldtrack.scene import load_scene
    size = load_scene(path).people.size_of(2)
    return None if size[0] == 1.72 else f"override height {size[0]}"


def _check_numeric_id(path: Path, outcome=None) -> str | None:
    from worldtrack.scene import load_scene
    return None if "7" in load_scene(path).cameras else "camera id 7 lost"


_CHECKS = {"octal-looking-size": _check_octal, "numeric-camera-id": _check_numeric_id, "anchors": _check_anchors}


def scene_case(mutation: str, seed: int, inserted: bytes = b"") -> Case:
    """The scene-file case ``mutation`` of the room made from ``seed``."""
    rng = np.random.default_rng(seed)
    scene = base_scene(rng)
    for kind, table in (("valid", VALID), ("invalid", INVALID), ("either", EITHER)):
        if mutation in table:
            data = table[mutation](copy.deepcopy(scene), rng)
            break
    else:
        kind, data = "either", dump(scene)
        k = int(rng.integers(len(data) + 1))
        data = data[:k] + inserted + data[k:]
    return Case("scene", mutation, kind, data, lambda p: ["scene", "check", str(p)], _CHECKS.get(mutation))


MUTATIONS = [*VALID, *INVALID, *EITHER, "inserted-bytes"]
