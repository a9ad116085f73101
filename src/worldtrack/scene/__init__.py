"""Scene files and what is computed from them once: floor, obstacles, occlusion maps."""

from worldtrack.scene.floor import EntryRegion, FloorGrid, FloorPolygon, WalkableArea
from worldtrack.scene.load import dump_scene, load_scene, scene_from_dict, scene_to_dict
from worldtrack.scene.model import Box, Patch, PersonDefaults, Scene

__all__ = ["Box", "EntryRegion", "FloorGrid", "FloorPolygon", "Patch", "PersonDefaults", "Scene",
           "WalkableArea", "dump_scene", "load_scene", "scene_from_dict", "scene_to_dict"]
