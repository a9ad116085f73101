"""What the ellipsoid tracker reports about each person besides the position: σ, velocity, state.

Paper 000 gives a position and nothing about how far it can be off. worldtrack adds:

* **σ**, the 1-σ position error in metres (per floor axis, so a 2-D Gaussian error falls within
  1 σ of the truth 39 % of the time and within 2 σ 86 %). Each frame a camera shows the person,
  their position covariance is ``Rᵀ diag(κ² / max(c_ray, c_min), κ² / max(c_across, c_min)) R``:

  - ``c`` is the curvature of the match's own score E (eq. 5) around the chosen place, along
    and across the line of sight of the camera that shows the person largest, from E at ±10 cm
    (:func:`score_curvature`), read every :data:`CURVATURE_EVERY` frames. A sharp peak means a well-placed person; a flat ridge along the
    line of sight (one camera, or two facing each other) does not. The curvature already holds
    the cameras' geometry (how many pixels a step moves the person at that distance, in those
    views) and what is seen of the person (hidden pixels do not change E). E acts as a
    log-likelihood of weight 1 / κ² (:data:`SCORE_NOISE`); ``c_min`` (:data:`MIN_CURVATURE`)
    caps a flat score at κ / √c_min ≈ 0.29 m.
  - While the person's evidence is failing (the life cycle is counting down to end the track),
    σ is :data:`FAILING_FACTOR` times larger.
  - A person flagged ``unmeasurable`` (head and feet hidden in every view, paper 000 Table 2 (b))
    gets at least :data:`UNMEASURABLE_M` along the line of sight.

  While no camera shows the person, σ² grows by what the velocity filter's position variance
  has grown since the last measurement (:mod:`.velocity`). The constants were fitted (Gaussian
  maximum likelihood, ``benchmarks/uncertainty.py --training --fit``) on synthetic scenes: the
  crowd with 2 cameras (seeds 1–3) and 1 camera (4–5), two-crossing (0–1) and entry (0–1).
  ``benchmarks/uncertainty.py`` measures the calibration on other seeds and scenarios. (A
  geometric term, the inverse of the cameras' floor information of
  :func:`worldtrack.map.fusion.floor_information` times a pixel error, got a weight of
  0.007–0.05 px in that fit, nothing beside the curvature, for a quarter of the tracker's time:
  it was left out.)
* **vx, vy, speed** from the constant-velocity filter of :mod:`.velocity` over the positions
  and their covariance, instead of the tracker's internal velocity (which moves in steps of the
  matching grid). The positions are not changed.
* **mode**: ``tracking``; ``occluded`` when less than :data:`OCCLUDED_OWN_SHARE` of the
  person's visible ellipse is theirs alone (others in front) or they are ``unmeasurable``;
  ``lost`` when no camera shows them this frame, or their evidence is failing (the life cycle is
  counting down to end the track, :mod:`.life`).

``width`` is not measured: it is the body width the tracker draws the person with (the scene's
``people`` sizes), reported as such.

>>> cov = position_covariance(np.array([4.0, 40.0]), np.array([1.0, 0.0]))
>>> np.round(np.sqrt(np.diag(cov)), 3).tolist()          # along the ray (x) 3× across (y)
[0.13, 0.041]
"""

from __future__ import annotations

import math
import weakref
from typing import TYPE_CHECKING, Mapping, NamedTuple

import numpy as np

from worldtrack.trackers.base import Person, PositionMap, Track
from worldtrack.trackers.ellipsoid import velocity
from worldtrack.trackers.ellipsoid.velocity import Motion

if TYPE_CHECKING:
    from worldtrack.trackers.ellipsoid.joint import JointImage
    from worldtrack.trackers.ellipsoid.tracker import EllipsoidTracker

#: Distance (m) of the places either side of the chosen one where E is read for its curvature.
SCORE_STEP_M = 0.1
#: κ: E behaves as a log-likelihood of weight 1 / κ² (fitted, see the module's docstring).
SCORE_NOISE = 0.26
#: The curvature of E is read for each person every this many frames (in turn) and reused in
#: between: scoring five places is most of the cost of σ.
CURVATURE_EVERY = 3
#: Least curvature of E counted, 1/m² (a flat score: at most κ / √c_min = 0.29 m from the score).
MIN_CURVATURE = 0.8
#: σ of a person whose evidence is failing (:mod:`.life` counts down to end them) is this many
#: times larger (fitted).
FAILING_FACTOR = 1.9
#: Least σ along the line of sight of a person whose head and feet are hidden everywhere, m.
UNMEASURABLE_M = 1.0
#: σ of a confirmed person no camera has measured yet (e.g. put on the map by hand), m.
UNMEASURED_M = 1.0
#: Below this share of their visible pixels that are theirs alone, a person is ``occluded``.
OCCLUDED_OWN_SHARE = 0.5

#: The five places where E is read, in steps along (line of sight, across it): here, ±along, ±across.
_PLACES = np.array([[0.0, 0.0], [1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]])


def score_curvature(joint: "JointImage", k: int, step_m: float = SCORE_STEP_M) -> tuple[np.ndarray, np.ndarray]:
    """How sharply E falls off around person ``k``'s place in ``joint``, everybody else fixed.

    Returns
    -------
    curvature : (2,) float, 1/m² — ``(2 E₀ − E₊ − E₋) / step²`` along the line of sight of the
        camera that shows the person largest, and across it; 0 where a place is out of every view
    along : (2,) float — the unit floor direction of that line of sight
    """
    d, across = joint.axes(k, along_ray=True)
    places = joint.xy[k] + step_m * (_PLACES[:, :1] * d + _PLACES[:, 1:] * across)
    e, _, _ = joint.score(k, places, True, current=0)
    if not np.isfinite(e).all():
        return np.zeros(2), d
    return np.array([2 * e[0] - e[1] - e[2], 2 * e[0] - e[3] - e[4]]) / step_m ** 2, d


def position_covariance(curvature: np.ndarray, along: np.ndarray, unmeasurable: bool = False,
                        failing: bool = False) -> np.ndarray:
    """(2, 2) m²: one frame's position covariance from the score's ``curvature`` (2,) 1/m² along
    and across the unit floor direction ``along`` (2,); times :data:`FAILING_FACTOR`² while the
    person's evidence is ``failing``; at least :data:`UNMEASURABLE_M` along the line of sight
    when ``unmeasurable`` (see the module's docstring)."""
    axes = np.column_stack([along, [-along[1], along[0]]])
    var = SCORE_NOISE ** 2 / np.maximum(np.asarray(curvature, float), MIN_CURVATURE)
    if failing:
        var *= FAILING_FACTOR ** 2
    if unmeasurable:
        var[0] = max(var[0], UNMEASURABLE_M ** 2)
    return axes @ np.diag(var) @ axes.T


class Components(NamedTuple):
    """What one frame's position covariance of a person is made of (:func:`position_covariance`).

    Attributes
    ----------
    curvature : (2,) float, 1/m² — of E along and across the line of sight
    along : (2,) float — the unit floor direction of the line of sight
    unmeasurable : bool — head and feet hidden in every view
    failing : bool — the person's evidence failed this frame (the life cycle's ``low`` counter)
    t : float — the time stamp, s (the curvature may have been read up to
        :data:`CURVATURE_EVERY` − 1 frames earlier)
    """

    curvature: np.ndarray
    along: np.ndarray
    unmeasurable: bool
    failing: bool
    t: float


def reported_mode(p: Person, t: float) -> str:
    """The state a user reads for a person: ``tracking``, ``occluded`` or ``lost`` (see the
    module's docstring); a person not yet tracked keeps their internal mode."""
    if p.mode != "tracking":
        return p.mode
    if not p.seen_now(t) or p.count("low") > 0:
        return "lost"
    if "unmeasurable" in p.flags or p.own_share < OCCLUDED_OWN_SHARE:
        return "occluded"
    return "tracking"


class PositionUncertainty:
    """One tracker's σ, velocity filter and reported state of each person.

    The filters are kept per person (weakly: a person taken off the map takes their filter along)
    and advance once per time stamp, so trackers sharing a map do not count a frame twice.
    """

    def __init__(self, curvature_every: int = CURVATURE_EVERY) -> None:
        self._motion: "weakref.WeakKeyDictionary[Person, Motion]" = weakref.WeakKeyDictionary()
        #: Per person, the parts of their last measured covariance (for calibrating the constants).
        self.components: "weakref.WeakKeyDictionary[Person, Components]" = weakref.WeakKeyDictionary()
        self.curvature_every = max(1, int(curvature_every))
        self._frames = 0

    def measure(self, tracker: "EllipsoidTracker", real: Mapping[str, np.ndarray], t: float) -> None:
        """Measure the covariance of every confirmed person the tracker's cameras show at ``t``
        (real images ``real``), feed it to their velocity filter, and set their ``sigma``."""
        people = list(tracker.position_map)
        cams = [cid for cid in real if cid in tracker.views]
        shown = [k for k, p in enumerate(people)
                 if p.confirmed and p.mode == "tracking" and p.seen_now(t) and set(p.seen_by) & set(cams)]
        # The curvature is read for each person every `curvature_every` frames, in turn (by id),
        # and reused in between: it is most of this step's cost.
        due = [k for k in shown if people[k] not in self.components
               or (self._frames + people[k].id) % self.curvature_every == 0]
        self._frames += 1
        joint = tracker.joint_image({cid: real[cid] for cid in cams}, people) if due else None
        covs: dict[int, np.ndarray] = {}
        for k in shown:
            p = people[k]
            curvature, along = score_curvature(joint, k) if k in due else self.components[p][:2]
            parts = Components(curvature, along, "unmeasurable" in p.flags, p.count("low") > 0, float(t))
            self.components[p] = parts
            covs[k] = position_covariance(*parts[:4])
        for k, p in enumerate(people):
            if p.confirmed and p.once("uncertainty", t):
                self._advance(p, covs.get(k), t)

    def _advance(self, p: Person, cov: np.ndarray | None, t: float) -> None:
        """Person ``p``'s filter to time ``t``, measured with ``cov`` (None: not measured); σ."""
        m = self._motion.get(p)
        xy = np.array([p.x, p.y])
        if cov is None:
            if m is None:
                p.sigma = max(p.sigma, UNMEASURED_M)
                return
            m = velocity.predict(m, t)
            p.sigma = math.sqrt(np.trace(m.measured_cov) / 2 + velocity.grown_variance(m))
        else:
            m = velocity.start(xy, cov, t, (p.vx, p.vy)) if m is None else velocity.update(velocity.predict(m, t), xy, cov)
            p.sigma = math.sqrt(np.trace(cov) / 2)
        self._motion[p] = m

    def track(self, p: Person, t: float) -> Track:
        """Person ``p``'s output record at ``t``: filtered velocity, σ and reported mode."""
        tr = p.track()
        m = self._motion.get(p)
        if m is not None:
            tr.vx, tr.vy = float(m.mean[2]), float(m.mean[3])
        tr.mode = reported_mode(p, t)
        return tr

    def tracks(self, position_map: PositionMap, t: float) -> list[Track]:
        """The confirmed people's output records at ``t``, in map order."""
        return [self.track(p, t) for p in position_map if p.confirmed]


__all__ = ["CURVATURE_EVERY", "Components", "FAILING_FACTOR", "MIN_CURVATURE", "OCCLUDED_OWN_SHARE", "PositionUncertainty", "SCORE_NOISE",
           "SCORE_STEP_M", "UNMEASURABLE_M", "UNMEASURED_M", "position_covariance",
           "reported_mode", "score_curvature"]
