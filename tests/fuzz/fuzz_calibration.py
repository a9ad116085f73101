"""Generated calibration point files (``worldtrack calibrate POINTS.csv``).

The points are markers in a room seen by a known camera. Valid mutations (other line endings,
comments, shuffled rows, half-pixel noise, thousands of points, the size given by flag) must
calibrate to that camera (centre within 5 cm); world coordinates in millimetres must still say
so (a warning naming millimetres). Invalid ones (pixels of 1e308, NaN, text, too few points, a
marker given twice with two pixels, points on a line, no header, no image size, NUL or non-UTF-8
bytes, a million points) must be refused.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np

from fuzz_runner import Case

SIZE = (640, 480)


def base_points(rng: np.random.Generator, n: int = 30) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """World points (n, 3) m, their pixels (n, 2) and the true camera centre (3,)."""
    from worldtrack.geometry.camera import Camera

    centre = np.array([rng.uniform(-1, 1), rng.uniform(-2.5, -1.5), rng.uniform(2.2, 3.2)])
    cam = Camera.look_at("cam", SIZE[0], SIZE[1], centre, [rng.uniform(-0.5, 0.5), 2.0, 0.6], hfov_deg=70.0)
    world = np.zeros((0, 3))
    while len(np.unique(np.round(world, 4), axis=0)) < n:
        w = np.column_stack([rng.uniform(-2.5, 2.5, 4 * n), rng.uniform(0.5, 5, 4 * n), rng.uniform(0, 2, 4 * n)])
        w[: len(w) // 3, 2] = 0.0                       # a third on the floor
        uv = cam.project(w)
        world = np.vstack([world, w[cam.in_image(uv, margin=5)]])
    world = np.unique(np.round(world, 4), axis=0)
    world = world[rng.permutation(len(world))[:n]]
    return world, cam.project(world), centre


def points_text(world: np.ndarray, image: np.ndarray, end: str = "\n", size: tuple[int, int] | None = SIZE) -> str:
    lines = ([f"# image_size: {size[0]}x{size[1]}"] if size else []) + ["X,Y,Z,x,y"]
    lines += [f"{X:.4f},{Y:.4f},{Z:.4f},{u:.3f},{v:.3f}" for (X, Y, Z), (u, v) in zip(world, image)]
    return end.join(lines) + end


def _cell(column: int, value: str) -> Callable:
    def mutate(world, image, rng):
        lines = points_text(world, image).splitlines()
        k = int(rng.integers(2, len(lines)))
        cells = lines[k].split(",")
        cells[column] = value
        lines[k] = ",".join(cells)
        return "\n".join(lines) + "\n"
    return mutate


def _duplicate_marker(world, image, rng):
    return points_text(np.vstack([world, world[:1]]), np.vstack([image, image[:1] + 40.0]))


def _on_a_line(world, image, rng):
    t = np.linspace(0, 1, len(world))[:, None]
    w = np.array([0.0, 1.0, 0.0]) + t * np.array([1.0, 2.0, 1.0])
    return points_text(w, image)


def _shuffle(world, image, rng):
    order = rng.permutation(len(world))
    return points_text(world[order], image[order])


def _noise(world, image, rng):
    return points_text(world, image + rng.normal(0, 0.3, image.shape))


def _mirror(world, image, rng):
    return points_text(world * np.array([1.0, -1.0, 1.0]), image)


def _truncate(world, image, rng):
    text = points_text(world, image)
    return text[: int(rng.integers(len(text)))]


def _flips(world, image, rng):
    data = bytearray(points_text(world, image).encode())
    for k in rng.integers(len(data), size=int(rng.integers(1, 6))):
        data[k] = int(rng.choice(list(b"0123456789.,-e\n#x ")))
    return data.decode("latin-1")


VALID: dict[str, Callable] = {
    "as-is": lambda w, i, r: points_text(w, i), "crlf": lambda w, i, r: points_text(w, i, "\r\n"),
    "cr": lambda w, i, r: points_text(w, i, "\r"),
    "comments": lambda w, i, r: "# measured by hand\n\n" + points_text(w, i).replace("\n", "\n# again\n", 3),
    "shuffled": _shuffle, "half-pixel-noise": _noise, "2000-points": lambda w, i, r: points_text(w, i),
    "size-by-flag": lambda w, i, r: points_text(w, i, size=None),
    "millimetres": lambda w, i, r: points_text(w * 1000.0, i),
}
INVALID: dict[str, Callable] = {
    "pixel-1e308": _cell(3, "1e308"), "pixel-nan": _cell(4, "nan"), "world-inf": _cell(0, "inf"),
    "world-1e300": _cell(2, "1e300"), "text-cell": _cell(1, "one"), "empty-cell": _cell(0, ""),
    "five-points": lambda w, i, r: points_text(w[:5], i[:5]), "marker-twice": _duplicate_marker,
    "points-on-a-line": _on_a_line, "mirrored-world": _mirror,
    "no-header": lambda w, i, r: points_text(w, i).replace("X,Y,Z,x,y\n", ""),
    "six-columns": lambda w, i, r: points_text(w, i).replace("X,Y,Z,x,y", "X,Y,Z,x,y,q"),
    "no-image-size": lambda w, i, r: points_text(w, i, size=None),
    "image-size-0x0": lambda w, i, r: points_text(w, i, size=(0, 0)),
    "nul-byte": lambda w, i, r: points_text(w, i).replace("\n", "\x00\n", 3),
    "a-million-points": lambda w, i, r: points_text(np.tile(w, (34_000, 1)), np.tile(i, (34_000, 1))),
}
EITHER: dict[str, Callable] = {"truncate": _truncate, "character-flips": _flips}


def _calibrates_to(centre: np.ndarray, scale: float = 1.0) -> Callable:
    """The printed camera centre is within 5 cm (times ``scale``) of the true one."""
    def check(path: Path, outcome) -> str | None:
        import re

        m = re.search(r"camera centre: \(([-\d.]+), ([-\d.]+), ([-\d.]+)\) m", outcome.stdout)
        if m is None:
            return "no camera centre printed"
        got = np.array([float(v) for v in m.groups()])
        if np.linalg.norm(got - centre * scale) > 0.05 * scale:
            return f"centre {got.round(3).tolist()} instead of {(centre * scale).round(3).tolist()}"
        if scale != 1.0 and "millimetres" not in outcome.stdout + outcome.stderr:
            return "no word about millimetres"
        return None
    return check


def calibration_case(mutation: str, seed: int, inserted: bytes = b"") -> Case:
    """The calibration-file case ``mutation`` of the markers made from ``seed``."""
    rng = np.random.default_rng(seed)
    world, image, centre = base_points(rng, 2000 if mutation == "2000-points" else 30)
    argv: Callable[[Path], list[str]] = lambda p: ["calibrate", str(p)]     # noqa: E731
    check = None
    for kind, table in (("valid", VALID), ("invalid", INVALID), ("either", EITHER)):
        if mutation in table:
            text = table[mutation](world, image, rng)
            data = text.encode("latin-1" if kind == "either" else "utf-8", "replace")
            if kind == "valid":
                check = _calibrates_to(centre, 1000.0 if mutation == "millimetres" else 1.0)
            if mutation == "size-by-flag":
                argv = lambda p: ["calibrate", str(p), "--image-size", f"{SIZE[0]}x{SIZE[1]}"]   # noqa: E731
            break
    else:
        kind, data = "either", points_text(world, image).encode()
        k = int(rng.integers(len(data) + 1))
        data = data[:k] + inserted + data[k:]
    return Case("calibration", mutation, kind, data, argv, check, suffix=".csv")


MUTATIONS = [*VALID, *INVALID, *EITHER, "inserted-bytes"]
