"""The scene: cameras, floor, obstacles, entry regions and person defaults, as plain data.

A :class:`Scene` is loaded once (``worldtrack.scene.load_scene``) and never changes; caches that
depend only on it (occluder depth maps, the floor distance field) hang off it and are built on
first use.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Union

import numpy as np
from numpy.typing import ArrayLike

from worldtrack.geometry.camera import Camera
from worldtrack.geometry.raycast import ray_box, ray_quad
from worldtrack.scene.floor import EntryRegion, FloorGrid, WalkableArea, entry_region_index

if TYPE_CHECKING:
    from worldtrack.scene.occlusion import OcclusionMap


@dataclass(frozen=True)
class Box:
    """An upright box obstacle (desk, shelf, cabinet).

    Parameters
    ----------
    name : str
    centre : (3,) metres — the box's centre (a 0.73 m desk on the floor has centre Z = 0.365)
    size : (3,) metres — full extents along its own x, y and Z
    yaw : float, radians — turn about Z
    blocks_walking : bool — a person cannot stand inside its footprint
    """

    name: str
    centre: np.ndarray
    size: np.ndarray
    yaw: float = 0.0
    blocks_walking: bool = True

    @property
    def footprint(self) -> np.ndarray:
        """(4, 2) floor corners, counter-clockwise."""
        hx, hy = self.size[0] / 2, self.size[1] / 2
        local = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]])
        c, s = np.cos(self.yaw), np.sin(self.yaw)
        return local @ np.array([[c, s], [-s, c]]) + self.centre[:2]

    @property
    def corners(self) -> np.ndarray:
        """(8, 3) corners: bottom four then top four."""
        fp = self.footprint
        z0, z1 = self.centre[2] - self.size[2] / 2, self.centre[2] + self.size[2] / 2
        return np.vstack([np.column_stack([fp, np.full(4, z0)]), np.column_stack([fp, np.full(4, z1)])])

    @property
    def top(self) -> float:
        return float(self.centre[2] + self.size[2] / 2)

    def intersect(self, origin: ArrayLike, directions: np.ndarray) -> np.ndarray:
        """Ray parameter (N,) of the nearest hit, ``inf`` for a miss."""
        return ray_box(origin, directions, self.centre, self.size, self.yaw)


@dataclass(frozen=True)
class Patch:
    """A flat rectangular surface (partition, desk top, screen) given by its 4 corners in order."""

    name: str
    corners: np.ndarray
    blocks_walking: bool = True

    @property
    def footprint(self) -> np.ndarray:
        """(4, 2) floor projection of the corners (degenerate to a segment for a vertical patch)."""
        return self.corners[:, :2].copy()

    @property
    def top(self) -> float:
        return float(self.corners[:, 2].max())

    def intersect(self, origin: ArrayLike, directions: np.ndarray) -> np.ndarray:
        return ray_quad(origin, directions, self.corners)


Obstacle = Union[Box, Patch]


@dataclass(frozen=True)
class PersonDefaults:
    """Ellipsoid size of people: the paper's adult (1.65 m × 0.40 m) unless overridden per id."""

    height: float = 1.65
    width: float = 0.40
    overrides: dict[int, tuple[float, float]] = field(default_factory=dict)

    def size_of(self, person_id: int) -> tuple[float, float]:
        """(height, width) in metres for a track id."""
        return self.overrides.get(int(person_id), (self.height, self.width))


@dataclass(eq=False)
class Scene:
    """Everything worldtrack knows about a room.

    Attributes
    ----------
    name : str
    cameras : dict[str, Camera]
    walkable : WalkableArea
    obstacles : list of Box or Patch
    entry_regions : list of EntryRegion
    people : PersonDefaults
    source : Path or None — the file it was loaded from (for messages)
    warnings : list of str — odd but valid things the loader noticed (a camera that sees none of
        the walkable floor), one line each, for the command line to print
    """

    name: str
    cameras: dict[str, Camera]
    walkable: WalkableArea
    obstacles: list[Obstacle] = field(default_factory=list)
    entry_regions: list[EntryRegion] = field(default_factory=list)
    people: PersonDefaults = field(default_factory=PersonDefaults)
    source: Path | None = None
    warnings: list[str] = field(default_factory=list)
    _occlusion: dict = field(default_factory=dict, repr=False)
    _distance: dict = field(default_factory=dict, repr=False)

    def camera(self, camera_id: str) -> Camera:
        """The camera with this id; a clear error naming the known ids otherwise."""
        try:
            return self.cameras[camera_id]
        except KeyError:
            from worldtrack.errors import InputError
            raise InputError(f"no camera {camera_id!r} in scene {self.name!r} "
                             f"(cameras: {', '.join(self.cameras)})") from None

    def occlusion(self, camera_id: str) -> "OcclusionMap":
        """The obstacle depth map of one camera, computed on first use and cached."""
        if camera_id not in self._occlusion:
            from worldtrack.scene.occlusion import OcclusionMap
            self._occlusion[camera_id] = OcclusionMap.build(self.camera(camera_id), self.obstacles)
        return self._occlusion[camera_id]

    def distance_field(self, resolution: float = 0.05) -> FloorGrid:
        """Signed distance to walls and obstacles (m) on a floor grid, cached per resolution."""
        if resolution not in self._distance:
            self._distance[resolution] = self.walkable.distance_field(resolution)
        return self._distance[resolution]

    def entry_region_index(self, xy: ArrayLike) -> np.ndarray:
        """(N,) index into :attr:`entry_regions` of the region holding each point, −1 if none."""
        return entry_region_index(self.entry_regions, xy)

    def with_cameras(self, cameras: dict[str, Camera]) -> "Scene":
        """A copy with other cameras (e.g. rescaled for a downsized video); caches not shared."""
        return Scene(self.name, dict(cameras), self.walkable, list(self.obstacles),
                     list(self.entry_regions), self.people, self.source)
