"""Rigid pose tracking, one frame at a time: template → particle filter → LM → weighted mean.

For each frame (§2–3): draw the model at the previous pose and keep its sparse template
(:mod:`~worldtrack.pose.render`); spread the kept candidates by noise and keep the best through
``stages`` coarse-to-fine stages (:mod:`~worldtrack.pose.particle`); refine the kept candidates by
``lm_iterations`` of batched Levenberg–Marquardt (:mod:`~worldtrack.pose.lm`); report their
cost-weighted mean pose. ``PF1LM10`` is ``TrackerConfig(stages=1, lm_iterations=10)``.

Two costs: ``"eigen"`` — the face's illumination eigen-template (§3.1, RGB) with the analytic
Jacobian of eq. 10; ``"colour-depth"`` — brightness-normalised colour and depth mixed by λ
(eqs. 16–19, RGB-D), as for the body and the real cube.

>>> from worldtrack.synth.faces import make_face, face_model, face_sequence
>>> face = make_face(0)
>>> seq = face_sequence(face, "sim1", seed=1, n_frames=3, size=(320, 240))
>>> frames = list(seq.frames())
>>> tr = RigidTracker(face_model(face), seq.intr, frames[0].R, frames[0].t, TrackerConfig(n_candidates=200))
>>> est = [tr.step(f.image) for f in frames[1:]]
>>> bool(rotation_error_deg(frames[-1].R, est[-1].R) < 2.0)
True
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

import cv2
import numpy as np

from worldtrack.errors import InputError
from worldtrack.pose.cost import DEPTH_SAMPLING, ColourDepthCost, EigenTemplateCost, SparseTemplate
from worldtrack.pose.lm import levenberg_marquardt
from worldtrack.pose.measures import rotation_error_deg  # noqa: F401  (doctest)
from worldtrack.pose.noise_weight import depth_share
from worldtrack.pose.models import PointModel, increment_between, rigid_state, state_pose
from worldtrack.pose.particle import candidate_weights, coarse_to_fine, mean_rotation
from worldtrack.pose.render import Intrinsics, posed_points
from worldtrack.pose.template import sparse_template_pixels
from worldtrack.pose.rigid import RigidSpace, face_normal_equations, gradient_images, shading_basis


@dataclass(frozen=True)
class TrackerConfig:
    """Settings of the rigid tracker (defaults: the paper's Tables 1–2 and PF1LM10).

    sigma_mm : first-stage σ of tx, ty, tz (mm); sigma_deg : of rotations about x, y, z (degrees)
    c : Geman–McClure scale — grey levels for ``eigen``; None = 0.5/N for ``colour-depth``
    c_depth_mm : depth scale c′ (mm); lam : λ, share of the depth term
    depth_weight : "fixed" — λ = ``lam`` (the paper's); "noise" — λ from the colour and depth
        differences' measured spreads, inverse-variance (:mod:`~worldtrack.pose.noise_weight`;
        ``lam`` until a frame is accepted, then the median spread over the last ``noise_window`` frames);
        "kernel" — λ from each term's Geman–McClure curvature over its gradient's variance, measured
        on the same differences (:func:`~worldtrack.pose.noise_weight.kernel_weight`); "sandwich" — the
        kernel weight over the pose score's design effect (correlated differences), each term
        measured at its own fit (:mod:`~worldtrack.pose.sandwich_weight`)
    jacobian : "analytic" (eq. 10, eigen cost only) or "numeric" (central differences, eq. 20)
    pf_points : rank the particle filter's candidates on only the strongest ``pf_points`` template
        points (LM then uses them all; worldtrack's default 256, for speed); None: all, as the paper
    motion : "velocity" — the kept candidates are first moved by the last frame's change of pose
        (constant velocity; worldtrack's addition); "none" — the paper's random walk
    smooth_px : Gaussian σ (pixels) applied to the input and to the drawn template alike
    camera_blur_px : the camera's own blur (σ, pixels), added to the drawn template's smoothing
        (not for appearance read from an image, which holds it already)
    shading_vectors : eigenvectors Φ of the eigen-template besides the mean v̄
    depth_sampling : "bilinear" (on one surface) or "nearest" pixel, for ``colour-depth``
    window_margin_px : the frame is cut to the template's box at the kept candidates' starting poses
        plus this margin (pixels) before it is smoothed and sampled — the same cost (a point
        beyond it scores as one outside the image), cheaper, and its pixels stay in cache;
        None: the whole frame
    lm_tol : a kept candidate stops its LM once a step lowers ε by less than this (ε is a negative
        log-likelihood in the candidates' weights exp(−ε): 1e-3 moves a weight by 0.1 %) or a step
        with damping above JᵀJ's scale is refused (face cost only; 0: always ``lm_iterations``, as
        the paper)
    edge_points : fill the template up to ``n_template`` with crests of the drawing's gradient
        magnitude after the extrema (worldtrack's addition; False: extrema only, as the paper)
    select_px : Gaussian σ (pixels) of the drawing whose extrema and crests are picked; None: the
        drawing the template's values are read from (σ of ``smooth_px`` and ``camera_blur_px``), so a
        point is an extremum of what is matched
    """

    stages: int = 1
    lm_iterations: int = 10
    n_candidates: int = 1000
    n_keep: int = 10
    n_template: int = 1024
    n_depth: int = 128
    sigma_mm: tuple = (5.0, 5.0, 10.0)
    sigma_deg: tuple = (5.0, 5.0, 2.5)
    c: float | None = None
    c_depth_mm: float = 5.0
    lam: float = 0.9
    depth_weight: str = "fixed"
    noise_window: int = 10
    jacobian: str = "analytic"
    smooth_px: float = 1.0
    camera_blur_px: float = 0.6
    shading_vectors: int = 9
    motion: str = "velocity"
    pf_points: int | None = 256
    depth_sampling: str = "bilinear"
    edge_points: bool = True
    window_margin_px: int | None = 48
    lm_tol: float = 1e-3
    select_px: float | None = None
    seed: int = 0


class PoseEstimate(NamedTuple):
    """A frame's result: ``R`` (3, 3), ``t`` (3,) object → camera (m); ``cost`` = mean ρ over the
    template at that pose (0 perfect, 1 nothing matches); ``n_template`` points used."""

    R: np.ndarray
    t: np.ndarray
    cost: float
    n_template: int


def to_grey(image: np.ndarray) -> np.ndarray:
    """(H, W) float32 grey levels of a BGR (or already grey) image."""
    img = np.asarray(image)
    if img.ndim == 3:
        img = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY) if img.dtype == np.uint8 else img @ np.float32([0.114, 0.587, 0.299])
    return img.astype(np.float32)


@dataclass
class RigidTracker:
    """Track one rigid model (see the module docstring).

    Parameters
    ----------
    model : PointModel with known albedo; intr : Intrinsics of the input frames
    R0, t0 : the pose at the first frame (object → camera, m)
    config : TrackerConfig; cost : "eigen" (RGB) or "colour-depth" (RGB-D)
    """

    model: PointModel
    intr: Intrinsics
    R0: np.ndarray
    t0: np.ndarray
    config: TrackerConfig = field(default_factory=TrackerConfig)
    cost: str = "eigen"

    def __post_init__(self):
        if self.config.motion not in ("velocity", "none"):
            raise InputError(f"motion: expected velocity or none, got {self.config.motion!r}")
        if self.cost not in ("eigen", "colour-depth"):
            raise InputError(f"cost: expected eigen or colour-depth, got {self.cost!r}")
        self.noise = depth_share(self.config.depth_weight, self.config.lam, self.config.noise_window)
        self.space = RigidSpace(length=max(self.model.radius, 1e-3))
        self.sigma = self.space.increment_sigma(self.config.sigma_mm, self.config.sigma_deg)
        self.basis = None
        if self.cost == "eigen":                               # over the textured points (an occluder's do not count)
            known = np.isfinite(self.model.albedo)
            self.basis = np.full((len(known), self.config.shading_vectors + 1), np.nan)
            self.basis[known] = shading_basis(self.model.normals[known], n_vectors=self.config.shading_vectors)
        self.rng = np.random.default_rng(self.config.seed)
        self.reset(self.R0, self.t0)

    def reset(self, R: np.ndarray, t: np.ndarray) -> None:
        """(Re-)initialise at a known pose."""
        self.state = rigid_state(np.asarray(R, float), np.asarray(t, float))
        self.kept = self.state[None].copy()
        self.velocity = np.zeros(6)
        self.depth_bias = getattr(self, "depth_bias", np.zeros(3))

    def learn_depth_offset(self, depth: np.ndarray, tilt: bool = True) -> np.ndarray:
        """Learn the depth sensor's bias at the object on a frame taken at the current (known) pose.

        ``Ẑ − Z`` (measured minus model depth, m) over the visible model points is fitted as
        ``a + b·x + c·y`` of the normalised image coordinates ``x = (u − cx)/fx``, ``y = (v − cy)/fy``
        (least squares over the points within 20 mm of the median — the silhouette's background left
        out); later depth readings are corrected by it. A stereo RGB-D camera's error is smooth over
        the image but not constant: the real ViSP camera reads the cube 4 mm too far and its depth
        is tilted by 1–2° against the colour geometry (the AprilTag board shows the same tilt), which
        pulled the colour+depth tracker's rotation off by 2.4°. ``tilt=False``: the offset ``a``
        alone (the median). Returns ``(a, b, c)`` (m).

        >>> from worldtrack.pose.models import PointModel
        >>> from worldtrack.pose.render import Intrinsics
        >>> bump = lambda x, y: 0.004 * np.sin(60 * x) * np.cos(60 * y)            # a bumpy 12 cm patch
        >>> g = np.mgrid[-0.06:0.06:0.001, -0.06:0.06:0.001].reshape(2, -1).T
        >>> pts = np.c_[g, bump(g[:, 0], g[:, 1])]; nrm = np.tile([0, 0, -1.0], (len(g), 1))
        >>> albedo = (100 + 50 * np.sin(90 * g[:, 0]) * np.cos(70 * g[:, 1])).astype(np.float32)
        >>> intr = Intrinsics(500.0, 500.0, 160.0, 120.0, 320, 240)
        >>> tr = RigidTracker(PointModel(pts, nrm, albedo, 0.001), intr, np.eye(3), np.array([0, 0, 0.5]),
        ...                   cost="colour-depth")
        >>> x, y = (np.arange(320) - 160) / 500, (np.arange(240) - 120) / 500
        >>> depth = 0.5 + bump(0.5 * x[None, :], 0.5 * y[:, None])               # what a true camera reads
        >>> depth = (depth + 0.004 + 0.01 * x[None, :]).astype(np.float32)       # 4 mm far, tilted
        >>> np.round(1000 * tr.learn_depth_offset(depth)).tolist()               # a, b, c (mm)
        [4.0, 10.0, 0.0]
        """
        from worldtrack.pose.cost import NEAREST_POSITIVE, project_sample
        from worldtrack.pose.render import splat

        R, t = state_pose(self.state)
        drawn = splat(posed_points(self.model.points, self.model.normals, R, t), self.intr)   # z-buffered
        inner = cv2.erode((drawn.index >= 0).astype(np.uint8), np.ones((3, 3), np.uint8), iterations=2).astype(bool)
        pts = self.model.points[np.unique(drawn.index[inner])]           # visible, off the silhouette
        T = self.space.transforms(self.state[None])
        z_hat, z = project_sample(np.asarray(depth, np.float32), self.intr, T,
                                  SparseTemplate(pts, np.zeros(len(pts), int), np.zeros(len(pts))), NEAREST_POSITIVE)
        d = z_hat[0, 0].astype(float) - z[0]
        xyz = pts @ T[0, 0, :, :3].T + T[0, 0, :, 3]
        ok = np.isfinite(d)
        self.depth_bias = np.zeros(3)
        if ok.any():
            self.depth_bias[0] = float(np.median(d[ok]))
            ok &= np.abs(d - self.depth_bias[0]) < 0.02
            if tilt and ok.sum() >= 10:
                A = np.c_[np.ones(ok.sum()), xyz[ok, 0] / xyz[ok, 2], xyz[ok, 1] / xyz[ok, 2]]
                self.depth_bias = np.linalg.lstsq(A, d[ok], rcond=None)[0]
        return self.depth_bias.copy()

    def corrected_depth(self, depth: np.ndarray, intr: Intrinsics) -> np.ndarray:
        """``depth`` (H, W, m; 0 = none) of a frame (or a window with intrinsics ``intr``) minus the
        learnt bias (:meth:`learn_depth_offset`)."""
        a, b, c = self.depth_bias
        H, W = depth.shape
        x = ((np.arange(W) - intr.cx) / intr.fx).astype(np.float32)
        y = ((np.arange(H) - intr.cy) / intr.fy).astype(np.float32)
        bias = np.float32(a) + np.float32(b) * x[None, :] + np.float32(c) * y[:, None]
        return np.where(depth > 0, depth - bias, 0).astype(np.float32)

    def template(self, state: np.ndarray):
        """The sparse template (:class:`~worldtrack.pose.template.TemplatePixels`) at ``state``."""
        R, t = state_pose(state)
        xyz = posed_points(self.model.points, self.model.normals, R, t)        # back faces culled
        albedo = self.model.albedo
        n_depth = self.config.n_depth if self.cost == "colour-depth" else 0
        sigma = float(np.hypot(self.config.smooth_px, 0.0 if self.model.from_image else self.config.camera_blur_px))
        select = sigma if self.config.select_px is None else self.config.select_px
        return sparse_template_pixels(albedo, xyz, self.intr, self.config.n_template, n_depth, sigma=sigma,
                                      select_sigma=select, edge_fill=self.config.edge_points)

    def window(self, tp, states: np.ndarray) -> tuple[Intrinsics, slice, slice]:
        """The part of the frame the candidates ``states`` can read: the template's box under them
        plus ``window_margin_px``; its intrinsics and the (rows, cols) slices of the frame."""
        intr, margin = self.intr, self.config.window_margin_px
        full = intr, slice(0, intr.height), slice(0, intr.width)
        idx = np.concatenate([tp.colour, tp.depth])
        if margin is None or len(idx) == 0:
            return full
        R, t = state_pose(states)
        xyz = self.model.points[idx] @ np.swapaxes(R, 1, 2) + t[:, None]
        z = xyz[..., 2]
        if not (z > 1e-6).all():
            return full
        u, v = intr.fx * xyz[..., 0] / z + intr.cx, intr.fy * xyz[..., 1] / z + intr.cy
        u0, v0 = max(int(np.floor(u.min())) - margin, 0), max(int(np.floor(v.min())) - margin, 0)
        u1, v1 = min(int(np.ceil(u.max())) + margin + 1, intr.width), min(int(np.ceil(v.max())) + margin + 1, intr.height)
        if u1 - u0 < 4 or v1 - v0 < 4:
            return full
        return (Intrinsics(intr.fx, intr.fy, intr.cx - u0, intr.cy - v0, u1 - u0, v1 - v0),
                slice(v0, v1), slice(u0, u1))

    def make_cost(self, grey: np.ndarray, depth: np.ndarray | None, state: np.ndarray, tp=None,
                  intr: Intrinsics | None = None):
        """The cost object for a (smoothed) grey frame, with the template taken at ``state`` (or ``tp``);
        ``intr`` of the frame (default: the tracker's — pass a window's for a cut frame)."""
        tp = self.template(state) if tp is None else tp
        intr = self.intr if intr is None else intr
        m = self.model
        value = tp.value
        colour = SparseTemplate(m.points[tp.colour], np.zeros(len(tp.colour), int), value)
        if self.cost == "eigen":
            basis = value[:, None] * self.basis[tp.colour]             # Φ̃ = diag(a)·Ψ
            return EigenTemplateCost(colour, basis, grey, intr, 10.0 if self.config.c is None else self.config.c)
        R, t = state_pose(state)
        zd = (m.points[tp.depth] @ R.T + t)[:, 2]
        dt = SparseTemplate(m.points[tp.depth], np.zeros(len(tp.depth), int), zd)
        if depth is not None and self.depth_bias.any():
            depth = self.corrected_depth(np.asarray(depth), intr)
        return ColourDepthCost(colour, dt, grey, depth, intr, self.config.c, self.config.c_depth_mm / 1000,
                               self.noise.lam, DEPTH_SAMPLING[self.config.depth_sampling])

    def _lm(self, cost, states: np.ndarray, iterations: int):
        """Batched LM of the kept candidates on one cost (compiled normal equations for the face)."""
        residuals = lambda X: cost.residuals(self.space.transforms(X))
        eps = lambda X: cost.epsilon(self.space.transforms(X))
        normal = None
        if self.cost == "eigen" and self.config.jacobian == "analytic":
            grads = gradient_images(cost.images[0])
            normal = lambda X: face_normal_equations(cost, self.space, grads, X)
        return levenberg_marquardt(self.space, residuals, states, iterations, normal_equations=normal, epsilon=eps,
                                   tol=self.config.lm_tol)

    def step(self, image: np.ndarray, depth: np.ndarray | None = None) -> PoseEstimate:
        """Track one frame: ``image`` BGR uint8 or grey; ``depth`` (H, W) metres, 0 = none."""
        cfg = self.config
        tp = self.template(self.state)
        start = self.space.retract(self.kept, np.broadcast_to(self.velocity, (len(self.kept), 6)))
        intr, rows, cols = self.window(tp, np.vstack([start, self.state[None]]))
        grey = cv2.GaussianBlur(to_grey(np.asarray(image)[rows, cols]), (0, 0), cfg.smooth_px)
        cost = self.make_cost(grey, None if depth is None else np.asarray(depth)[rows, cols], self.state, tp, intr)
        if cost.size == 0:
            raise InputError("the model shows no textured point at the current pose (is it in view?)")
        eps = lambda X: cost.epsilon(self.space.transforms(X))
        pf_cost = cost.subset(cfg.pf_points) if cfg.pf_points else cost
        pf_eps = lambda X: pf_cost.epsilon(self.space.transforms(X))
        kept = coarse_to_fine(self.space, pf_eps, start, self.sigma, cfg.stages, cfg.n_candidates, cfg.n_keep, self.rng)
        res = self._lm(cost, kept.states, cfg.lm_iterations)
        w = candidate_weights(res.cost)
        R, t = state_pose(res.states)
        Rm, tm = mean_rotation(R, w), (w[:, None] * t).sum(0)
        new_state = rigid_state(Rm, tm)
        if cfg.motion == "velocity":
            self.velocity = increment_between(self.state, new_state, self.space.length)
        self.state = new_state
        self.kept = res.states
        if self.cost == "colour-depth":
            self.noise.observe(cost, self.space.transforms(self.state[None]))
        mean_cost = float(eps(self.state[None])[0]) / cost.size
        return PoseEstimate(Rm, tm, mean_cost, cost.size)
