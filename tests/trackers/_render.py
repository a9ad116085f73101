"""Rendering helpers shared by the tracker tests (imported as ``_render``: pytest puts this folder on the path)."""

from __future__ import annotations

import cv2
import numpy as np


def texture(seed: int, shape: tuple[int, int] = (240, 320)) -> np.ndarray:
    """A smooth random colour texture (H, W, 3) uint8 of ``shape = (H, W)``: the empty scene."""
    rng = np.random.default_rng(seed)
    img = cv2.GaussianBlur(rng.uniform(60, 200, (*shape, 3)).astype(np.float32), (0, 0), 3)
    return np.clip(img, 0, 255).astype(np.uint8)
