"""Drawing a tracked pose on a frame: the model's outline and its axes (seed 003's video)."""

from __future__ import annotations

import cv2
import numpy as np

from worldtrack.pose.render import Intrinsics, splat


def draw_pose(image: np.ndarray, points: np.ndarray, R: np.ndarray, t: np.ndarray, intr: Intrinsics,
              axis_length: float, colour=(0, 255, 255), label: str | None = None) -> np.ndarray:
    """A copy of ``image`` (BGR) with the outline of model ``points`` (M, 3) at pose (R, t) and its
    x/y/z axes (red/green/blue, ``axis_length`` metres) drawn on it."""
    out = np.ascontiguousarray(image.copy() if image.ndim == 3 else cv2.cvtColor(image, cv2.COLOR_GRAY2BGR))
    xyz = np.asarray(points, float) @ np.asarray(R, float).T + np.asarray(t, float)
    r = splat(xyz, intr)
    mask = cv2.morphologyEx((r.index >= 0).astype(np.uint8), cv2.MORPH_CLOSE, np.ones((5, 5), np.uint8))
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    cv2.drawContours(out, contours, -1, colour, 1, cv2.LINE_AA)
    ends = np.vstack([np.zeros(3), np.eye(3) * axis_length]) @ np.asarray(R, float).T + np.asarray(t, float)
    if (ends[:, 2] > 1e-6).all():
        uv = np.column_stack([intr.fx * ends[:, 0] / ends[:, 2] + intr.cx, intr.fy * ends[:, 1] / ends[:, 2] + intr.cy])
        o = tuple(int(round(v)) for v in uv[0])
        for k, c in enumerate(((0, 0, 255), (0, 200, 0), (255, 0, 0))):
            cv2.line(out, o, tuple(int(round(v)) for v in uv[k + 1]), c, 2, cv2.LINE_AA)
    if label:
        cv2.putText(out, label, (8, 20), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1, cv2.LINE_AA)
    return out
