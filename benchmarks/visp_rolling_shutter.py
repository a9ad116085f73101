"""The ViSP board truth re-fitted for a rolling shutter: a check of the cube's ground truth.

The data's board poses ``cMg(t)`` (ViSP's, and :func:`visp_truth.refit_board_poses`) fit each frame's
tag corners with a global-shutter camera. The sequence's colour camera is a RealSense of the D415/
D435 kind (fx = 607 px at 640×480; that colour camera is 69.4° wide at 16:9, ≈ 616 px in its 640×480
mode, and its OmniVision OV2740 sensor has the shutter type "Rolling Shutter" in the camera's
manual — an identification from the intrinsics, the data's files do not name the camera), so row ``v`` is read a
fraction ``readout · (v − H/2)/H`` of a frame period after the middle row, while the hand-held camera
moves. The board (rows 40–260) is then read earlier than the cube (rows 240–370), and its image is
sheared — which a global-shutter fit takes as a tilt of the board, levered 0.6 m forward to the cube.

Here each frame's board pose (at mid-frame time) is fitted to all its tag corners with a first-order
rolling-shutter projection: the corner seen on row ``v`` through the pose ``exp(s·ξ(t))·cMg(t)``, ``s`` its
row time in frame periods, ``ξ(t)`` the camera's motion per frame period from the global-shutter
board poses (central differences; rotation vector and translation, camera frame). The one unknown,
the readout time (in frame periods), is chosen on a grid by the tag corners' own residual — nothing
here looks at the cube, its depth or any tracker. The cube's truth is the board's pose at the time
the cube's rows were read: ``cMo(t) = exp(s_cube·ξ)·cMg(t) · [exp(s_cube·ξ)·cMg(0)]⁻¹ · cMo(0)``.

On the ViSP sequence the corners choose a readout of one frame period (median corner RMS 0.206 →
0.180 px), and the cube's truth moves 4–10 mm: the image-only cube estimate is 10.1 / 21.6 mm
(median / p90) from the data's truth and 4.4 / 9.3 mm from this one. The depth images, which see no
tags, agree: the board's depth plane tilts against the data's board by 1.10° / 1.91° frame to frame
(median / p90, its constant part removed), against this board by 0.60° / 1.27° (issue 36g).
"""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

import cv2
import numpy as np
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from visp_truth import TagData, _pose, _vector, load_tags, refit_board_and_layout

READOUTS = (0.0, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5)          # frame periods: the grid searched


class RollingShutterBoard(NamedTuple):
    """Board poses at mid-frame time (T × 4×4, camera ← board), the camera's motion per frame
    period (T × 6: rotation vector, translation in m; camera frame), the readout chosen (frame
    periods), and the median corner RMS (px) for each readout of the grid."""
    poses: np.ndarray
    twists: np.ndarray
    readout: float
    rms_by_readout: dict


def camera_twists(poses: np.ndarray) -> np.ndarray:
    """Camera motion per frame period at each frame (T × 6) from poses camera ← static scene (T × 4×4):
    central differences ``log(P[t+1]·P[t−1]⁻¹)/2``, one-sided at the ends."""
    def log(M: np.ndarray) -> np.ndarray:
        return np.r_[Rotation.from_matrix(M[:3, :3]).as_rotvec(), M[:3, 3]]
    n, inv = len(poses), np.linalg.inv
    if n < 2:
        return np.zeros((n, 6))
    middle = [log(poses[t + 1] @ inv(poses[t - 1])) / 2 for t in range(1, n - 1)]
    return np.array([log(poses[1] @ inv(poses[0])), *middle, log(poses[-1] @ inv(poses[-2]))])


def moved(pose: np.ndarray, twist: np.ndarray, s: np.ndarray) -> np.ndarray:
    """``exp(s·twist)·pose`` to first order for each time offset in ``s`` (n,) → (n, 4, 4)."""
    out = np.repeat(np.eye(4)[None], len(s), axis=0)
    out[:, :3, :3] = Rotation.from_rotvec(s[:, None] * twist[:3]).as_matrix()
    out[:, :3, 3] = s[:, None] * twist[3:]
    return out @ pose


def project_rolling(K: np.ndarray, pose: np.ndarray, twist: np.ndarray, row_time: np.ndarray,
                    X: np.ndarray) -> np.ndarray:
    """Pixels (n, 2) of points ``X`` (n, 3), each seen at its own time ``row_time`` (n,) frame periods."""
    M = moved(pose, twist, row_time)
    p = (np.einsum("nij,nj->ni", M[:, :3, :3], X) + M[:, :3, 3]) @ K.T
    return p[:, :2] / p[:, 2:]


def _fit_frame(K, X, x, row_time, twist, start):
    residual = lambda v: (project_rolling(K, _pose(v), twist, row_time, X) - x).ravel()
    sol = least_squares(residual, _vector(start))
    return _pose(sol.x), float(np.sqrt(np.mean(sol.fun ** 2)))


def rolling_shutter_board_poses(sequence: Path, readouts=READOUTS) -> RollingShutterBoard:
    """Re-fit every frame's board pose with a rolling shutter, the tags' layout and the camera's
    motion taken from the global-shutter refit; the readout (frame periods) that gives the tag
    corners the smallest mean RMS is kept.

    >>> board = rolling_shutter_board_poses(Path("visp_rbt/sequence"))   # doctest: +SKIP
    >>> board.readout                                                   # doctest: +SKIP
    1.0
    """
    start, layout, _ = refit_board_and_layout(sequence)
    return fit_rolling_shutter(load_tags(sequence), layout, np.array(start), readouts)


def fit_rolling_shutter(tags: TagData, layout: dict, start: np.ndarray, readouts=READOUTS) -> RollingShutterBoard:
    """Board poses fitted to the corners of ``tags`` with the tags' ``layout`` (name → board ← tag)
    for each readout of the grid, from the poses ``start`` (T × 4×4), which also give the camera's
    motion; the readout with the smallest mean corner RMS is kept."""
    twists = camera_twists(start)
    per_frame = []
    for t in range(len(tags.frames)):
        seen = [tag for tag in tags.names if (t, tag) in tags.corners]
        X = np.concatenate([tags.square @ layout[tag][:3, :3].T + layout[tag][:3, 3] for tag in seen])
        x = np.concatenate([tags.corners[(t, tag)] for tag in seen])
        per_frame.append((X, x, (x[:, 1] - tags.height / 2) / tags.height))
    best, rms_by = None, {}
    for readout in readouts:
        fits = [_fit_frame(tags.K, X, x, readout * rows, twists[t], start[t])
                for t, (X, x, rows) in enumerate(per_frame)]
        rms = np.array([f[1] for f in fits])
        rms_by[readout] = float(np.median(rms))
        if best is None or rms.mean() < best[0]:
            best = (rms.mean(), readout, np.array([f[0] for f in fits]))
    return RollingShutterBoard(best[2], twists, best[1], rms_by)


def cube_truth_at_its_rows(board: RollingShutterBoard, cMo0: np.ndarray, K: np.ndarray, height: int,
                           half: float) -> list[np.ndarray]:
    """The cube's pose per frame (camera ← cube) at the time its rows were read: the board moved to
    the cube's mean image row (its 8 corners at the board-given pose), then ``cMo(0)`` carried along."""
    corners = np.array([[x, y, z] for x in (-half, half) for y in (-half, half) for z in (-half, half)])
    inv = np.linalg.inv
    at_rows = []
    for pose, twist in zip(board.poses, board.twists):
        G = pose @ inv(board.poses[0]) @ cMo0
        p = (corners @ G[:3, :3].T + G[:3, 3]) @ K.T
        s = board.readout * (np.mean(p[:, 1] / p[:, 2]) - height / 2) / height
        at_rows.append(moved(pose, twist, np.array([s]))[0])
    return [M @ inv(at_rows[0]) @ cMo0 for M in at_rows]


def board_tilt_against_depth(sequence: Path, depths: list, boards: dict) -> dict:
    """A check from the other sensor: per frame, the plane fitted to the depth over the tags' convex
    hull (robust, 3 MAD) against each board fit's plane. The tilt between them (rotation about the
    camera's x and y, degrees) has a constant part — the depth sensor's own — and a frame-to-frame
    part, which is the board fit's error where the depth is steady. Returns, per name in ``boards``
    (name → T × 4×4 poses), the median and p90 (deg) of each frame's deviation from the median tilt."""
    tags = load_tags(sequence)
    K, (h, w) = tags.K, depths[0].shape
    v, u = np.mgrid[0:h, 0:w]
    normals = []
    for t, Z in enumerate(depths):
        hull = np.concatenate([tags.corners[(t, tag)] for tag in tags.names if (t, tag) in tags.corners])
        mask = np.zeros((h, w), np.uint8)
        cv2.fillConvexPoly(mask, cv2.convexHull(hull.astype(np.float32)).astype(np.int32), 1)
        m = (mask > 0) & (Z > 0)
        X = np.c_[(u[m] - K[0, 2]) / K[0, 0] * Z[m], (v[m] - K[1, 2]) / K[1, 1] * Z[m], Z[m]]
        keep = np.ones(len(X), bool)
        for _ in range(4):
            c = X[keep].mean(0)
            n = np.linalg.svd(X[keep] - c, full_matrices=False)[2][2]
            r = (X - c) @ n
            keep = np.abs(r - np.median(r)) < 3 * 1.4826 * np.median(np.abs(r - np.median(r)))
        normals.append(n if n[2] < 0 else -n)
    out = {}
    for name, poses in boards.items():
        nb = np.array([M[:3, 2] if M[2, 2] < 0 else -M[:3, 2] for M in poses])
        tilt = np.degrees(np.cross(nb, np.array(normals)))[:, :2]
        dev = np.linalg.norm(tilt - np.median(tilt, 0), axis=1)
        out[name] = (float(np.median(dev)), float(np.percentile(dev, 90)))
    return out
