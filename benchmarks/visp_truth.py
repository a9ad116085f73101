"""Checks of the ViSP cube's ground truth: the board re-fitted from the tags' own corners, and the
cube's pose from the colour images alone.

The data's ``grid`` poses ``cMg(t)`` are one estimate of the AprilTag board per frame. Here the
board is fitted again from the detected corners of every tag alone: the tags' layout on the board
(each tag's pose relative to tag 2, seen in every frame) and the 99 board poses are estimated in
turn — ``cv2.solvePnP`` of all the frame's tag corners given the layout, then each tag's layout
pose by least squares over all frames given the board poses — four rounds. Nothing here looks at
the cube or at any tracker's output. Where the two truths differ, the board data cannot decide
between them (both reproject the corners to a fraction of a pixel), so the difference is a
measure of the ground truth's own uncertainty at the cube.

The corners in ``apriltag_data.json`` are stored (row, column), ViSP's ``vpImagePoint`` order; in
the tag's frame they are (−s/2, −s/2), (s/2, −s/2), (s/2, s/2), (−s/2, s/2) for tag size s
(checked: projected through each tag's ``cMo`` they land within 2.6 px of the detections; median
0.07 px with ``cam.json``'s intrinsics, and the intrinsics that fit them best are ``cam.json``'s).

:func:`image_only_poses` estimates the cube's pose from the colour images alone (SIFT matches to
frame 0 on the cube, PnP), frame by frame with no tracking, depth or tags. On this sequence it is
3.6 / 8.1 mm (median / p90) from a depth-only truth (ICP of the whole static scene) and 10.6 /
24.3 mm from the board's; drawn on the frames, the board-truth cube is visibly off the cube where
the two differ most (frames 16, 48, 84; issue 36f) — the board's pose error, levered from the
board (1.05 m away) to the cube (0.5 m), not the trackers'.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import NamedTuple

import cv2
import numpy as np
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

REFERENCE_TAG = "2"


def _pose(v: np.ndarray) -> np.ndarray:
    M = np.eye(4)
    M[:3, :3], M[:3, 3] = Rotation.from_rotvec(v[:3]).as_matrix(), v[3:]
    return M


def _vector(M: np.ndarray) -> np.ndarray:
    return np.r_[Rotation.from_matrix(M[:3, :3]).as_rotvec(), M[:3, 3]]


def _project(K: np.ndarray, M: np.ndarray, X: np.ndarray) -> np.ndarray:
    p = (X @ M[:3, :3].T + M[:3, 3]) @ K.T
    return p[:, :2] / p[:, 2:]


class TagData(NamedTuple):
    """The tags of a ViSP sequence: intrinsics ``K`` (3×3), image height (px), one tag's corners in
    its own frame (4×3, m), the detected corners per (frame, tag) as (u, v) pixels (4×2), the tag
    names, the per-frame detections as stored."""
    K: np.ndarray
    height: int
    square: np.ndarray
    corners: dict
    names: list
    frames: list


def load_tags(sequence: Path) -> TagData:
    """Read ``apriltag_data.json`` and ``cam.json`` (corners stored (row, column): swapped here)."""
    tags_json = json.loads((sequence / "apriltag_data.json").read_text())
    cam = json.loads((sequence / "cam.json").read_text())
    K = np.array([[cam["px"], 0, cam["u0"]], [0, cam["py"], cam["v0"]], [0, 0, 1]])
    half = tags_json["tag_size"] / 2
    square = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float) * half
    frames = tags_json["detections"]
    corners = {(t, tag): np.array(x["tag_corners"])[:, ::-1] for t, f in enumerate(frames) for tag, x in f.items()}
    names = sorted({tag for f in frames for tag in f}, key=int)
    return TagData(K, int(cam.get("h", 480)), square, corners, names, frames)


def refit_board_poses(sequence: Path, rounds: int = 4) -> tuple[list[np.ndarray], float]:
    """Board poses (T × 4×4, camera ← board, board = tag 2's frame) and the median per-frame RMS
    corner reprojection error (pixels) of the fit.

    >>> poses, rms = refit_board_poses(Path("visp_rbt/sequence"))   # doctest: +SKIP
    """
    board, _, rms = refit_board_and_layout(sequence, rounds)
    return board, rms


def refit_board_and_layout(sequence: Path, rounds: int = 4) -> tuple[list[np.ndarray], dict, float]:
    """:func:`refit_board_poses`, also returning the tags' layout (tag name → 4×4, board ← tag)."""
    K, _, square, corners, names, frames = load_tags(sequence)
    board = [np.array(f[REFERENCE_TAG]["cMo"]) for f in frames]
    layout = {tag: _pose(np.median([_vector(np.linalg.inv(board[t]) @ np.array(f[tag]["cMo"]))
                                    for t, f in enumerate(frames) if tag in f], axis=0)) for tag in names}
    layout[REFERENCE_TAG] = np.eye(4)
    for _ in range(rounds):
        rms = []
        for t in range(len(frames)):
            seen = [tag for tag in names if (t, tag) in corners]
            X = np.concatenate([square @ layout[tag][:3, :3].T + layout[tag][:3, 3] for tag in seen])
            x = np.concatenate([corners[(t, tag)] for tag in seen])
            rvec = cv2.Rodrigues(board[t][:3, :3])[0]
            _, rvec, tvec = cv2.solvePnP(X, x, K, None, rvec, board[t][:3, 3].copy(), useExtrinsicGuess=True,
                                         flags=cv2.SOLVEPNP_ITERATIVE)
            board[t] = np.eye(4)
            board[t][:3, :3], board[t][:3, 3] = cv2.Rodrigues(rvec)[0], tvec.ravel()
            rms.append(float(np.sqrt(np.mean((_project(K, board[t], X) - x) ** 2))))
        for tag in names:
            if tag == REFERENCE_TAG:
                continue
            seen = [t for t in range(len(frames)) if (t, tag) in corners]
            residual = lambda v, seen=seen, tag=tag: np.concatenate(
                [(_project(K, board[t] @ _pose(v), square) - corners[(t, tag)]).ravel() for t in seen])
            layout[tag] = _pose(least_squares(residual, _vector(layout[tag]), loss="huber").x)
    return board, layout, float(np.median(rms))


def box_surface_points(K: np.ndarray, cMo: np.ndarray, half: float, uv: np.ndarray, margin: float = 0.003):
    """Where the pixels ``uv`` (n, 2) meet a cube of half-side ``half`` (m) at pose ``cMo``: object
    points (n, 3) and a mask of the rays that hit a face at least ``margin`` m inside its edges."""
    rays = np.c_[(uv[:, 0] - K[0, 2]) / K[0, 0], (uv[:, 1] - K[1, 2]) / K[1, 1], np.ones(len(uv))]
    centre, dirs = -cMo[:3, :3].T @ cMo[:3, 3], rays @ cMo[:3, :3]        # in the object frame
    with np.errstate(divide="ignore", invalid="ignore"):
        a, b = (-half - centre) / dirs, (half - centre) / dirs
    near, far = np.nanmax(np.minimum(a, b), 1), np.nanmin(np.maximum(a, b), 1)
    X = centre + near[:, None] * dirs
    inside = (near < far) & (near > 0) & (np.sort(np.abs(X), 1)[:, 1] < half - margin)
    return X, inside


def image_only_poses(sequence: Path, cMo0: np.ndarray, half: float) -> tuple[list[np.ndarray], list[int]]:
    """A check of the board truth from the colour images alone: per frame, SIFT features matched to
    frame 0's on the cube (3-D points where their rays meet the cube at the given ``cMo(0)``), then
    ``cv2.solvePnPRansac`` (2 px) and ``cv2.solvePnPRefineLM`` on the inliers. No tracking (nothing
    drifts), no depth, no tags. Frames with fewer than 8 inliers (motion blur: 4 of 99 here) get a
    NaN pose. Returns the poses (camera ← cube) and the inlier counts."""
    cam = json.loads((sequence / "cam.json").read_text())
    K = np.array([[cam["px"], 0, cam["u0"]], [0, cam["py"], cam["v0"]], [0, 0, 1]])
    grey = lambda k: cv2.imread(str(sequence / f"color_image_{k:04d}.png"), cv2.IMREAD_GRAYSCALE)
    n = len(json.loads((sequence / "apriltag_data.json").read_text())["grid"])
    sift = cv2.SIFT_create(nfeatures=0, contrastThreshold=0.02)
    kp0, des0 = sift.detectAndCompute(grey(0), None)
    X, on_cube = box_surface_points(K, cMo0, half, np.array([k.pt for k in kp0]))
    des0, X = des0[on_cube], X[on_cube]
    matcher = cv2.BFMatcher(cv2.NORM_L2)
    poses, counts = [np.array(cMo0, float)], [int(on_cube.sum())]
    for k in range(1, n):
        kp, des = sift.detectAndCompute(grey(k), None)
        good = [a for a, b in matcher.knnMatch(des0, des, k=2) if a.distance < 0.75 * b.distance]
        obj, img = X[[a.queryIdx for a in good]], np.array([kp[a.trainIdx].pt for a in good]).reshape(-1, 2)
        prev = next(M for M in poses[::-1] if np.isfinite(M).all())
        rvec, tvec = cv2.Rodrigues(prev[:3, :3])[0], prev[:3, 3].reshape(3, 1).copy()
        inliers = None
        if len(good) >= 8:
            _, rvec, tvec, inliers = cv2.solvePnPRansac(obj, img, K, None, rvec, tvec, useExtrinsicGuess=True,
                                                        reprojectionError=2.0, iterationsCount=500)
        if inliers is None or len(inliers) < 8:
            poses.append(np.full((4, 4), np.nan))
            counts.append(0 if inliers is None else len(inliers))
            continue
        rvec, tvec = cv2.solvePnPRefineLM(obj[inliers.ravel()], img[inliers.ravel()], K, None, rvec, tvec)
        M = np.eye(4)
        M[:3, :3], M[:3, 3] = cv2.Rodrigues(rvec)[0], tvec.ravel()
        poses.append(M)
        counts.append(len(inliers))
    return poses, counts


def _corners(half: float) -> np.ndarray:
    return np.array([[x, y, z] for x in (-half, half) for y in (-half, half) for z in (-half, half)])


def best_constant_transform(relative: np.ndarray, half: float) -> np.ndarray:
    """The constant X (4×4) closest to every ``relative[t]`` (T × 4×4) over a cube's 8 corners, least
    squares (Kabsch over all frames' corners): the one board ← cube transform that best explains
    ``estimate(t) = cMg(t)·X`` when ``relative[t] = cMg(t)⁻¹·estimate(t)``."""
    P = _corners(half)
    Y = (np.einsum("nij,kj->nki", relative[:, :3, :3], P) + relative[:, None, :3, 3]).reshape(-1, 3)
    mu = Y.mean(0)
    U, _, Vt = np.linalg.svd(np.tile(P, (len(relative), 1)).T @ (Y - mu))
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T))])
    X = np.eye(4)
    X[:3, :3], X[:3, 3] = Vt.T @ D @ U.T, mu
    return X


def constant_transform_check(grid: np.ndarray, cMo0: np.ndarray, estimate: np.ndarray, half: float) -> dict:
    """Could one constant transform (or a frame shift) explain an estimate's gap to the board truth?
    Gaps (mm, deg per frame 1…; NaN where the estimate is NaN) of ``estimate`` (T × 4×4) to
    ``cMg(t)·X`` for: X = cMg(0)⁻¹·cMo(0) (the truth as read); X the mean of cMg(0)⁻¹·estimate(i) over
    the first 10 frames (ViSP's own test of this data, ``catchRBTDataset.cpp``); the best X over all
    frames; the best X with the board one frame earlier / later."""
    inv = np.linalg.inv
    ok = np.isfinite(estimate).all(axis=(1, 2))
    frames = np.arange(1, len(grid))
    truths = {"as read": grid @ inv(grid[0]) @ cMo0,
              "ViSP's 10-frame anchor": grid @ best_constant_transform(inv(grid[0]) @ estimate[:10][ok[:10]], half),
              "best constant": grid @ best_constant_transform(inv(grid[ok]) @ estimate[ok], half)}
    for shift in (-1, 1):
        j = np.clip(np.arange(len(grid)) + shift, 0, len(grid) - 1)
        X = best_constant_transform(inv(grid[j[ok]]) @ estimate[ok], half)
        truths[f"best constant, board {shift:+d} frame"] = grid[j] @ X
    out = {}
    for name, truth in truths.items():
        mm = 1000 * np.linalg.norm(truth[frames, :3, 3] - estimate[frames, :3, 3], axis=1)
        R = np.einsum("nij,nkj->nik", truth[frames, :3, :3], estimate[frames, :3, :3])
        deg = np.degrees(np.arccos(np.clip((np.trace(R, axis1=1, axis2=2) - 1) / 2, -1, 1)))
        out[name] = (mm, deg)
    return out


def visible_face_points(half: float, per_side: int = 15) -> tuple[np.ndarray, np.ndarray]:
    """A grid of ``per_side``² points on each of a cube's six faces (object frame, m; 80 % of each
    face, away from the edges where depth mixes cube and table) and their outward normals."""
    g = np.linspace(-0.8, 0.8, per_side) * half
    a, b = (v.ravel() for v in np.meshgrid(g, g))
    pts, nrm = [], []
    for axis in range(3):
        others = [i for i in range(3) if i != axis]
        for sign in (-1.0, 1.0):
            X = np.zeros((len(a), 3))
            X[:, axis], X[:, others[0]], X[:, others[1]] = sign * half, a, b
            pts.append(X)
            nrm.append(np.tile(np.eye(3)[axis] * sign, (len(a), 1)))
    return np.concatenate(pts), np.concatenate(nrm)


def depth_disagreement(K: np.ndarray, poses: np.ndarray, depths: list, half: float) -> np.ndarray:
    """How far each cube pose is from what the depth sensor measures — a check that sees no tag and
    no colour. Per frame (T,): the median |measured − predicted depth| (mm) over points on the
    faces the pose shows the camera, after removing the sensor's offset at the cube (the median
    difference at frame 0's pose, as the tracker learns it). NaN where the pose is NaN."""
    X, N = visible_face_points(half)

    def differences(M, depth):
        P, n = X @ M[:3, :3].T + M[:3, 3], N @ M[:3, :3].T
        P = P[np.einsum("ij,ij->i", n, -P) > 0]
        uv = np.round(P @ K.T[:, :2] / P[:, 2:]).astype(int)
        ok = (uv[:, 0] >= 0) & (uv[:, 0] < depth.shape[1]) & (uv[:, 1] >= 0) & (uv[:, 1] < depth.shape[0])
        z = depth[uv[ok, 1], uv[ok, 0]]
        return (z - P[ok, 2])[z > 0]

    offset = float(np.median(differences(poses[0], depths[0])))
    return np.array([1000 * np.median(np.abs(differences(M, d) - offset)) if np.isfinite(M).all() else np.nan
                     for M, d in zip(poses, depths)])
