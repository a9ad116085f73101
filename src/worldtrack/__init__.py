"""worldtrack: track people in world coordinates — metres on the floor of a known room.

>>> from worldtrack import load_scene
>>> scene = load_scene("examples/scenes/kato_lab.yaml")      # doctest: +SKIP
>>> cam = scene.cameras["cam1"]                              # doctest: +SKIP
>>> cam.backproject([[80, 100]], z=0.0)                      # doctest: +SKIP

The names below are imported on first use (PEP 562), so ``import worldtrack`` and
``worldtrack --help`` do not load NumPy, SciPy or OpenCV.
"""

from __future__ import annotations

import importlib

TYPE_CHECKING = False       # typing itself is not imported: at start-up every import is a moment
if TYPE_CHECKING:           # Ctrl-C can land in (see worldtrack.entry)
    from typing import Any

__version__ = "0.1.0"

from worldtrack.errors import InputError, SceneError  # noqa: E402

# Public names that live in heavier modules: name -> module.
_LAZY = {"Camera": "worldtrack.geometry.camera", "Scene": "worldtrack.scene", "load_scene": "worldtrack.scene"}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'worldtrack' has no attribute {name!r}")


__all__ = ["Camera", "InputError", "Scene", "SceneError", "__version__", "load_scene"]
