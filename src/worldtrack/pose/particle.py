"""The particle filter with coarse-to-fine stages, and the representative pose (seed 003, §2.3–2.4, §5.1).

From the ``n_keep`` (~10) candidates kept at t−1, noise makes ``n_candidates`` (~1000) poses; the
``n_keep`` with the lowest cost are kept (§2.3). Coarse-to-fine (§2.4): the step is repeated with
the noise halved at each stage, ``σ_s = σ_(s−1) / 2`` (PF1, PF2, PF3 = 1, 2, 3 stages). The kept
candidates then go to LM (:mod:`worldtrack.pose.lm`).

The frame's pose is a cost-weighted mean of the kept candidates (§5.1): weight
``w_k ∝ exp(−(ε_k − min ε))`` — ε read as a negative log-likelihood — translations averaged
linearly and rotations by the weighted quaternion mean (the rotation that maximises
``Σ w_k (q_k·q)²``, :meth:`scipy.spatial.transform.Rotation.mean`), a proper rotation.
"""

from __future__ import annotations

from typing import Callable, NamedTuple

import numpy as np
from scipy.spatial.transform import Rotation

from worldtrack.pose.lm import PoseSpace


class Kept(NamedTuple):
    """Candidates kept by a stage: ``states`` (n, S) and their ``cost`` (n,), best first."""

    states: np.ndarray
    cost: np.ndarray


def pf_stage(space: PoseSpace, cost: Callable[[np.ndarray], np.ndarray], kept: np.ndarray, sigma: np.ndarray,
             n_candidates: int, n_keep: int, rng: np.random.Generator) -> Kept:
    """One stage: ``n_candidates`` noisy copies of the kept states (plus the kept states
    themselves), evaluated in one call of ``cost`` (states → (K,) ε); the best ``n_keep`` returned."""
    per = max(1, int(n_candidates) // len(kept))
    noise = rng.normal(size=(len(kept) * per, space.dim)) * np.asarray(sigma)[None]
    cand = np.concatenate([kept, space.retract(np.repeat(kept, per, axis=0), noise)])
    eps = cost(cand)
    best = np.argsort(eps, kind="stable")[:n_keep]
    return Kept(cand[best], eps[best])


def coarse_to_fine(space: PoseSpace, cost: Callable[[np.ndarray], np.ndarray], kept: np.ndarray,
                   sigma: np.ndarray, stages: int, n_candidates: int, n_keep: int,
                   rng: np.random.Generator) -> Kept:
    """``stages`` PF stages, σ halved after each (§2.4). ``stages = 0`` only evaluates ``kept``."""
    if stages <= 0:
        eps = cost(kept)
        order = np.argsort(eps, kind="stable")
        return Kept(kept[order], eps[order])
    s = np.asarray(sigma, float)
    out = None
    for _ in range(int(stages)):
        out = pf_stage(space, cost, kept if out is None else out.states, s, n_candidates, n_keep, rng)
        s = s / 2.0
    return out


def candidate_weights(cost: np.ndarray) -> np.ndarray:
    """Normalised weights ``w_k ∝ exp(−(ε_k − min ε))`` of kept candidates."""
    c = np.asarray(cost, float)
    w = np.exp(-(c - c.min()))
    return w / w.sum()


def mean_rotation(R: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Weighted mean (3, 3) of rotations (K, 3, 3): the quaternion (Markley) mean."""
    return Rotation.from_matrix(np.asarray(R, float)).mean(weights=np.asarray(weights, float)).as_matrix()
