"""Joint angles of the articulated people of :mod:`worldtrack.synth.bodies`: the arm joints' rotations,
:class:`JointAngles` (one row per person), and :func:`posed`, a walking gait (arm and leg swing with
the stride, sitting) from a track's place, heading, gait phase and amplitude.

The joints and their conventions are described in :mod:`worldtrack.synth.bodies`.

>>> import numpy as np
>>> bool(np.allclose(limb_rotation(0.0, 0.0), np.eye(3)))
True
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from worldtrack.geometry.rotation import rot_x, rot_y, rot_z


def limb_rotation(rz: ArrayLike, ry: ArrayLike) -> np.ndarray:
    """Seed 003's 2-DoF joint ``Rz(rz)·Ry(ry)`` as rotation matrices (..., 3, 3)."""
    return rot_z(rz) @ rot_y(ry)


# Limb frames of the arms in the torso frame (columns: limb x, y, z): x points sideways out.
ARM_FRAMES = np.stack([rot_z(np.pi / 2), rot_z(-np.pi / 2)])  # left, right
ARM_SIDES = np.array([1.0, -1.0])  # left, right: sign of the body y axis


def arm_swing_rotation(swing: ArrayLike, abduction: ArrayLike, side: int) -> np.ndarray:
    """Shoulder rotation ``J_sh`` (..., 3, 3) of an arm hanging down, swung forward by ``swing``.

    ``abduction`` (radians) lifts the arm sideways away from the body.
    """
    s = ARM_SIDES[side]
    G = rot_y(-np.asarray(swing, float)) @ rot_x(-s * (np.pi / 2 - np.asarray(abduction, float)))
    F = ARM_FRAMES[side]
    return F.T @ G @ F


def elbow_flex_rotation(flex: ArrayLike, side: int) -> np.ndarray:
    """Elbow rotation ``J_el`` bending the forearm forward by ``flex`` radians (for a hanging arm)."""
    return rot_z(-ARM_SIDES[side] * np.asarray(flex, float))


@dataclass
class JointAngles:
    """Pose of N people (all arrays have N rows). Angles in radians, lengths in metres.

    Attributes
    ----------
    xy : (N, 2) ground point; yaw : (N,) heading
    pelvis_twist : (N,) rotation of the pelvis about z
    torso : (N, 3) (rz, ry, rx) relative to the body frame; torso_offset : (N, 3) body-frame shift
    head : (N, 3) (rz, ry, rx) relative to the torso
    shoulder, elbow : (N, 2, 3, 3) joint rotations (left, right)
    hip : (N, 2, 2) (flexion, abduction); knee : (N, 2) flexion
    grounded : (N,) bool — shift the body so the lower ankle is at standing ankle height
    """

    xy: np.ndarray
    yaw: np.ndarray
    pelvis_twist: np.ndarray
    torso: np.ndarray
    torso_offset: np.ndarray
    head: np.ndarray
    shoulder: np.ndarray
    elbow: np.ndarray
    hip: np.ndarray
    knee: np.ndarray
    grounded: np.ndarray

    @classmethod
    def neutral(cls, xy: ArrayLike, yaw: ArrayLike) -> "JointAngles":
        """Standing upright, arms hanging slightly away from the body, elbows slightly bent."""
        xy = np.atleast_2d(np.asarray(xy, dtype=float))
        n = len(xy)
        yaw = np.broadcast_to(np.asarray(yaw, dtype=float), (n,)).copy()
        sh = np.stack([arm_swing_rotation(np.zeros(n), np.full(n, 0.12), k) for k in (0, 1)], axis=1)
        el = np.stack([elbow_flex_rotation(np.full(n, 0.15), k) for k in (0, 1)], axis=1)
        return cls(xy.copy(), yaw, np.zeros(n), np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3)),
                   sh, el, np.zeros((n, 2, 2)), np.zeros((n, 2)), np.ones(n, dtype=bool))

    def __len__(self) -> int:
        return len(self.xy)


def gait_amplitude(speed: ArrayLike) -> np.ndarray:
    """Relative swing amplitude of the limbs at ground speed (m/s): 0 standing, 1 at 1.3 m/s."""
    return np.clip(np.asarray(speed, dtype=float) / 1.3, 0.0, 1.2)


def stride_length(height: ArrayLike, speed: ArrayLike) -> np.ndarray:
    """Length (m) of a full gait cycle (two steps): 0.83·H at 1.3 m/s, shorter when slower."""
    v = np.clip(np.asarray(speed, dtype=float) / 1.3, 0.15, 1.3)
    return 0.83 * np.asarray(height, dtype=float) * np.sqrt(v)


def posed(xy: ArrayLike, yaw: ArrayLike, phase: ArrayLike, amplitude: ArrayLike, sit: ArrayLike) -> JointAngles:
    """Joint angles for walking (gait ``phase``, radians; ``amplitude`` from :func:`gait_amplitude`)
    blended with sitting (``sit`` = 0 standing … 1 seated). Vectorised over N people.

    A standing person (amplitude 0) has no limb swing at any phase.
    """
    ja = JointAngles.neutral(xy, yaw)
    n = len(ja)
    ph = np.broadcast_to(np.asarray(phase, dtype=float), (n,))
    a = np.broadcast_to(np.asarray(amplitude, dtype=float), (n,))
    s = np.clip(np.broadcast_to(np.asarray(sit, dtype=float), (n,)), 0.0, 1.0)
    walk = 1.0 - s
    for side, ph_side in ((0, ph), (1, ph + np.pi)):
        # Hip swings ±0.42 rad at normal speed; knee flexes in swing (hip moving forward, cos > 0).
        hip = 0.42 * a * np.sin(ph_side)
        knee = a * (0.08 + 0.95 * np.maximum(0.0, np.cos(ph_side)) ** 2)
        ja.hip[:, side, 0] = walk * hip + s * (np.pi / 2)
        ja.hip[:, side, 1] = 0.03 + 0.05 * s
        ja.knee[:, side] = walk * knee + s * (np.pi / 2)
        # Arms swing against the same-side leg; sitting puts the hands on the thighs.
        swing = walk * (-0.35 * a * np.sin(ph_side)) + s * 0.35
        ja.shoulder[:, side] = arm_swing_rotation(swing, np.full(n, 0.12), side)
        ja.elbow[:, side] = elbow_flex_rotation(0.15 + walk * 0.25 * a + s * 0.9, side)
    ja.pelvis_twist = walk * 0.06 * a * np.sin(ph)
    ja.torso[:, 0] = -walk * 0.05 * a * np.sin(ph)
    ja.torso[:, 1] = walk * 0.05 * a + 0.45 * np.sin(np.pi * s) + 0.05 * s
    return ja
