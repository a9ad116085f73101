"""Following one target person with a moving stereo / RGB-D camera (seed 001), one frame at a time.

Per frame (:meth:`FollowTracker.step`):

1. predict the target (and every other tracked person) with the constant-velocity Kalman filter
   over the real time step;
2. plan-view detection from depth (:mod:`~worldtrack.follow.planview`), silhouettes
   (:mod:`~worldtrack.follow.silhouette`), colour normalisation and HS histograms
   (:mod:`~worldtrack.follow.colour`);
3. for every candidate RBhat (eq. 1) against the target's templates, E (eq. 2) against its
   prediction, the illumination weight α and D (eq. 3) (:mod:`~worldtrack.follow.dissimilarity`);
4. the decision: the paper's smallest D under the threshold, or (``track_others``) one assignment
   of all candidates to the target and the others (:mod:`~worldtrack.follow.others`); a lost
   target is looked for among the people seen now (:mod:`~worldtrack.follow.reid`);
5. the identity kept open (:mod:`~worldtrack.follow.identity`): each person's colour against the
   target's templates is averaged over time, and another track that clearly fits better takes the
   target's place (a wrong pick at a cut-in is undone when the target shows itself again);
6. the Kalman update with the chosen candidate, the template rules
   (:mod:`~worldtrack.follow.templates`; nothing is learnt while the identity is on probation),
   new and ended tracks of the others.

>>> import numpy as np
>>> from worldtrack.synth import make_scenario
>>> from worldtrack.follow import FollowTracker, frame_from_synth
>>> sc = make_scenario("follow-target", size=(160, 120), frames=12, seed=1, others=0)
>>> tracker = FollowTracker(scene=sc.scene)
>>> for b in sc.frames():
...     truth = (b.gt[0]["x"], b.gt[0]["y"])
...     step = tracker.follow(frame_from_synth(b), b.views["robot"].camera, start_xy=truth if b.frame == 0 else None)
>>> bool(step.found), bool(np.hypot(*(step.xy - truth)) < 0.15)
(True, True)
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from worldtrack.errors import InputError
from worldtrack.follow import kalman
from worldtrack.follow.colour import bhattacharyya, histograms, n_bins, normalise_colour
from worldtrack.follow.config import FollowConfig
from worldtrack.follow.dissimilarity import (decide, dissimilarity, illumination_weight, position_error,
                                             wb_change)
from worldtrack.follow.identity import IdentityEvidence
from worldtrack.follow.observation import Observation
from worldtrack.follow.others import Others, assign
from worldtrack.follow.reid import reidentify, within_reach
from worldtrack.follow.planview import Candidates, detect
from worldtrack.follow.silhouette import silhouettes
from worldtrack.follow.templates import Templates
from worldtrack.follow.vetoes import TargetHeight, heads_seen, hiding_target, pieces_of_others
from worldtrack.geometry.camera import Camera
from worldtrack.trackers.base import Frame
from worldtrack.scene.model import Scene

#: Others are tracked mostly by position: their α is at least this (their templates are recent).
OTHERS_MIN_ALPHA = 0.5
#: A person within this distance (m) of the target makes its silhouette unsafe to learn from.
CLEAR_RADIUS = 1.0
#: Unseen longer than this (s), the target's predicted velocity decays with this time constant.
COAST_S = 1.5
#: Found again after being unseen this long (s), the target's identity is on probation.
REACQUIRED_AFTER = 0.3


@dataclass
class FollowStep:
    """The result of one frame.

    Attributes
    ----------
    t : float, seconds; found : bool — the target was identified in this frame
    xy, velocity : (2,) filtered position (m) and velocity (m/s), world (predicted when not found)
    measured : (2,) the chosen candidate's position, NaN when not found
    chosen : int — index of the target's candidate, −1 if none
    candidates : Candidates; silhouettes : (H, W) int32 (0 background, i + 1 candidate i)
    D, RBhat, E : (N,) each candidate against the target (eqs. 3, 1, 2)
    alpha : float (eq. 3); w_steps : float — |W| in gain steps; gate : float, metres
    owner : (N,) int — who each candidate was given to: 1 the target, ≥ 2 another person, 0 nobody
    others_ids : (K,) int; others_xy : (K, 2) — the other people tracked (predicted when unseen);
    others_velocity : (K, 2) m/s — their Kalman velocities (a planner predicts where they walk)
    hidden : bool — not found, and somebody nearer the camera covers where the target should stand
    (depth says it is behind them: a follower keeps to its prediction); last_xy : (2,) m, where it
    was last measured
    """

    t: float
    found: bool
    xy: np.ndarray
    velocity: np.ndarray
    measured: np.ndarray
    chosen: int
    candidates: Candidates
    silhouettes: np.ndarray
    D: np.ndarray
    RBhat: np.ndarray
    E: np.ndarray
    alpha: float
    w_steps: float
    gate: float
    owner: np.ndarray
    others_ids: np.ndarray
    others_xy: np.ndarray
    others_velocity: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    hidden: bool = False
    last_xy: np.ndarray = field(default_factory=lambda: np.full(2, np.nan))


class FollowTracker:
    """Follows one target person (id 1) among others; see the module docstring.

    Parameters
    ----------
    config : FollowConfig, optional (the ``default`` preset)
    scene : Scene, optional — its walkable area removes walls and obstacles from the plan view
    """

    def __init__(self, config: FollowConfig | None = None, scene: Scene | None = None):
        self.config = config or FollowConfig()
        self.walkable = scene.distance_field(0.05) if scene is not None else None
        self.others = Others(n_bins(self.config), self.config.accel_sigma, self.config.measurement_sigma,
                             self.config.others_max_coast)
        self.templates: Templates | None = None
        self.x = np.zeros(4)
        self.P = np.eye(4)
        self.t = self.last_seen = 0.0
        self.last_xy = np.full(2, np.nan)
        self._alpha = 0.0
        self.identity = IdentityEvidence(self.config.identity_tau)
        self.probation_until = -np.inf
        self.height = TargetHeight()
        self.hidden = False

    # ------------------------------------------------------------------ observation
    def observe(self, frame: Frame, camera: Camera) -> Observation:
        """Candidates, silhouettes and histograms of one frame (no state changes)."""
        if frame.depth is None:
            raise InputError(f"frame {frame.index}: no depth (give a depth or disparity image per frame)")
        if frame.depth.shape != frame.image.shape[:2]:
            raise InputError(f"frame {frame.index}: depth is {frame.depth.shape[1]}x{frame.depth.shape[0]} "
                             f"but the colour image is {frame.image.shape[1]}x{frame.image.shape[0]}")
        cfg = self.config
        cands = detect(frame.depth, camera, cfg, self.walkable)
        sil = silhouettes(cands.labels, cands.stride, frame.depth, cands.depth)
        gains = frame.meta.get("wb_gains")
        image, wb = normalise_colour(frame.image, gains, cfg.normalise, sil > 0)
        return Observation(cands, sil, histograms(image, sil, len(cands), cfg), wb, camera)

    # ------------------------------------------------------------------ start and step
    def start(self, frame: Frame, camera: Camera, target_xy, max_distance: float = 1.0) -> FollowStep:
        """Register the candidate nearest ``target_xy`` (m, world) as the target; InputError if none is
        within ``max_distance``. Everyone else seen becomes another tracked person."""
        return self.start_with(self.observe(frame, camera), frame.t, target_xy, max_distance, frame.index)

    def start_with(self, obs: Observation, t: float, target_xy, max_distance: float = 1.0,
                   index: int = 0) -> FollowStep:
        """:meth:`start` on an observation made elsewhere (e.g. candidates from ground truth)."""
        c = obs.candidates
        d = np.hypot(*(c.xy - np.asarray(target_xy, float)).T) if len(c) else np.zeros(0)
        if len(d) == 0 or d.min() > max_distance:
            raise InputError(f"target: nobody found within {max_distance:g} m of ({target_xy[0]:.2f}, "
                             f"{target_xy[1]:.2f}) in frame {index}")
        i = int(np.argmin(d))
        self.templates = Templates(obs.hists[i], obs.wb, self.config.short_term_tau)
        x, P = kalman.initial_state(c.xy[i:i + 1], self.config.measurement_sigma)
        self.x, self.P = x[0], P[0]
        self.t = self.last_seen = t
        self.identity = IdentityEvidence(self.config.identity_tau)
        self.probation_until = -np.inf
        self.last_xy = c.xy[i].copy()
        self.height = TargetHeight()
        if heads_seen(c, obs.silhouettes, obs.camera)[i]:
            self.height.learn(float(c.top[i]), 0.0)
        self.others = Others(n_bins(self.config), self.config.accel_sigma, self.config.measurement_sigma,
                             self.config.others_max_coast)
        rest = np.arange(len(c)) != i
        owner = np.zeros(len(c), dtype=np.int64)
        owner[i] = 1
        if self.config.track_others:
            owner[rest] = self.others.add(c.xy[rest], obs.hists[rest], t)
        zeros = np.zeros(len(c))
        return self._result(t, obs, i, zeros, zeros, d * self.config.k, 0.0, 0.0, owner)

    def follow(self, frame: Frame, camera: Camera, start_xy=None) -> FollowStep:
        """:meth:`start` when ``start_xy`` is given (or nothing is followed yet), else :meth:`step`."""
        if start_xy is not None or self.templates is None:
            if start_xy is None:
                raise InputError("follow: give the target's position on the first frame (start_xy)")
            return self.start(frame, camera, start_xy)
        return self.step(frame, camera)

    def step(self, frame: Frame, camera: Camera) -> FollowStep:
        """Follow the target into ``frame`` (taken by ``camera``, the camera's pose at that frame)."""
        if self.templates is None:
            raise InputError("follow: call start() with the target's position first")
        if frame.t < self.t:
            raise InputError(f"frame {frame.index}: time stamp {frame.t:.3f} s is before the previous frame's")
        return self.step_with(self.observe(frame, camera), frame.t)

    def step_with(self, obs: Observation, t: float) -> FollowStep:
        """:meth:`step` on an observation made elsewhere, at time ``t`` (s)."""
        cfg = self.config
        dt = t - self.t
        if dt > 0:
            x, P = kalman.predict(self.x[None], self.P[None], dt, cfg.accel_sigma)
            self.x, self.P = x[0], P[0]
            if t - self.last_seen > COAST_S and not self.hidden:   # long unseen (and not known to be
                self.x[2:] *= np.exp(-dt / COAST_S)                # behind somebody): the walk slows down
            self.others.predict(dt)
        self.t = t
        c = obs.candidates
        E = position_error(c.xy, self.x[None, :2], cfg.k)[:, 0]
        rb = self.templates.rbhat(obs.hists)
        w = wb_change(obs.wb, self.templates.registered_wb)
        alpha = float(illumination_weight(w, cfg.p, cfg.wb_unit, cfg.alpha_floor, cfg.weighting))
        D = dissimilarity(rb, E, alpha, cfg.alpha_th)
        self._alpha = alpha
        gate = min(cfg.gate + cfg.gate_growth * (t - self.last_seen), cfg.max_gate)
        hiding = hiding_target(obs, self.x[:2], self.last_xy) if cfg.occluders else np.zeros(len(c), bool)
        allowed = (E / cfg.k <= gate) & ~hiding
        # Somebody of another height is somebody else. While the target is seen, only taller: a top is never
        # measured above the head, but one hidden by somebody the depth missed looks shorter, its head "seen".
        self._heads = heads_seen(c, obs.silhouettes, obs.camera)
        found_again = t - self.last_seen >= REACQUIRED_AFTER or t < self.probation_until
        mismatch = self.height.mismatch(c.top, self._heads & found_again, cfg.height_margin)
        allowed &= ~mismatch
        if t - self.last_seen > COAST_S:
            allowed &= rb < cfg.reid_rbhat      # the prediction no longer tells: colour must agree
        if cfg.track_others:
            chosen, owner = self._assign_all(obs, D, allowed, hiding | mismatch, t, dt)
            chosen = self._weigh_identity(obs, rb, chosen, owner, t, dt)
        else:
            chosen = decide(D, cfg.threshold, allowed)
            owner = np.zeros(len(c), dtype=np.int64)
            if chosen >= 0:
                owner[chosen] = 1
        if chosen >= 0:
            x, P = kalman.update(self.x[None], self.P[None], c.xy[chosen][None], cfg.measurement_sigma)
            self.x, self.P = x[0], P[0]
            if t - self.last_seen >= REACQUIRED_AFTER:
                self.probation_until = t + cfg.probation
            self.last_seen, self.last_xy = t, c.xy[chosen].copy()
        self.hidden = chosen < 0 and bool(hiding.any())
        self._update_templates(obs, chosen, D, rb, alpha, dt)
        return self._result(t, obs, chosen, D, rb, E, alpha, w, owner, gate)

    # ------------------------------------------------------------------ internals
    def _assign_all(self, obs: Observation, D: np.ndarray, allowed: np.ndarray, hiding: np.ndarray, t: float,
                    dt: float) -> tuple[int, np.ndarray]:
        """One assignment of all candidates to the target (row 0) and the others; new tracks for the rest."""
        cfg = self.config
        c = obs.candidates
        others = self.others
        cost = np.where(allowed, D, np.inf)[None]
        if len(others):
            E_o = position_error(c.xy, others.x[:, :2], cfg.k)
            rb_o = bhattacharyya(obs.hists, others.hist)
            alpha_o = max(self._alpha, OTHERS_MIN_ALPHA)
            D_o = dissimilarity(rb_o, E_o, alpha_o, cfg.alpha_th)
            gate_o = others.gate(t, cfg.gate, cfg.gate_growth, cfg.max_gate)
            D_o = np.where(E_o / cfg.k <= gate_o[None], D_o, np.inf)
            cost = np.vstack([cost, D_o.T])
        rows = assign(cost, cfg.threshold)
        chosen = int(rows[0])
        owner = np.zeros(len(c), dtype=np.int64)
        if chosen >= 0:
            owner[chosen] = 1
        matched = np.flatnonzero(rows[1:] >= 0)
        if len(matched):
            cand = rows[1:][matched]
            others.update(matched, c.xy[cand], obs.hists[cand], t, dt)
            owner[cand] = others.ids[matched]
        others.expire(t)
        if chosen >= 0 and t - self.last_seen >= REACQUIRED_AFTER and pieces_of_others(c.xy, owner > 1)[chosen]:
            owner[chosen], chosen = 0, -1       # found again beside somebody tracked: a piece of them
        if chosen < 0:
            chosen = reidentify(obs, owner, hiding, t, others=others, templates=self.templates, predicted=self.x[:2],
                                last_seen=self.last_seen, alpha=self._alpha, coast_s=COAST_S, cfg=cfg)
        free = np.flatnonzero(owner == 0)
        maybe = self._within_reach(c.xy[free], t) & ~pieces_of_others(c.xy, owner > 1)[free]
        owner[free] = others.add(c.xy[free], obs.hists[free], t, maybe)
        return chosen, owner

    def _weigh_identity(self, obs: Observation, rb: np.ndarray, chosen: int, owner: np.ndarray, t: float,
                        dt: float) -> int:
        """Add this frame's colour evidence (:mod:`~worldtrack.follow.identity`); another track seen now
        that fits the target's templates clearly better than the followed one exchanges roles with it.
        Changes ``owner`` in place; returns the target's candidate."""
        cfg = self.config
        self.identity.keep(self.others.ids)
        if cfg.identity_margin <= 0 or self._alpha >= cfg.alpha_th:
            return chosen
        seen = np.flatnonzero(owner > 1)
        self.identity.observe(dt, float(rb[chosen]) if chosen >= 0 else None, owner[seen], rb[seen])
        better = self.identity.better(cfg.identity_margin)
        if better is None or better not in owner:
            return chosen
        new = int(np.flatnonzero(owner == better)[0])
        hist = obs.hists[chosen] if chosen >= 0 else None
        self.x, self.P, self.last_seen = self.others.exchange(better, self.x, self.P, self.last_seen, hist)
        if chosen >= 0:
            owner[chosen] = better
        owner[new] = 1
        self.identity.exchange(better)
        self.probation_until = t + cfg.probation
        if self.templates.short is not None:     # it may have learnt the wrong person: restart it
            self.templates.short, self.templates.short_wb = self.templates.long.copy(), self.templates.long_wb
        return new

    def _within_reach(self, xy: np.ndarray, t: float) -> np.ndarray:
        """(N,) positions (N, 2) within reach of the lost target (:func:`~worldtrack.follow.reid.within_reach`)."""
        return within_reach(xy, self.x[:2], t - self.last_seen, self.config)

    def _update_templates(self, obs: Observation, chosen: int, D: np.ndarray, rb: np.ndarray, alpha: float,
                          dt: float) -> None:
        cfg = self.config
        hist = obs.hists[chosen] if chosen >= 0 else None
        d = float(D[chosen]) if chosen >= 0 else np.inf
        if self.t < self.probation_until:        # identity on probation: nothing learnt yet
            hist = None
        self.templates.paper_update(hist, obs.wb, alpha, d, cfg.alpha_th, cfg.update_max_d, cfg.update_every)
        if hist is None or self.templates.short is None:
            return
        # Learn when position alone is sure: close to the prediction and nobody else near. Not D:
        # after a change of light the target's D stays high until the template has learnt it.
        c = obs.candidates
        near = np.hypot(*(c.xy - c.xy[chosen]).T) < CLEAR_RADIUS
        close = np.hypot(*(c.xy[chosen] - self.x[:2])) * cfg.k < cfg.update_max_d
        if near.sum() == 1 and close:
            self.templates.learn(hist, obs.wb, dt)
            if self._heads[chosen]:
                self.height.learn(float(c.top[chosen]), dt)

    def _result(self, t: float, obs: Observation, chosen: int, D, rb, E, alpha: float, w: float,
                owner: np.ndarray, gate: float = 0.0) -> FollowStep:
        c = obs.candidates
        measured = c.xy[chosen].copy() if chosen >= 0 else np.full(2, np.nan)
        return FollowStep(t, chosen >= 0, self.x[:2].copy(), self.x[2:].copy(), measured, int(chosen), c,
                          obs.silhouettes, np.asarray(D, float), np.asarray(rb, float), np.asarray(E, float),
                          float(alpha), float(w), float(gate), owner, self.others.ids.copy(),
                          self.others.x[:, :2].copy(), self.others.x[:, 2:].copy(), self.hidden and chosen < 0,
                          self.last_xy.copy())
