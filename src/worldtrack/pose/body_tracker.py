"""Tracking the 14-DoF upper body with RGB-D (seed 003, §4): cascade PF, then joint LM.

Per frame: draw the body at the previous pose and keep N = 128 colour and N′ = 128 depth template
points (§4.3); the particle filter moves the torso (6 DoF), then the right arm (4), then the left
arm (4) — the paper's cascade (§4.4), 1500 candidates each, σ of Table 6 halved per stage; LM then
refines all 14 parameters *jointly* (§4.6) with central-difference Jacobians (eq. 20) on the
colour + depth cost (eqs. 16–19). ``lm_iterations = 0`` is the paper's conventional cascade.
The representative pose is the cost-weighted mean, with rotation means for the torso and for
each joint's ``Rz·Ry``, of the kept candidates in the best one's basin (:func:`representative_pose`).

>>> from worldtrack.synth.upper_body import body_sequence
>>> seq = body_sequence(2, n_frames=3, size=(320, 240))
>>> f0, f1 = seq.render(0), seq.render(1)
>>> tr = BodyTracker(seq.true_model, seq.intr, f0.params, BodyConfig(n_candidates=300, lm_iterations=3))
>>> est = tr.step(f1.image, f1.depth)
>>> est.params.shape
(14,)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import cv2
import numpy as np

from worldtrack.geometry.rotation import euler_zyx, rot_y, rot_z
from worldtrack.pose.body import LEFT_ARM, RIGHT_ARM, TORSO, BodyModel, BodySpace, SubSpace, stacked_points
from worldtrack.pose.cost import DEPTH_SAMPLING, ColourDepthCost, SparseTemplate
from worldtrack.pose.noise_weight import depth_share
from worldtrack.pose.lm import levenberg_marquardt
from worldtrack.pose.particle import candidate_weights, coarse_to_fine, mean_rotation
from worldtrack.pose.render import Intrinsics
from worldtrack.pose.template import sparse_template_pixels
from worldtrack.pose.tracker import to_grey


@dataclass(frozen=True)
class BodyConfig:
    """Settings (defaults: the paper's Tables 5–6 and PF1LM15).

    sigma_mm : first-stage σ of the torso's tx, ty, tz (mm); sigma_deg : of θ, φ, ψ, then each
    arm's shoulder (θs, φs) and elbow (θe, φe), degrees; pf : "cascade" (torso → right arm → left
    arm, the paper's) or "joint" (all 14 at once); depth_sampling : "bilinear" (on one surface) or
    "nearest" pixel (see :class:`~worldtrack.pose.cost.ColourDepthCost`); depth_weight : "fixed"
    (λ = ``lam``, the paper's), "noise" (λ from the two terms' measured spreads), "kernel" (from
    each term's robust-kernel weight; :mod:`~worldtrack.pose.noise_weight`, over the last
    ``noise_window`` frames) or "sandwich" (that weight over the score's design effect, each term
    at its own fit; :mod:`~worldtrack.pose.sandwich_weight`)
    """

    stages: int = 1
    lm_iterations: int = 15
    n_candidates: int = 1500
    n_keep: int = 10
    n_template: int = 128
    n_depth: int = 128
    sigma_mm: tuple = (5.0, 0.5, 5.0)
    sigma_deg: tuple = (1.0, 1.0, 1.0, 8.0, 8.0, 15.0, 15.0, 8.0, 8.0, 15.0, 15.0)
    c_depth_mm: float = 5.0
    lam: float = 0.9
    depth_weight: str = "fixed"
    noise_window: int = 10
    smooth_px: float = 1.0
    camera_blur_px: float = 0.6
    pf: str = "cascade"
    elbow_limit_deg: float | None = 150.0
    depth_sampling: str = "bilinear"
    seed: int = 0


class BodyEstimate(NamedTuple):
    """``params`` (14,) pose; ``cost`` mean ρ over the template; ``n_template`` points used."""

    params: np.ndarray
    cost: float
    n_template: int


def _zy_angles(R: np.ndarray) -> tuple[float, float]:
    """(θ, φ) with ``R = Rz(θ)·Ry(φ)``."""
    return float(np.arctan2(R[1, 0], R[0, 0])), float(-np.arcsin(np.clip(R[2, 0], -1, 1)))


def _zyx_angles(R: np.ndarray) -> tuple[float, float, float]:
    """(θ, φ, ψ) with ``R = Rz(θ)·Ry(φ)·Rx(ψ)``."""
    return (float(np.arctan2(R[1, 0], R[0, 0])), float(-np.arcsin(np.clip(R[2, 0], -1, 1))),
            float(np.arctan2(R[2, 1], R[2, 2])))


def mean_body_pose(P: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Weighted mean of parameter vectors (K, 14): translations averaged, the torso's and each
    joint's rotation by the rotation mean (no wrap-around or gimbal trouble from averaging angles)."""
    out = np.empty(14)
    out[:3] = (w[:, None] * P[:, :3]).sum(0)
    out[3:6] = _zyx_angles(mean_rotation(euler_zyx(P[:, 3], P[:, 4], P[:, 5]), w))
    for j in (6, 8, 10, 12):
        out[j:j + 2] = _zy_angles(mean_rotation(rot_z(P[:, j]) @ rot_y(P[:, j + 1]), w))
    return out


def representative_pose(P: np.ndarray, eps, step_scale: np.ndarray) -> np.ndarray:
    """The frame's pose: the cost-weighted mean (§5.1) of the kept candidates in the best one's basin.

    A weighted mean stands for its candidates only if they sit in one basin of the cost: there
    (the cost quasi-convex) the mean costs no more than the worst candidate averaged. Kept
    candidates can straddle two basins — e.g. a forearm swung 15–25° one way and the right one —
    and their mean is then a pose none of them holds, worse than all of them. So the candidates
    are taken in order of distance from the best (parameter steps divided by ``step_scale``), the
    means of the nearest 1, 2, …, K are scored together, and the largest group whose mean costs no
    more than its worst member is used (all K whenever their plain mean passes: the paper's mean).

    Parameters
    ----------
    P : (K, 14) kept candidates; eps : states (n, 14) → ε (n,); step_scale : (14,) parameter units
    (e.g. the first-stage σ) in which distances from the best candidate are measured

    Returns
    -------
    (14,) the representative pose

    >>> bowl = lambda X: np.minimum(((X - 0.1) ** 2).sum(1), ((X + 0.1) ** 2).sum(1))   # two basins
    >>> P = np.zeros((3, 14)); P[0], P[1], P[2] = 0.1, 0.12, -0.09
    >>> float(representative_pose(P, bowl, np.ones(14))[0].round(2))   # the first two's mean, not 0.05
    0.11
    """
    P = np.asarray(P, float)
    cost = eps(P)
    best = int(np.argmin(cost))
    order = np.argsort(np.linalg.norm((P - P[best]) / step_scale, axis=1), kind="stable")
    P, cost = P[order], cost[order]
    plain = mean_body_pose(P, candidate_weights(cost))
    if eps(plain[None])[0] <= cost.max() + 1e-12:                      # the common case: one basin
        return plain
    means = np.stack([mean_body_pose(P[:k], candidate_weights(cost[:k])) for k in range(1, len(P))])
    ok = eps(means) <= np.maximum.accumulate(cost[:-1]) + 1e-12
    return means[np.flatnonzero(ok)[-1]] if ok.any() else P[0]


class BodyTracker:
    """Track an upper body (see the module docstring).

    Parameters
    ----------
    model : BodyModel with known appearance; intr : Intrinsics; p0 : (14,) pose at the first frame
    """

    def __init__(self, model: BodyModel, intr: Intrinsics, p0: np.ndarray, config: BodyConfig = BodyConfig()):
        self.model, self.intr, self.config = model, intr, config
        self.noise = depth_share(config.depth_weight, config.lam, config.noise_window)
        self.space = BodySpace(model=model, elbow_limit=None if config.elbow_limit_deg is None
                               else np.radians(config.elbow_limit_deg))
        self.sigma = self.space.increment_sigma(config.sigma_mm, config.sigma_deg)
        self.points, self.normals, self.albedo, self.part = stacked_points(model)
        self.local = self.points                                       # part-frame coordinates
        ends = np.cumsum([0] + [len(m.points) for m in model.parts])
        self.part_slices = [slice(a, b) for a, b in zip(ends[:-1], ends[1:])]
        self.from_image = bool(model.parts[0].from_image)
        self.rng = np.random.default_rng(config.seed)
        self.reset(p0)

    def reset(self, p: np.ndarray) -> None:
        self.state = np.asarray(p, float).copy()
        self.kept = self.state[None].copy()

    def _camera_points(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Camera-frame points and normals (M, 3) of the whole body at ``p``."""
        T = self.space.transforms(p[None])[0]
        xyz, nrm = np.empty_like(self.local), np.empty_like(self.normals)
        for k in range(len(T)):
            sel = self.part_slices[k]
            xyz[sel] = self.local[sel] @ T[k, :, :3].T + T[k, :, 3]
            nrm[sel] = self.normals[sel] @ T[k, :, :3].T
        return xyz, nrm

    def make_cost(self, grey: np.ndarray, depth: np.ndarray | None) -> ColourDepthCost:
        cfg = self.config
        xyz, nrm = self._camera_points(self.state)
        sigma = float(np.hypot(cfg.smooth_px, 0.0 if self.from_image else cfg.camera_blur_px))
        tp = sparse_template_pixels(self.albedo, xyz, self.intr, cfg.n_template, cfg.n_depth, sigma=sigma, normals=nrm,
                                    groups=self.part)
        ci, di = tp.colour[np.argsort(self.part[tp.colour], kind="stable")], tp.depth
        order = np.argsort(self.part[tp.colour], kind="stable")
        colour = SparseTemplate(self.local[ci], self.part[ci], tp.value[order])
        dtemp = SparseTemplate(self.local[di], self.part[di], xyz[di, 2])
        return ColourDepthCost(colour, dtemp, grey, depth, self.intr, None, cfg.c_depth_mm / 1000, self.noise.lam,
                               DEPTH_SAMPLING[cfg.depth_sampling])

    def _pf(self, eps, start: np.ndarray):
        cfg = self.config
        if cfg.pf == "joint":
            return coarse_to_fine(self.space, eps, start, self.sigma, cfg.stages, cfg.n_candidates, cfg.n_keep, self.rng)
        kept, sigma = start, self.sigma.copy()
        out = None
        for _ in range(max(cfg.stages, 0)):
            for group in (TORSO, RIGHT_ARM, LEFT_ARM):               # the paper's cascade order
                idx = np.arange(14)[group]
                out = coarse_to_fine(SubSpace(self.space, idx), eps, kept, sigma[idx], 1, cfg.n_candidates,
                                     cfg.n_keep, self.rng)
                kept = out.states
            sigma = sigma / 2
        return out if out is not None else coarse_to_fine(self.space, eps, start, self.sigma, 0, 0, cfg.n_keep, self.rng)

    def step(self, image: np.ndarray, depth: np.ndarray | None) -> BodyEstimate:
        """Track one frame: ``image`` BGR or grey, ``depth`` (H, W) metres (0 = none)."""
        grey = cv2.GaussianBlur(to_grey(image), (0, 0), self.config.smooth_px)
        cost = self.make_cost(grey, depth)
        residuals = lambda X: cost.residuals(self.space.transforms(X))
        eps = lambda X: cost.epsilon(self.space.transforms(X))
        kept = self._pf(eps, self.kept)
        res = levenberg_marquardt(self.space, residuals, kept.states, self.config.lm_iterations)
        self.state = representative_pose(res.states, eps, self.sigma * np.r_[[self.space.length] * 3, [1.0] * 11])
        self.kept = res.states
        self.noise.observe(cost, self.space.transforms(self.state[None]))
        return BodyEstimate(self.state.copy(), float(eps(self.state[None])[0]) / cost.size, cost.size)
