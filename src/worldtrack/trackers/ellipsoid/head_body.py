"""A person drawn as a body and a head, for deciding between explanations of one silhouette.

The tracker draws a person as one ellipsoid (paper 000). That is enough to place somebody, but not
to tell "one tall person" from "a shorter one with somebody farther behind on the same line of
sight": the single ellipse is wider than a real head at the top, so a short ellipse plus a second
person's small top fits a lone tall person better than the lone ellipse does. What tells the two
apart is the head's size (:mod:`.two_on_ray`). Drawn as a body ellipsoid (floor to
``BODY_BELOW_TOP_M`` under the top of the head) and a head ellipsoid (``HEAD_HEIGHT_M`` ×
``HEAD_WIDTH_M``), a lone person's silhouette is explained by one person with a head of their own
size, and a top that is a farther person's smaller head by two.

A head is drawn with the tracker's own compiled ellipse kernel: an ellipsoid standing on the floor
of a camera lifted by ``dz`` (:func:`lifted`) is one standing ``dz`` above the real floor.

:func:`sample_window` takes a sampled window of the ternary real image; :func:`person_masks` draws
people into it (a nearer obstacle hides them); :func:`window_score` is eq. 5 with the foreground no
one explains in the denominator (the tracker's symmetric score) for a union of such masks.

>>> import numpy as np
>>> from worldtrack.geometry.camera import Camera
>>> from worldtrack.trackers.ellipsoid.args import camera_args
>>> cam = camera_args(Camera.look_at("c", 160, 120, [0.0, -4.0, 2.6], [0.0, 0.0, 0.8], hfov_deg=60.0), 5.0)
>>> up = lifted(cam, 1.0)
>>> x = np.array([0.0, 0.0, 1.0, 1.0])                    # a point 1 m above the floor ...
>>> bool(np.allclose(cam.P @ x, up.P @ np.array([0.0, 0.0, 0.0, 1.0])))   # ... is the lifted camera's floor
True
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from worldtrack.trackers.ellipsoid.args import CameraArgs, DrawArgs
from worldtrack.trackers.ellipsoid.forms import ellipse_forms

#: A head, hair included: height and width, m (adults' head length 0.23 m, breadth 0.15–0.16 m).
HEAD_HEIGHT_M = 0.24
HEAD_WIDTH_M = 0.17
#: The body ellipsoid ends this far below the top of the head (the neck), m.
BODY_BELOW_TOP_M = 0.12


class SampledWindow(NamedTuple):
    """Pixels of an image window on a stride: ideal coordinates (M,) ``u, v``, the ternary real
    image there ``real`` (M,) int8, and the obstacles' floor distance ``occ`` (M,) m."""

    u: np.ndarray
    v: np.ndarray
    real: np.ndarray
    occ: np.ndarray


def lifted(cam: CameraArgs, dz: float) -> CameraArgs:
    """``cam`` with its floor raised by ``dz`` m: what stands on the lifted floor stands ``dz`` above the real one."""
    P = cam.P.copy()
    P[:, 3] += dz * cam.P[:, 2]
    return cam._replace(P=P)


def sample_window(cam: CameraArgs, real: np.ndarray, box: tuple[int, int, int, int], target_pixels: int
                  ) -> SampledWindow:
    """The window ``box`` = (u0, u1, v0, v1) of ``real`` on a stride giving about ``target_pixels``
    pixels (0: every pixel), on a grid aligned to the image."""
    u0, u1, v0, v1 = (int(b) for b in box)
    stride = 1 if target_pixels <= 0 else max(1, int(np.sqrt(max(u1 - u0, 1) * max(v1 - v0, 1) / target_pixels)))
    vv, uu = np.meshgrid(np.arange(v0 + (-v0) % stride, v1, stride), np.arange(u0 + (-u0) % stride, u1, stride),
                         indexing="ij")
    vv, uu = vv.ravel(), uu.ravel()
    if cam.has_dist:
        u, v = cam.grid[vv, uu, 0].astype(float), cam.grid[vv, uu, 1].astype(float)
    else:
        u, v = uu.astype(float), vv.astype(float)
    return SampledWindow(u, v, real[vv, uu], cam.occ[vv, uu])


def person_parts(cam: CameraArgs, xy: np.ndarray, height: float, width: float, draw: DrawArgs
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Inner forms (2, 5), ring forms (2, 5), boxes (2, 4) and validity (2,) of a person's body and head."""
    at = np.asarray(xy, float).reshape(1, 2)
    body = ellipse_forms(cam, at, np.array([height - BODY_BELOW_TOP_M]), np.array([width]), draw)
    head = ellipse_forms(lifted(cam, height - HEAD_HEIGHT_M), at, np.array([HEAD_HEIGHT_M]), np.array([HEAD_WIDTH_M]),
                         draw)
    return tuple(np.concatenate([b, h]) for b, h in zip(body, head))


def _inside(forms: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """(M,) bool: points inside any of the ellipses ``forms`` (K, 5)."""
    out = np.zeros(len(u), bool)
    for f in forms:
        du, dv = u - f[0], v - f[1]
        out |= f[2] * du * du + 2.0 * f[3] * du * dv + f[4] * dv * dv < 1.0
    return out


def person_masks(cam: CameraArgs, win: SampledWindow, xy: np.ndarray, height: float, width: float,
                 draw: DrawArgs) -> tuple[np.ndarray, np.ndarray]:
    """(M,) bool masks of the window's pixels inside a person's body-and-head and inside its ring,
    pixels an obstacle nearer than the person hides left out."""
    inner, ring, _, valid = person_parts(cam, xy, height, width, draw)
    seen = win.occ >= np.hypot(xy[0] - cam.centre[0], xy[1] - cam.centre[1])
    return _inside(inner[valid], win.u, win.v) & seen, _inside(ring[valid], win.u, win.v) & seen


def parts_box(cam: CameraArgs, xy: np.ndarray, height: float, width: float, draw: DrawArgs) -> np.ndarray | None:
    """(4,) box u0, u1, v0, v1 of a person's body and head with their rings (None: not drawn)."""
    _, _, box, valid = person_parts(cam, xy, height, width, draw)
    box = box[valid & (box[:, 0] < box[:, 1]) & (box[:, 2] < box[:, 3])]
    if not len(box):
        return None
    return np.array([box[:, 0].min(), box[:, 1].max(), box[:, 2].min(), box[:, 3].max()])


def window_score(real: np.ndarray, inside: np.ndarray, ring: np.ndarray) -> tuple[float, float]:
    """Numerator and denominator of eq. 5 over a window for the union ``inside`` (M,) of the people
    drawn and the union ``ring`` of their rings, the foreground nobody explains counted in the
    denominator (the symmetric score).

    >>> import numpy as np
    >>> real = np.array([1, 1, -1, 0], np.int8)
    >>> window_score(real, np.array([1, 1, 0, 0], bool), np.array([1, 1, 1, 0], bool))   # exact: 3 / 3
    (3.0, 3.0)
    """
    sim = inside.astype(np.int8) - (ring & ~inside).astype(np.int8)
    num = float(np.dot(sim.astype(float), real.astype(float)))
    den = float(np.count_nonzero(sim) + np.count_nonzero((sim == 0) & (real > 0)))
    return num, den


__all__ = ["BODY_BELOW_TOP_M", "HEAD_HEIGHT_M", "HEAD_WIDTH_M", "SampledWindow", "lifted", "parts_box",
           "person_masks", "person_parts", "sample_window", "window_score"]
