"""Shared fixtures of the pose tests: a synthetic RGB-D face sequence and depth noise."""

import numpy as np
import pytest

from worldtrack.pose.measures import rotation_error_deg
from worldtrack.pose.tracker import RigidTracker, TrackerConfig
from worldtrack.synth.faces import face_model, face_sequence, make_face


@pytest.fixture(scope="session")
def rgbd_face():
    """Face 3, Sim1 motion, sequence seed 5, 10 frames: (face, sequence, frames)."""
    face = make_face(3)
    seq = face_sequence(face, "sim1", seed=5, n_frames=10)
    return face, seq, list(seq.frames())


@pytest.fixture(scope="session")
def noisy():
    """``noisy(depth, sigma_m, seed)``: Gaussian noise of ``sigma_m`` metres added where depth is measured."""
    def add(depth: np.ndarray, sigma_m: float, seed: int) -> np.ndarray:
        rng = np.random.default_rng(seed)
        return np.where(depth > 0, depth + rng.normal(0, sigma_m, depth.shape), 0).astype(np.float32)
    return add


@pytest.fixture(scope="session")
def track_rgbd_face(rgbd_face, noisy):
    """``track(mode, sigma_m)``: the rigid colour+depth tracker with ``depth_weight=mode`` over
    :func:`rgbd_face` with ``sigma_m`` depth noise → (mean rotation error in degrees, its λ source
    at the end). Each setting runs once per session."""
    face, seq, frames = rgbd_face
    done = {}

    def track(mode: str, sigma: float):
        if (mode, sigma) not in done:
            tr = RigidTracker(face_model(face), seq.intr, frames[0].R, frames[0].t,
                              TrackerConfig(depth_weight=mode, seed=1), cost="colour-depth")
            e = [rotation_error_deg(f.R, tr.step(f.image, noisy(f.depth, sigma, k)).R) for k, f in enumerate(frames[1:])]
            done[mode, sigma] = float(np.mean(e)), tr.noise
        return done[mode, sigma]
    return track
