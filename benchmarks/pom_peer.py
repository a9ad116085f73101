"""Run EPFL's Probabilistic Occupancy Map (POM) as an external program on worldtrack's scenes.

POM (Fleuret, Berclaz, Lengagne, Fua, TPAMI 2008; ``../shared/peers/pom``, read its ``PEER.md``) is
GPL-3.0: it is copied into a temporary folder, built there with ``g++`` and run as a separate
process; none of its code enters worldtrack. This module only writes what POM reads and reads what
it writes:

* the **grid**: floor locations every ``cell`` metres over the walkable area (and an evaluation
  area, if given) that at least one camera sees;
* the **rectangles**: for every camera and location, the image bounding box of a standing person
  (a box ``width`` × ``width`` × ``height`` metres on the floor at the location, its 8 corners
  projected through :class:`worldtrack.geometry.Camera`, lens distortion included), clipped to the
  image; ``notvisible`` when a corner is behind the camera or less than ``MIN_INSIDE`` of the box
  falls inside the image;
* the **masks**: one 8-bit grey PNG per camera and frame, 255 where the foreground model says
  "person", 0 elsewhere (POM's input format);
* the **result**: one text file per frame, ``<location> <probability>`` per line.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from worldtrack.io.tracks import TrackTable

#: The peer's folder, relative to the repository (``../shared/peers/pom``) unless WORLDTRACK_POM says.
ROOT = Path(__file__).resolve().parents[1]
#: A rectangle that keeps less than this share of its area inside the image is "not visible".
MIN_INSIDE = 0.3


def pom_source() -> Path:
    """Where POM's sources are: ``$WORLDTRACK_POM`` or ``../shared/peers/pom`` beside the repository."""
    env = os.environ.get("WORLDTRACK_POM")
    return Path(env) if env else ROOT.parent / "shared" / "peers" / "pom"


def why_not_buildable(source: Path) -> str | None:
    """None when POM can be built here, else one line saying what is missing."""
    if not (source / "pom.cc").is_file():
        return f"POM: skipped — no sources at {source} (set WORLDTRACK_POM)"
    for tool in ("g++", "make"):
        if shutil.which(tool) is None:
            return f"POM: skipped — {tool} is not installed (Debian: apt-get install g++ make)"
    probe = subprocess.run(["g++", "-E", "-x", "c++", "-"], input="#include <png.h>\n", capture_output=True, text=True)
    if probe.returncode != 0:
        return "POM: skipped — libpng headers are missing (Debian: apt-get install libpng-dev)"
    return None


def build(source: Path, workdir: Path) -> Path:
    """Copy POM's sources into ``workdir`` and build them; the path of the ``pom`` program."""
    src = workdir / "pom-src"
    shutil.copytree(source, src, ignore=shutil.ignore_patterns("*.o", "pom", "Makefile.depend"))
    for p in src.iterdir():
        p.chmod(0o644)                      # the shared copy is read-only
    done = subprocess.run(["make", "-C", str(src), "pom"], capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"POM did not build:\n{done.stderr[-2000:]}")
    return src / "pom"


def floor_grid(scene, cell: float, area: np.ndarray | None = None, margin: float = 0.0) -> np.ndarray:
    """(N, 2) metres: cell centres every ``cell`` m on the walkable floor (inside ``area`` if given)."""
    from worldtrack.scene.floor import points_in_polygon

    x0, x1, y0, y1 = scene.walkable.bounds
    if area is not None:
        x0, x1 = max(x0, area[:, 0].min()), min(x1, area[:, 0].max())
        y0, y1 = max(y0, area[:, 1].min()), min(y1, area[:, 1].max())
    xs = np.arange(x0 + cell / 2, x1, cell)
    ys = np.arange(y0 + cell / 2, y1, cell)
    xy = np.stack(np.meshgrid(xs, ys, indexing="xy"), axis=-1).reshape(-1, 2)
    keep = scene.walkable.contains(xy)
    if area is not None:
        keep &= points_in_polygon(xy, area)
    return xy[keep]


def person_rectangles(camera, xy: np.ndarray, height: float, width: float) -> tuple[np.ndarray, np.ndarray]:
    """Image boxes of a standing person at each floor point, as POM models people.

    The box spans the projections of the person's feet and head, ``width`` metres across the
    camera's line of sight: the points ``(x, y) ± width/2 · n`` at heights 0 and ``height``, with
    ``n`` the floor direction perpendicular to the line from the camera to ``(x, y)``.

    Returns
    -------
    rects : (N, 4) int — ``xmin, ymin, xmax, ymax`` in pixels, clipped to the image
    visible : (N,) bool — in front of the camera and at least ``MIN_INSIDE`` of the box in the image
    """
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    sight = xy - camera.centre[:2]
    across = np.column_stack([-sight[:, 1], sight[:, 0]]) / np.maximum(np.linalg.norm(sight, axis=1), 1e-9)[:, None]
    pts = [np.column_stack([xy + s * width / 2 * across, np.full(len(xy), z)]) for s in (-1, 1) for z in (0.0, height)]
    uv = camera.project(np.stack(pts, axis=1))                                          # (N, 4, 2) pixels
    front = np.all(np.isfinite(uv), axis=(1, 2))
    uv = np.where(front[:, None, None], uv, 0.0)
    lo, hi = uv.min(axis=1), uv.max(axis=1)
    size = np.array([camera.width - 1, camera.height - 1], float)
    clo, chi = np.clip(lo, 0, size), np.clip(hi, 0, size)
    full = np.prod(np.maximum(hi - lo, 1e-9), axis=1)
    kept = np.prod(np.maximum(chi - clo, 0.0), axis=1)
    visible = front & (kept >= MIN_INSIDE * full) & np.all(chi - clo >= 1.0, axis=1)
    rects = np.column_stack([np.round(clo), np.round(chi)]).astype(int)
    return rects, visible


def seen_by_some_camera(cameras, xy: np.ndarray, height: float, width: float) -> np.ndarray:
    """(N,) bool: the locations whose person box is visible in at least one of ``cameras``."""
    seen = np.zeros(len(xy), dtype=bool)
    for cam in cameras:
        seen |= person_rectangles(cam, xy, height, width)[1]
    return seen


@dataclass
class PomRun:
    """One POM run's folder and what goes in it."""

    workdir: Path
    cameras: list            # worldtrack Camera objects, POM camera number = index
    xy: np.ndarray           # (N, 2) metres, the locations
    frames: int

    @property
    def mask_format(self) -> str:
        return str(self.workdir / "masks" / "c%c_f%f.png")

    @property
    def result_format(self) -> str:
        return str(self.workdir / "out" / "proba_f%f.txt")

    def mask_path(self, camera_index: int, frame: int) -> Path:
        return self.workdir / "masks" / f"c{camera_index}_f{frame}.png"

    def write_mask(self, camera_index: int, frame: int, mask: np.ndarray) -> None:
        """Save a (H, W) mask (non-zero = person) as POM's 8-bit grey PNG."""
        cv2.imwrite(str(self.mask_path(camera_index, frame)), np.where(mask > 0, 255, 0).astype(np.uint8),
                    [cv2.IMWRITE_PNG_COMPRESSION, 1])

    def write_config(self, height: float, width: float, prior: float, sigma: float) -> tuple[Path, int]:
        """Write ``pom.cfg``: room, cameras, every rectangle, formats, PROCESS. Returns (path, visible rectangles)."""
        (self.workdir / "masks").mkdir(parents=True, exist_ok=True)
        (self.workdir / "out").mkdir(parents=True, exist_ok=True)
        lines = [f"ROOM -1 -1 {len(self.cameras)} {len(self.xy)}"]
        lines += [f"CAMERA {c} {cam.width} {cam.height}" for c, cam in enumerate(self.cameras)]
        n_visible = 0
        for c, cam in enumerate(self.cameras):
            rects, visible = person_rectangles(cam, self.xy, height, width)
            n_visible += int(visible.sum())
            for n in range(len(self.xy)):
                body = " ".join(map(str, rects[n])) if visible[n] else "notvisible"
                lines.append(f"RECTANGLE {c} {n} {body}")
        lines += [f"PRIOR {prior:g}", f"SIGMA_IMAGE_DENSITY {sigma:g}",
                  f"INPUT_VIEW_FORMAT {self.mask_format}", f"RESULT_FORMAT {self.result_format}",
                  f"PROCESS 0 {self.frames}", ""]
        path = self.workdir / "pom.cfg"
        path.write_text("\n".join(lines))
        return path, n_visible

    def run(self, binary: Path, config: Path, core: int | None) -> float:
        """Run POM on every frame; its wall time in seconds (pinned to ``core`` when given)."""
        cmd = [str(binary), str(config)]
        if core is not None and shutil.which("taskset"):
            cmd = ["taskset", "-c", str(core)] + cmd
        t0 = time.perf_counter()
        done = subprocess.run(cmd, capture_output=True, text=True)
        seconds = time.perf_counter() - t0
        if done.returncode != 0:
            raise RuntimeError(f"POM failed ({done.returncode}): {done.stderr[-2000:]}")
        return seconds

    def probabilities(self) -> np.ndarray:
        """(F, N) occupancy probability of every location in every frame."""
        out = np.zeros((self.frames, len(self.xy)))
        for f in range(self.frames):
            a = np.loadtxt(self.workdir / "out" / f"proba_f{f}.txt", ndmin=2)
            out[f, a[:, 0].astype(int)] = a[:, 1]
        return out


def detections(prob: np.ndarray, xy: np.ndarray, threshold: float, frame_numbers: np.ndarray) -> TrackTable:
    """Locations whose probability exceeds ``threshold``, as a table of detections (one id per row).

    Parameters
    ----------
    prob : (F, N) — :meth:`PomRun.probabilities`
    xy : (N, 2) metres — the locations
    threshold : probability
    frame_numbers : (F,) int — the frame number of each row of ``prob``
    """
    f, n = np.nonzero(prob > threshold)
    return TrackTable.from_arrays(np.asarray(frame_numbers)[f], np.arange(f.size), xy[n, 0], xy[n, 1])
