"""Where a person stands, from the lowest point of their silhouette: a foot model seen by this camera (opt-in).

The feet anchor (:mod:`.feet`) back-projects the lowest point of a silhouette to the floor. That
point is the near edge of the feet, not where the person stands (between the feet, under the
pelvis), and how far it falls short depends on the camera: a foot is a few centimetres high, and
its lowest image point is where a viewing ray grazes it, between the floor contact and the toe. A
ray that grazes a point at height ``z`` meets the floor ``z·d / (H − z)`` farther from the camera
(``d`` the floor distance, ``H`` the camera's height), so a steep view sees the toe almost where it
is and a flat one sees it shifted away. A constant offset (``feet.centre_offset_m``) ignores that.

This module renders the model instead of assuming a constant (analysis by synthesis). The feet are
two foot-shaped ellipsoids of the usual anthropometric fractions of the body height ``h`` (Drillis
& Contini: foot length 0.152 h, breadth 0.055 h, the ankle a quarter of the foot from the heel,
the feet under the hips): their reach towards the camera, averaged over the heading (unknown for a
standing person, and the velocity along one camera's ray is the least reliable part of a track),
is ``REACH_SHARE · h`` (0.087 h, 0.15 m at 1.7 m). The section of the feet in the vertical plane of
the line of sight is an ellipse centred on the standing point, half ``REACH_SHARE · h`` along the
ray and ``FOOT_HALF_HEIGHT_SHARE · h`` high (half a foot's height); its lowest image point is the
grazing ray of largest depression, which :func:`grazing_shortfall_m` finds and back-projects.

For a 1.7 m person and a camera 2.85 m high: 0.097 m at 5 m, 0.083 m at 7 m, 0.072 m at 9 m. The
anchor's feet on the line-of-sight development seeds 400-405 (2083 readings, before this module)
were 0.095 / 0.098 / 0.065 m short of the truth at 0-6 / 6-8 / 8-10 m.

Measured with ``feet.anchor``, ``feet.head_fallback=false``, ``depth.remeasure_after_encounter`` (issue 37,
session 10): paper_kato cam1 whole body 0.095-0.117 m -> 0.022-0.034 m (a constant 0.1 m: 0.023-0.037);
PETS (3 starts) MOTA 0.931 -> 0.937, IDF1 0.841 -> 0.793, switches 5 -> 2.7 (constant: 9.3), error 0.221 ->
0.244 m against the box-bottom truth; one camera held-out 420-439 0.443 -> 0.457, never-used 450-459
0.418 -> 0.470. Off by default (the anchor is).

>>> round(grazing_shortfall_m(2.85, 7.0, 1.7), 3)
0.083
"""

from __future__ import annotations

import numpy as np

#: Reach of the feet towards the camera, averaged over the heading, as a share of the body height
#: (two feet, each 0.152 h long and 0.055 h broad with the ankle 0.041 h from the heel, ankles
#: 0.1 h apart: the mean over headings of the farthest point of either foot along a direction).
REACH_SHARE = 0.087
#: Half the height of a foot (its section's vertical semi-axis), share of the body height.
FOOT_HALF_HEIGHT_SHARE = 0.022
#: Points on the near half of the feet's section where the grazing ray is looked for.
_SAMPLES = 181
_ANGLES = np.linspace(-0.5 * np.pi, 0.5 * np.pi, _SAMPLES)


def grazing_shortfall_m(camera_height_m: float, distance_m: float, height_m: float) -> float:
    """How far (m) the floor point under a person's lowest image point falls short of where they stand,
    along the line of sight.

    Parameters
    ----------
    camera_height_m : height of the camera's centre above the floor, m
    distance_m : floor distance from the point below the camera to the person, m
    height_m : the person's height, m (the feet scale with it)

    Returns
    -------
    float — ≥ 0, m; 0 when the camera is not above the feet or the person is under it
    """
    reach, half = REACH_SHARE * height_m, FOOT_HALF_HEIGHT_SHARE * height_m
    if camera_height_m <= 2 * half or distance_m <= reach:
        return 0.0
    x = distance_m - reach * np.cos(_ANGLES)        # the section's near half: contact, toe, top
    z = half + half * np.sin(_ANGLES)
    slope = (camera_height_m - z) / x                  # tan of each point's depression
    k = int(np.argmax(slope))
    return float(max(distance_m - camera_height_m / slope[k], 0.0))


def standing_point(feet_xy: np.ndarray, camera_centre: np.ndarray, height_m: float) -> np.ndarray:
    """The floor point (2,) where a person of ``height_m`` (m) stands whose lowest image point
    back-projects to ``feet_xy`` (2,, m) in a camera centred at ``camera_centre`` (3,, m): that far
    along the line of sight beyond the feet by :func:`grazing_shortfall_m`."""
    feet_xy = np.asarray(feet_xy, dtype=float)
    ray = feet_xy - camera_centre[:2]
    distance = float(np.hypot(*ray))
    if distance < 1e-9:
        return feet_xy
    shortfall = grazing_shortfall_m(float(camera_centre[2]), distance, height_m)
    # The model is drawn at the standing point, which is that much farther than the feet: once more there.
    shortfall = grazing_shortfall_m(float(camera_centre[2]), distance + shortfall, height_m)
    return feet_xy + shortfall * ray / distance


__all__ = ["FOOT_HALF_HEIGHT_SHARE", "REACH_SHARE", "grazing_shortfall_m", "standing_point"]
