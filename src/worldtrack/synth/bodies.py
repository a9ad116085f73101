"""Articulated people: body shapes drawn per person, joint angles, and the parts they make.

A person is 18 analytic parts — ellipsoids and capsules — posed by forward kinematics::

    head, nose, neck, shoulders, torso, pelvis,
    upper arm, forearm, hand      (left, right)
    thigh, shank, foot            (left, right)

Body frame (per person): origin on the floor below the pelvis centre, x forward (the heading),
y to the person's left, z up. World = ``Rz(yaw)·body + (x, y, 0)``. The person's **ground point**
— the ``x, y`` that ground truth reports and a tracker should estimate — is that origin: the
pelvis centre projected on the floor. Standing, it lies midway between the ankles; walking, the
feet swing symmetrically about it; sitting, the feet are about a thigh length in front of it.

Proportions follow the usual anthropometric fractions of the body height ``H`` (ankle 0.039 H,
knee 0.285 H, hip 0.530 H, shoulder 0.818 H, top of head 1.0 H). The shoulder width ``W`` is the
outer breadth across the upper arms at shoulder height, so a standing person is exactly ``W``
wide there.

Joints
------
* legs: hip flexion (forward +) and abduction, knee flexion, in the body frame;
* torso: ``Rz·Ry·Rx`` Euler angles (rz, ry, rx) relative to the body frame, about the lumbar joint
  at 0.60 H (ry > 0 leans forward), plus an optional translation of that joint (seed 003's 6-DoF
  torso);
* head: ``Rz·Ry·Rx`` relative to the torso about the top of the neck (ry > 0 looks down);
* arms: each arm has a limb frame whose x axis points along the limb and, at rest, sideways out of
  the shoulder (z up). The shoulder is a rotation ``J_sh`` of that frame and the elbow a rotation
  ``J_el`` of the upper-arm frame; :func:`~worldtrack.synth.joints.limb_rotation` builds seed 003's 2-DoF ``Rz·Ry`` joints
  (rz swings in the horizontal plane, ry > 0 lowers the limb). The two arm frames are rotated
  copies, not mirror images: rz > 0 swings the left arm backward and the right arm forward.

The body is *grounded* by default: after posing, it is shifted vertically so that the lower ankle
sits at its standing height (so the stance foot stays on the floor while walking and the pelvis
drops when sitting).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike

from worldtrack.errors import InputError
from worldtrack.geometry.rotation import euler_zyx, rot_x, rot_y, rot_z
from worldtrack.synth.joints import ARM_FRAMES, ARM_SIDES, JointAngles

# Part indices within one person.
PART_NAMES = ("head", "nose", "neck", "shoulders", "torso", "pelvis",
              "l_upper_arm", "l_forearm", "l_hand", "r_upper_arm", "r_forearm", "r_hand",
              "l_thigh", "l_shank", "l_foot", "r_thigh", "r_shank", "r_foot")
PARTS_PER_PERSON = len(PART_NAMES)
HEAD, NOSE, NECK, SHOULDERS, TORSO, PELVIS = range(6)
L_UPPER_ARM, L_FOREARM, L_HAND, R_UPPER_ARM, R_FOREARM, R_HAND = range(6, 12)
L_THIGH, L_SHANK, L_FOOT, R_THIGH, R_SHANK, R_FOOT = range(12, 18)

ELLIPSOID, CAPSULE = 0, 1
_KIND = np.array([ELLIPSOID, ELLIPSOID, CAPSULE, CAPSULE, ELLIPSOID, ELLIPSOID,
                  CAPSULE, CAPSULE, ELLIPSOID, CAPSULE, CAPSULE, ELLIPSOID,
                  CAPSULE, CAPSULE, ELLIPSOID, CAPSULE, CAPSULE, ELLIPSOID], dtype=np.int8)

# Texture codes used by the shader (render.py).
TEX_PLAIN, TEX_HEAD, TEX_STRIPES = 0, 1, 2

HEIGHT_RANGE = (1.50, 1.95)
SHOULDER_RANGE = (0.35, 0.55)

# Fractions of the body height H.
ANKLE_H, KNEE_H, HIP_H = 0.039, 0.285, 0.530
LUMBAR_H, SHOULDER_H, NECK_BASE_H, NECK_TOP_H = 0.60, 0.818, 0.83, 0.88
UPPER_ARM_L, FOREARM_L = 0.186, 0.146

# Skin tones and clothing, BGR albedo in display units (0–255 under unit light).
SKIN_TONES = np.array([[178, 196, 235], [150, 180, 225], [120, 150, 200], [90, 120, 170],
                       [70, 95, 140], [50, 68, 100]], dtype=float)
HAIR_COLOURS = np.array([[20, 22, 25], [30, 45, 70], [40, 70, 110], [90, 140, 180],
                         [150, 150, 150], [35, 35, 40]], dtype=float)
CLOTHING = np.array([
    [30, 30, 32], [60, 40, 30], [120, 70, 30], [40, 40, 120], [40, 120, 40], [200, 200, 200],
    [230, 230, 230], [90, 90, 95], [140, 140, 140], [60, 100, 150], [40, 80, 170], [150, 60, 60],
    [110, 150, 170], [170, 120, 90], [70, 50, 110], [50, 150, 200], [25, 25, 80], [90, 70, 60],
], dtype=float)
SHOES = np.array([[25, 25, 25], [40, 50, 70], [200, 200, 200], [60, 60, 60]], dtype=float)


@dataclass(frozen=True)
class BodyShape:
    """One person's build and clothes, fixed for the whole sequence.

    Parameters
    ----------
    height : float, metres — standing body height (floor to top of head), 1.50–1.95 by default
    shoulder_width : float, metres — outer breadth across the upper arms, 0.35–0.55 by default
    girth : float — limb and trunk thickness relative to an average build (≈ 0.85–1.2)
    skin, hair, top, bottom, shoes : (3,) BGR albedo, 0–255
    short_sleeves, shorts, stripes : bool
    hair_style : int — 0 bald, 1 short, 2 long
    """

    height: float
    shoulder_width: float
    girth: float = 1.0
    skin: tuple = (150.0, 180.0, 225.0)
    hair: tuple = (30.0, 45.0, 70.0)
    top: tuple = (120.0, 70.0, 30.0)
    bottom: tuple = (40.0, 40.0, 50.0)
    shoes: tuple = (25.0, 25.0, 25.0)
    short_sleeves: bool = False
    shorts: bool = False
    stripes: bool = False
    hair_style: int = 1


def draw_body_shape(rng: np.random.Generator, height: float | None = None, shoulder_width: float | None = None,
                    camouflage: ArrayLike | None = None, p_camouflage: float = 0.3,
                    height_range: tuple[float, float] = HEIGHT_RANGE,
                    shoulder_range: tuple[float, float] = SHOULDER_RANGE) -> BodyShape:
    """Draw a person: height ~ N(1.70, 0.10) m and shoulder width ≈ 0.245·H ± 0.03 m, both clipped.

    Parameters
    ----------
    rng : numpy.random.Generator
    height, shoulder_width : float, optional — fix instead of drawing (metres)
    camouflage : (K, 3) BGR, optional
        Background colours (floor, walls). With probability ``p_camouflage`` the top or the bottom
        is made close to one of them, so that background subtraction leaves holes in the person.
    """
    lo, hi = height_range
    H = float(np.clip(rng.normal(1.70, 0.10), lo, hi)) if height is None else float(height)
    wlo, whi = shoulder_range
    W = float(np.clip(0.245 * H + rng.normal(0.0, 0.03), wlo, whi)) if shoulder_width is None else float(shoulder_width)
    if not 0.5 < H < 2.5:
        raise InputError(f"height: expected metres in (0.5, 2.5), got {H}")
    if not 0.2 < W < 0.8:
        raise InputError(f"shoulder_width: expected metres in (0.2, 0.8), got {W}")
    girth = float(np.clip(W / (0.245 * H) * rng.uniform(0.92, 1.08), 0.8, 1.25))
    jitter = lambda c: tuple(float(v) for v in np.clip(np.asarray(c) * rng.uniform(0.85, 1.15, 3), 5, 250))
    skin = jitter(SKIN_TONES[rng.integers(len(SKIN_TONES))])
    top = jitter(CLOTHING[rng.integers(len(CLOTHING))])
    bottom = jitter(CLOTHING[rng.choice([0, 1, 3, 7, 8, 9, 13, 16, 17])])
    if camouflage is not None and len(camouflage) and rng.random() < p_camouflage:
        bg = np.asarray(camouflage, dtype=float)[rng.integers(len(camouflage))]
        near = tuple(float(v) for v in np.clip(bg * rng.uniform(0.9, 1.1) + rng.normal(0, 6, 3), 5, 250))
        if rng.random() < 0.5:
            top = near
        else:
            bottom = near
    hair_style = int(rng.choice([0, 1, 1, 1, 2, 2]))
    return BodyShape(H, W, girth, skin, jitter(HAIR_COLOURS[rng.integers(len(HAIR_COLOURS))]), top, bottom,
                     jitter(SHOES[rng.integers(len(SHOES))]), bool(rng.random() < 0.3),
                     bool(rng.random() < 0.1), bool(rng.random() < 0.2), hair_style)


# ------------------------------------------------------------------------------------ parts

@dataclass
class PartArrays:
    """Analytic parts of several people, ready for ray casting.

    Attributes
    ----------
    kind : (P,) int8 — 0 ellipsoid, 1 capsule
    centre : (P, 3) — ellipsoid centre, or capsule end point a
    end : (P, 3) — capsule end point b (= centre for ellipsoids)
    radius : (P,) — capsule radius; for an ellipsoid its largest semi-axis
    axes : (P, 3, 3) — rows: the part's local axes in world coordinates (a capsule's x runs from a to b)
    radii : (P, 3) — ellipsoid semi-axes along those rows (capsules: radius, three times)
    person : (P,) int32 — index of the owning person in this frame's list
    part : (P,) int8 — index into :data:`PART_NAMES`
    albedo : (P, 3) float32 — BGR
    texture : (P,) int8 — shader texture code
    """

    kind: np.ndarray
    centre: np.ndarray
    end: np.ndarray
    radius: np.ndarray
    axes: np.ndarray
    radii: np.ndarray
    person: np.ndarray
    part: np.ndarray
    albedo: np.ndarray
    texture: np.ndarray
    head_top: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))

    def __len__(self) -> int:
        return len(self.kind)

    def geometry(self) -> np.ndarray:
        """(P, 17) float64 rows ``[kind, a(3), b(3), r, M(9)]`` with ``M = diag(1/radii)·axes``.

        For an ellipsoid, ``M·(p − a)`` maps it to the unit sphere.
        """
        P = len(self)
        g = np.empty((P, 17))
        g[:, 0] = self.kind
        g[:, 1:4] = self.centre
        g[:, 4:7] = self.end
        g[:, 7] = self.radius
        g[:, 8:17] = (self.axes / self.radii[:, :, None]).reshape(P, 9)
        return g

    def mirrored_z(self) -> "PartArrays":
        """The parts reflected in the floor plane (Z → −Z), for floor reflections."""
        flip = np.array([1.0, 1.0, -1.0])
        return replace(self, centre=self.centre * flip, end=self.end * flip, axes=self.axes * flip,
                       head_top=self.head_top * flip)

    def subset(self, keep: np.ndarray) -> "PartArrays":
        """The parts of the people whose indices are in ``keep`` (renumbered 0…)."""
        keep = np.asarray(keep, dtype=int)
        sel = np.isin(self.person, keep)
        remap = np.full(int(self.person.max(initial=-1)) + 1, -1, dtype=np.int32)
        remap[keep] = np.arange(len(keep), dtype=np.int32)
        return PartArrays(self.kind[sel], self.centre[sel], self.end[sel], self.radius[sel], self.axes[sel],
                          self.radii[sel], remap[self.person[sel]], self.part[sel], self.albedo[sel],
                          self.texture[sel], self.head_top[keep] if len(self.head_top) else self.head_top)

    def shape_matrices(self) -> np.ndarray:
        """(P, 3, 3) ``S = axesᵀ·diag(radii²)·axes`` (the 3×3 block of the dual quadric)."""
        return np.einsum("pki,pk,pkj->pij", self.axes, self.radii ** 2, self.axes)


def _frame_from_x(x: np.ndarray, up_hint: np.ndarray) -> np.ndarray:
    """Rows (x, y, z) of right-handed frames (N, 3, 3) with x along the given vectors (N, 3) and
    y = hint × x (falling back to world Y × x where the hint is parallel to x)."""
    x = x / np.linalg.norm(x, axis=-1, keepdims=True)
    y = np.cross(up_hint, x)
    bad = np.linalg.norm(y, axis=-1) < 1e-6
    if np.any(bad):
        y[bad] = np.cross(np.array([0.0, 1.0, 0.0]), x[bad])
    y /= np.linalg.norm(y, axis=-1, keepdims=True)
    z = np.cross(x, y)
    return np.stack([x, y, z], axis=1)


def body_parts(shapes: list[BodyShape], ja: JointAngles) -> PartArrays:
    """Forward kinematics: the 18 parts of each of N people, vectorised over people.

    Parameters
    ----------
    shapes : list of N BodyShape
    ja : JointAngles with N rows

    Returns
    -------
    PartArrays with ``18·N`` parts, person-major; ``head_top`` (N, 3) is each head's highest point.
    """
    n = len(shapes)
    if n != len(ja):
        raise ValueError(f"{n} body shapes but {len(ja)} poses")
    if n == 0:
        z3 = np.zeros((0, 3))
        return PartArrays(np.zeros(0, np.int8), z3, z3, np.zeros(0), np.zeros((0, 3, 3)), z3,
                          np.zeros(0, np.int32), np.zeros(0, np.int8), np.zeros((0, 3), np.float32),
                          np.zeros(0, np.int8), z3)
    H = np.array([s.height for s in shapes])
    W = np.array([s.shoulder_width for s in shapes])
    g = np.array([s.girth for s in shapes])
    c1 = H[:, None]
    ez = np.array([0.0, 0.0, 1.0])

    # Radii and lengths (N,).
    r_ua, r_fa = 0.026 * H * g, 0.020 * H * g
    r_th, r_sh = 0.040 * H * g, 0.028 * H * g
    r_neck = 0.028 * H * g
    len_ua, len_fa = UPPER_ARM_L * H, FOREARM_L * H
    len_th, len_sk = (HIP_H - KNEE_H) * H, (KNEE_H - ANKLE_H) * H
    head_r = np.column_stack([0.054 * H, 0.044 * H, 0.065 * H])

    def v(x, y, z):
        return np.stack(np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float), np.asarray(z, float)), -1)

    # ---- pelvis and legs (body frame)
    R_pel = rot_z(ja.pelvis_twist)                                  # (N,3,3)
    pelvis_c = v(0, 0, 0.555 * H)
    parts_c = np.zeros((n, PARTS_PER_PERSON, 3))
    parts_e = np.zeros((n, PARTS_PER_PERSON, 3))
    parts_r = np.zeros((n, PARTS_PER_PERSON))
    parts_ax = np.tile(np.eye(3), (n, PARTS_PER_PERSON, 1, 1))
    parts_rad = np.ones((n, PARTS_PER_PERSON, 3))

    def ell(k, centre, R_local_to_body, radii):
        parts_c[:, k] = centre
        parts_e[:, k] = centre
        parts_ax[:, k] = np.swapaxes(R_local_to_body, -1, -2)      # rows = local axes
        parts_rad[:, k] = radii
        parts_r[:, k] = radii.max(axis=1)

    def cap(k, a, b, r):
        parts_c[:, k] = a
        parts_e[:, k] = b
        parts_r[:, k] = r
        parts_rad[:, k] = r[:, None]
        # A frame with x along the segment (for the surface texture only).
        parts_ax[:, k] = _frame_from_x(b - a, np.broadcast_to([1.0, 0.0, 0.0], a.shape).copy())

    ell(PELVIS, pelvis_c, R_pel, np.column_stack([0.062 * H * g, 0.092 * H * g, 0.068 * H]))
    ankles = np.zeros((n, 2, 3))
    for side in (0, 1):
        s = ARM_SIDES[side]
        hip_j = pelvis_c + np.einsum("nij,nj->ni", R_pel, v(0, s * 0.050 * H * g, -0.025 * H))
        flex, abd = ja.hip[:, side, 0], ja.hip[:, side, 1]
        R_th = R_pel @ rot_y(-flex) @ rot_x(s * abd)
        knee_j = hip_j + len_th[:, None] * (R_th @ -ez)
        R_sk = R_pel @ rot_y(-(flex - ja.knee[:, side])) @ rot_x(s * abd)
        ankle = knee_j + len_sk[:, None] * (R_sk @ -ez)
        ankles[:, side] = ankle
        base = (L_THIGH, R_THIGH)[side]
        cap(base, hip_j, knee_j, r_th)
        cap(base + 1, knee_j, ankle, r_sh)
        R_foot = R_pel @ rot_z(s * 0.12)
        foot_c = ankle + np.einsum("nij,nj->ni", R_foot, v(0.035 * H, 0, -ANKLE_H * H + 0.022 * H))
        ell(base + 2, foot_c, R_foot, np.column_stack([0.076 * H, 0.029 * H * g, 0.022 * H]))

    # ---- torso, neck, head
    R_tor = euler_zyx(ja.torso[:, 0], ja.torso[:, 1], ja.torso[:, 2])
    lumbar = v(0, 0, LUMBAR_H * H) + ja.torso_offset

    def at(local):
        return lumbar + np.einsum("nij,nj->ni", R_tor, local)

    ell(TORSO, at(v(0, 0, 0.11 * H)), R_tor,
        np.column_stack([0.065 * H * g, W / 2 - 0.9 * r_ua, 0.15 * H]))
    shoulder_j = np.stack([at(v(0, s * (W / 2 - r_ua), (SHOULDER_H - LUMBAR_H) * H)) for s in ARM_SIDES], axis=1)
    cap(SHOULDERS, shoulder_j[:, 0], shoulder_j[:, 1], 1.05 * r_ua)
    neck_top = at(v(0, 0, (NECK_TOP_H - LUMBAR_H) * H))
    cap(NECK, at(v(0, 0, (NECK_BASE_H - LUMBAR_H) * H)), neck_top, r_neck)
    R_head = R_tor @ euler_zyx(ja.head[:, 0], ja.head[:, 1], ja.head[:, 2])
    head_c = neck_top + np.einsum("nij,nj->ni", R_head, v(0.006 * H, 0, 0.055 * H))
    ell(HEAD, head_c, R_head, head_r)
    nose_c = head_c + np.einsum("nij,nj->ni", R_head, v(0.050 * H, 0, -0.012 * H))
    ell(NOSE, nose_c, R_head, np.column_stack([0.010 * H, 0.007 * H, 0.013 * H]))

    # ---- arms
    for side in (0, 1):
        F = ARM_FRAMES[side]
        U = R_tor @ F @ ja.shoulder[:, side]                        # upper-arm frame in body coordinates
        Fa = U @ ja.elbow[:, side]
        elbow_j = shoulder_j[:, side] + len_ua[:, None] * U[:, :, 0]
        wrist = elbow_j + len_fa[:, None] * Fa[:, :, 0]
        base = (L_UPPER_ARM, R_UPPER_ARM)[side]
        cap(base, shoulder_j[:, side], elbow_j, r_ua)
        cap(base + 1, elbow_j, wrist, r_fa)
        ell(base + 2, wrist + 0.05 * c1 * Fa[:, :, 0], Fa,
            np.column_stack([0.052 * H, 0.024 * H * g, 0.012 * H * g]))

    # ---- grounding, then body → world
    if np.any(ja.grounded):
        drop = np.where(ja.grounded, ankles[:, :, 2].min(axis=1) - ANKLE_H * H, 0.0)
        parts_c[:, :, 2] -= drop[:, None]
        parts_e[:, :, 2] -= drop[:, None]
    Rw = rot_z(ja.yaw)                                              # (N,3,3) body → world
    shift = np.column_stack([ja.xy, np.zeros(n)])[:, None, :]
    centre = np.einsum("nij,npj->npi", Rw, parts_c) + shift
    end = np.einsum("nij,npj->npi", Rw, parts_e) + shift
    axes = np.einsum("npij,nkj->npik", parts_ax, Rw)                # rows rotated: axes·Rwᵀ

    # ---- colours and textures
    alb = np.empty((n, PARTS_PER_PERSON, 3))
    tex = np.zeros((n, PARTS_PER_PERSON), dtype=np.int8)
    for i, sh in enumerate(shapes):
        skin, top, bottom = np.asarray(sh.skin), np.asarray(sh.top), np.asarray(sh.bottom)
        alb[i] = top
        alb[i, [HEAD, NOSE, NECK, L_HAND, R_HAND]] = skin
        if sh.short_sleeves:
            alb[i, [L_FOREARM, R_FOREARM]] = skin
        alb[i, [PELVIS, L_THIGH, R_THIGH, L_SHANK, R_SHANK]] = bottom
        if sh.shorts:
            alb[i, [L_SHANK, R_SHANK]] = skin
        alb[i, [L_FOOT, R_FOOT]] = np.asarray(sh.shoes)
        tex[i, HEAD] = TEX_HEAD
        if sh.stripes:
            tex[i, TORSO] = TEX_STRIPES
    radii = parts_rad.reshape(-1, 3)
    pa = PartArrays(np.tile(_KIND, n), centre.reshape(-1, 3), end.reshape(-1, 3), parts_r.reshape(-1),
                    axes.reshape(-1, 3, 3), radii, np.repeat(np.arange(n, dtype=np.int32), PARTS_PER_PERSON),
                    np.tile(np.arange(PARTS_PER_PERSON, dtype=np.int8), n),
                    alb.reshape(-1, 3).astype(np.float32), tex.reshape(-1))
    # Highest point of each head ellipsoid: c + S·ez / sqrt(ezᵀ·S·ez).
    heads = np.arange(n) * PARTS_PER_PERSON + HEAD
    S = pa.shape_matrices()[heads]
    top_pt = pa.centre[heads] + S[:, :, 2] / np.sqrt(S[:, 2, 2])[:, None]
    pa.head_top = top_pt
    return pa


def hair_colours(shapes: list[BodyShape]) -> np.ndarray:
    """(N, 3) hair albedo (skin colour for bald people) and (N,) hair style, for the head shader."""
    return np.array([s.hair if s.hair_style else s.skin for s in shapes], dtype=np.float32)
