"""Drawing tracks on camera images: ellipse outlines, ids, optionally the −1 ring and foreground."""

from __future__ import annotations

from typing import Iterable, Sequence

import cv2
import numpy as np

from worldtrack.geometry.camera import Camera
from worldtrack.geometry.quadric import ellipse_parameters, ellipsoid_conics, person_ellipsoid

_PALETTE = [(31, 119, 180), (255, 127, 14), (44, 160, 44), (214, 39, 40), (148, 103, 189), (140, 86, 75),
            (227, 119, 194), (127, 127, 127), (188, 189, 34), (23, 190, 207)]


def id_colour(track_id: int) -> tuple[int, int, int]:
    """A stable BGR colour per id."""
    r, g, b = _PALETTE[(int(track_id) - 1) % len(_PALETTE)]
    return (b, g, r)


def ellipse_outline(camera: Camera, x: float, y: float, height: float, width: float,
                    grow_px: float = 0.0, samples: int = 64) -> np.ndarray | None:
    """Outline (samples, 2) of a person's ellipsoid in the real (distorted) image, or None.

    ``grow_px`` enlarges both semi-axes (to draw the −1 ring's outer edge).
    """
    cen, rad = person_ellipsoid([[x, y]], height, width)
    depth = camera.depth(cen)[0] - np.linalg.norm(rad[0] * camera.optical_axis)
    if depth <= 0.05:
        return None
    C = ellipsoid_conics(camera.P, cen, rad)
    centre, axes, ang = ellipse_parameters(C)
    if not np.isfinite(axes).all():
        return None
    a, b = axes[0] + grow_px
    t = np.linspace(0, 2 * np.pi, samples, endpoint=False)
    ca, sa = np.cos(ang[0]), np.sin(ang[0])
    pts = np.column_stack([centre[0, 0] + a * np.cos(t) * ca - b * np.sin(t) * sa,
                           centre[0, 1] + a * np.cos(t) * sa + b * np.sin(t) * ca])
    return camera.distort_pixels(pts)


def projected_box(camera: Camera, track) -> tuple[float, float, float, float] | None:
    """The image box ``(u_min, v_min, width, height)`` (pixels, 0-based, not clipped to the image)
    around a person's ellipsoid as ``camera`` sees it (lens distortion included), or None when the
    person is not in front of the camera.

    Parameters
    ----------
    track : an object with ``x, y, height, width`` (metres)
    """
    outline = ellipse_outline(camera, track.x, track.y, track.height, track.width)
    if outline is None or not np.isfinite(outline).all():
        return None
    lo, hi = outline.min(axis=0), outline.max(axis=0)
    return float(lo[0]), float(lo[1]), float(hi[0] - lo[0]), float(hi[1] - lo[1])


def draw_label(image: np.ndarray, text: str, scale: float) -> None:
    """White text on a dark band in the top-left corner, readable on any background (in place)."""
    size = 0.45 * scale * 1.3
    thick = max(1, int(round(scale)))
    (w, h), base = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, size, thick)
    pad = max(2, int(3 * scale))
    band = image[: h + base + 2 * pad, : w + 2 * pad]
    band[:] = (band * 0.35).astype(np.uint8)
    cv2.putText(image, text, (pad, pad + h), cv2.FONT_HERSHEY_SIMPLEX, size, (255, 255, 255), thick, cv2.LINE_AA)


def draw_tracks(image: np.ndarray, camera: Camera, tracks: Iterable, ring_px: float | None = None,
                mask: np.ndarray | None = None, label: str | None = None) -> np.ndarray:
    """A copy of ``image`` with each track's ellipse, id and score drawn.

    Parameters
    ----------
    image : (H, W, 3) uint8 BGR
    tracks : objects with ``id, x, y, height, width`` (and optionally ``score``, ``flags``)
    ring_px : draw the outer edge of the −1 ring this many pixels outside the ellipse (dashed look)
    mask : (H, W) foreground mask to tint in magenta
    label : text for the top-left corner (frame number, time)
    """
    out = image.copy()
    if mask is not None:
        tint = out.copy()
        tint[mask.astype(bool)] = (255, 0, 255)
        out = cv2.addWeighted(out, 0.7, tint, 0.3, 0)
    scale = max(out.shape[0] / 480.0, 0.35)
    thick = max(1, int(round(2 * scale)))
    for tr in tracks:
        outline = ellipse_outline(camera, tr.x, tr.y, tr.height, tr.width)
        if outline is None:
            continue
        colour = id_colour(tr.id)
        pts = np.round(outline).astype(np.int32)
        cv2.polylines(out, [pts], True, colour, thick, cv2.LINE_AA)
        if ring_px:
            ring = ellipse_outline(camera, tr.x, tr.y, tr.height, tr.width, grow_px=ring_px, samples=48)
            if ring is not None:
                r = np.round(ring).astype(np.int32)
                for k in range(0, len(r), 2):  # dashed
                    cv2.line(out, tuple(r[k]), tuple(r[(k + 1) % len(r)]), colour, 1, cv2.LINE_AA)
        top = pts[np.argmin(pts[:, 1])]
        text = f"{tr.id}"
        if "unmeasurable" in getattr(tr, "flags", ()):
            text += "?"
        org = (int(top[0]) - int(6 * scale), int(top[1]) - int(4 * scale))
        cv2.putText(out, text, org, cv2.FONT_HERSHEY_SIMPLEX, 0.5 * scale * 1.4, (0, 0, 0), thick + 2, cv2.LINE_AA)
        cv2.putText(out, text, org, cv2.FONT_HERSHEY_SIMPLEX, 0.5 * scale * 1.4, colour, thick, cv2.LINE_AA)
    if label:
        draw_label(out, label, scale)
    return out


def side_by_side(images: Sequence[np.ndarray]) -> np.ndarray:
    """Images of equal height placed left to right."""
    h = max(i.shape[0] for i in images)
    padded = [cv2.copyMakeBorder(i, 0, h - i.shape[0], 0, 0, cv2.BORDER_CONSTANT) for i in images]
    return np.hstack(padded)
