"""worldtrack: track people in world coordinates — metres on the floor of a known room.

>>> from worldtrack import load_scene
>>> scene = load_scene("examples/scenes/kato_lab.yaml")      # doctest: +SKIP
>>> cam = scene.cameras["cam1"]                              # doctest: +SKIP
>>> cam.backproject([[80, 100]], z=0.0)                      # doctest: +SKIP
"""

__version__ = "0.1.0"

from worldtrack.errors import InputError, SceneError  # noqa: E402
from worldtrack.geometry.camera import Camera  # noqa: E402
from worldtrack.scene import Scene, load_scene  # noqa: E402

__all__ = ["Camera", "InputError", "Scene", "SceneError", "__version__", "load_scene"]
