"""The tracker's own velocity, updated with a smaller gain along a lone camera's line of sight.

Each frame the velocity that drives the prediction (:mod:`.prediction`) moves towards the match's
own move over the frame interval by ``match.velocity_smoothing`` (:meth:`.life.LifeCycle._update_velocity`).
With one camera, the match places a person well across its line of sight and poorly along it: E is
nearly flat there, so the match moves a predicted person only part of the way back to where the
image puts them. That is a position gain well below 1 along the ray in a loop with the velocity
gain, and the loop rings: on PETS 2009 S2.L1 (issue 37) a person standing still 25.6 m from the
camera was placed ±0.6 m along the ray with a period of about 30 frames (4 s), the velocity
swinging ±1 m/s. An alpha-beta filter with position gain g and velocity gain a·g has damping
ζ ≈ √(g/a) / 2, so a smaller velocity gain along the ray damps it, while across the ray, which
the camera measures well, the velocity still follows every turn.

``match.velocity_along_ray`` (default 1: as before) scales the velocity gain for the component
along the line of sight of the one camera that showed the person this frame; a person several
cameras show is updated as before.

``match.velocity_sure_sigma_m`` (default 0: off) instead follows how well the position is measured
along the line of sight, whatever the number of cameras: the share is ``(σ_sure / σ)²`` (at most
1), σ the along-the-ray error from E's curvature (:mod:`.uncertainty`, :func:`curvature_share`).
Issue 37 (crowd 10, two cameras facing each other): a person half hidden from one camera sits on
a flat E along the other's ray; each frame's move along it (the hidden camera's pull) went into
the velocity at half gain, 0.3 → 1.2 m/s in four frames, and the prediction carried the track onto
the next person (dev seed 33, track 8).

Measured (issue 37, PETS 2009 S2.L1, ``benchmarks/real_data.py``, start frames 0-2): at 0.4 the
mean error 0.251 -> 0.238 m but MOTA 0.926 -> 0.912 and ID switches 1 -> 3.7; at 0.2 0.246 m,
MOTA 0.922, switches 4.3. Like ``crowd.predict_along_ray`` (:mod:`.prediction`), it costs the
walkers whom the match follows along the ray only with the velocity's help, so it stays off (1).
A smaller ``match.velocity_smoothing`` in both directions did better there (0.3: MOTA 0.946,
0.245 m, switches 1.7).

>>> ray = np.array([0.0, 1.0])                                      # the camera looks along +y
>>> damped_velocity(np.zeros(2), np.array([1.0, 1.0]), 0.5, 0.2, ray).round(2).tolist()
[0.5, 0.1]
>>> damped_velocity(np.zeros(2), np.array([1.0, 1.0]), 0.5, 0.2, None).round(2).tolist()
[0.5, 0.5]
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from worldtrack.trackers.base import Person
from worldtrack.trackers.ellipsoid.uncertainty import MIN_CURVATURE, SCORE_NOISE, Components


def damped_velocity(v: np.ndarray, measured: np.ndarray, gain: float, along_share: float,
                    ray: np.ndarray | None) -> np.ndarray:
    """The velocity (2,) m/s after one update towards ``measured`` (2,) m/s, the frame's move over
    its interval: by ``gain`` across ``ray`` (a unit floor vector, (2,)) and ``gain × along_share``
    along it; by ``gain`` in both directions when ``ray`` is None."""
    v = np.asarray(v, float)
    d = np.asarray(measured, float) - v
    if ray is None:
        return v + gain * d
    along = float(d @ ray) * np.asarray(ray, float)
    return v + gain * (d - along) + gain * along_share * along


def curvature_share(curvature: float, sure_sigma_m: float) -> float:
    """The velocity gain's share along a line of sight where E's curvature is ``curvature`` (1/m²):
    ``min(1, (sure_sigma_m / σ)²)``, σ = κ / √max(c, c_min) the position's 1-σ error there
    (:mod:`.uncertainty`). A person placed to ``sure_sigma_m`` (m) or better gets the full gain; a
    flat E (σ up to 0.29 m) lets the match move them but hardly moves their velocity."""
    var = SCORE_NOISE ** 2 / max(float(curvature), MIN_CURVATURE)
    return min(1.0, sure_sigma_m ** 2 / var)


def flat_ray(components: Mapping[Person, Components], sure_sigma_m: float, p: Person) -> tuple[np.ndarray, float] | None:
    """(The line of sight (2,) along which E's curvature was last read for ``p``, the velocity gain's
    share along it, :func:`curvature_share`); None before a first reading (``match.velocity_sure_sigma_m``)."""
    parts = components.get(p)
    if parts is None:
        return None
    return np.asarray(parts.along, float), curvature_share(parts.curvature[0], sure_sigma_m)


def flat_rays(components: Mapping[Person, Components], sure_sigma_m: float):
    """:func:`flat_ray` on ``components`` and ``sure_sigma_m``: a function of the person alone
    (:attr:`.life.LifeCycle.velocity_flat`)."""
    return lambda p: flat_ray(components, sure_sigma_m, p)


__all__ = ["curvature_share", "damped_velocity", "flat_ray", "flat_rays"]
