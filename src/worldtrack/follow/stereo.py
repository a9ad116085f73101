"""Disparity from a rectified stereo pair with OpenCV's semi-global block matching (StereoSGBM).

The paper's Bumblebee2 delivers disparity itself; a user with a plain stereo pair computes it
here. Depth then is ``Z = fx·B / d`` (metres, B the baseline). SGBM works on grey images; its
fixed-point output (1/16 px) is turned into pixels, with 0 where it found no match.

Parameters (OpenCV's recommended forms): ``blockSize`` 5, ``P1 = 8·blockSize²``,
``P2 = 32·blockSize²``, uniqueness 10 %, speckle window 100 px with range 2, and as many
disparities (a multiple of 16) as a person at ``min_depth`` needs.

>>> import numpy as np
>>> rng = np.random.default_rng(0)
>>> left = rng.integers(0, 255, (60, 120, 3), dtype=np.uint8)
>>> right = np.roll(left, -8, axis=1)                # everything 8 px of disparity
>>> d = StereoMatcher(fx=100.0, baseline=0.1, min_depth=0.5).disparity(left, right)
>>> float(np.median(d[10:50, 40:100]))
8.0
"""

from __future__ import annotations

import cv2
import numpy as np

from worldtrack.errors import InputError


class StereoMatcher:
    """StereoSGBM for a rectified pair of ``fx`` pixels focal length and ``baseline`` metres."""

    def __init__(self, fx: float, baseline: float, min_depth: float = 0.8, block_size: int = 5):
        if not (fx > 0 and baseline > 0 and min_depth > 0):
            raise InputError(f"stereo: expected positive fx, baseline and min_depth, got {fx}, {baseline}, {min_depth}")
        self.fx, self.baseline = float(fx), float(baseline)
        n = int(np.ceil(self.fx * self.baseline / min_depth / 16.0)) * 16
        self.num_disparities = max(16, n)
        self.sgbm = cv2.StereoSGBM_create(minDisparity=0, numDisparities=self.num_disparities, blockSize=block_size,
                                          P1=8 * block_size ** 2, P2=32 * block_size ** 2, disp12MaxDiff=1,
                                          uniquenessRatio=10, speckleWindowSize=100, speckleRange=2,
                                          mode=cv2.STEREO_SGBM_MODE_SGBM)

    def disparity(self, left: np.ndarray, right: np.ndarray) -> np.ndarray:
        """(H, W) float32 disparity in pixels of the left image, 0 = no match."""
        if left.shape != right.shape:
            raise InputError(f"stereo: left image is {left.shape[1]}x{left.shape[0]} but right is "
                             f"{right.shape[1]}x{right.shape[0]}")
        grey = [cv2.cvtColor(im, cv2.COLOR_BGR2GRAY) if im.ndim == 3 else im for im in (left, right)]
        raw = self.sgbm.compute(grey[0], grey[1])
        d = raw.astype(np.float32) / 16.0
        d[raw <= 0] = 0.0
        return d

    def depth(self, left: np.ndarray, right: np.ndarray) -> np.ndarray:
        """(H, W) float32 depth in metres, 0 = no match."""
        return disparity_to_depth(self.disparity(left, right), self.fx, self.baseline)


def disparity_to_depth(disparity: np.ndarray, fx: float, baseline: float) -> np.ndarray:
    """``Z = fx·B / d`` (metres) where ``d > 0``, else 0.

    >>> [round(float(z), 4) for z in disparity_to_depth(np.array([0.0, 12.0], np.float32), 240.0, 0.12)]
    [0.0, 2.4]
    """
    d = np.asarray(disparity, dtype=np.float32)
    out = np.zeros_like(d)
    ok = d > 0
    out[ok] = np.float32(fx * baseline) / d[ok]
    return out
